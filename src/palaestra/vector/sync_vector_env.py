"""``SyncVectorEnv``: sub-envs in this process, stepped in a loop (the loop engine)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from palaestra.core import Env
from palaestra.vector.engine import LoopEngine
from palaestra.vector.engine_env import EngineVectorEnv
from palaestra.vector.vector_env import AutoresetMode

__all__ = ["SyncVectorEnv"]


class SyncVectorEnv(EngineVectorEnv):
    """Runs ``env_fns``' envs one after the other in this process (Gymnasium's signature).

    >>> import palaestra as gym
    >>> envs = SyncVectorEnv([lambda: gym.make("CartPole-v1") for _ in range(2)])
    >>> obs, infos = envs.reset(seed=42)
    >>> obs.shape, infos
    ((2, 4), {})
    >>> envs.close()
    """

    def __init__(
        self,
        env_fns: Sequence[Callable[[], Env[Any, Any]]],
        copy: bool = True,
        observation_mode: str | tuple[Any, Any] = "same",
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
    ) -> None:
        self.env_fns = env_fns
        self.observation_mode = observation_mode
        engine = LoopEngine(env_fns, observation_mode, "SyncVectorEnv")
        self.envs = engine.envs
        super().__init__(engine, copy=copy, autoreset_mode=autoreset_mode)
