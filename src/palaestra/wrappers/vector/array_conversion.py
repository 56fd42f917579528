"""Vector ``ArrayConversion`` and ``NumpyToTorch`` (``gymnasium.wrappers.vector``): the batch
of actions converted to the env's array module, observations, rewards, flags and infos to the
target's (arrays, not Python scalars, unlike the single-env wrapper)."""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np

from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.vector.vector_env import VectorEnv, VectorWrapper
from palaestra.wrappers.array_conversion import ConvertsArrays

__all__ = ["ArrayConversion", "NumpyToTorch"]


class ArrayConversion(VectorWrapper[Any, Any, Any], ConvertsArrays):
    """A vector env stepped with ``target_xp`` arrays and answering in them."""

    def __init__(
        self,
        env: VectorEnv[Any, Any, Any],
        env_xp: ModuleType,
        target_xp: ModuleType,
        env_device: Any = None,
        target_device: Any = None,
    ) -> None:
        VectorWrapper.__init__(self, env)
        self._init_conversion(env_xp, target_xp, env_device, target_device)

    def step(self, actions: Any) -> tuple[Any, Any, Any, Any, dict[str, Any]]:
        obs, rewards, terminated, truncated, infos = self.env.step(self._in(actions))
        return (
            self._out(obs),
            self._out(rewards),
            self._out(terminated),
            self._out(truncated),
            self._out(infos),
        )

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        if options:
            options = self._in(options)
        obs, infos = self.env.reset(seed=seed, options=options)
        return self._out(obs), self._out(infos)


class NumpyToTorch(ArrayConversion):
    """A numpy vector env driven with torch tensors (on ``device``)."""

    def __init__(self, env: VectorEnv[Any, Any, Any], device: Any = None) -> None:
        import torch

        RecordConstructorArgs.__init__(self, device=device)
        super().__init__(env, env_xp=np, target_xp=torch, target_device=device)
        self.device = device
