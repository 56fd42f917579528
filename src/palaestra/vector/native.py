"""``BatchedVectorEnv``: a built-in env's native batch behind the Gymnasium vector API.

``make_vec("CartPole-v1", n)`` returns one by default (the ids' ``vector_entry_point``); it
steps all ``n`` envs with one array op each and matches ``n`` single envs row for row: row i
of ``reset(seed=s)`` is the env ``make(id)`` reset with ``seed=s + i``. Batches do not draw, so
with a ``render_mode`` the entry points return a ``SyncVectorEnv`` of real envs instead.

The toy-text batches (FrozenLake, CliffWalking, Taxi, Blackjack) plug in the same way; they
also report infos (``prob``, Taxi's ``action_mask``) as arrays.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from palaestra.vector.engine_env import EngineVectorEnv
from palaestra.vector.native_engine import NativeEngine
from palaestra.vector.vector_env import AutoresetMode

if TYPE_CHECKING:  # the env modules load only when a batch is made
    from palaestra.vector.native_engine import NativeBatch

__all__ = [
    "BatchedVectorEnv",
    "acrobot",
    "blackjack",
    "cartpole",
    "cliff_walking",
    "continuous_mountain_car",
    "frozen_lake",
    "mountain_car",
    "pendulum",
    "taxi",
]


class BatchedVectorEnv(EngineVectorEnv):
    """A ``BatchedEnv`` with time limits and autoreset, as a ``VectorEnv``.

    >>> import palaestra as gym
    >>> envs = gym.make_vec("MountainCar-v0", num_envs=3)
    >>> envs
    BatchedVectorEnv(MountainCar-v0, num_envs=3)
    >>> obs, infos = envs.reset(seed=0)
    >>> obs.shape, obs.dtype
    ((3, 2), dtype('float32'))
    """

    def __init__(
        self,
        batch: NativeBatch,
        max_episode_steps: int | None = None,
        copy: bool = True,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        metadata: dict[str, Any] | None = None,
    ) -> None:
        self.batch = batch
        engine = NativeEngine(batch, max_episode_steps, metadata)
        super().__init__(engine, copy=copy, autoreset_mode=autoreset_mode)


def _make(
    kind: str,
    num_envs: int,
    max_episode_steps: int | None,
    render_mode: str | None,
    vector_kwargs: dict[str, Any],
    env_kwargs: dict[str, Any],
) -> EngineVectorEnv:
    if kind in _TOY_TEXT:
        from palaestra.envs import toy_text as tt

        batch_cls, env_cls = (getattr(tt, name) for name in _TOY_TEXT[kind])
        return _build(
            batch_cls, env_cls, num_envs, max_episode_steps, render_mode, vector_kwargs, env_kwargs
        )
    from palaestra.envs import classic_control as cc

    classes: dict[str, tuple[Any, Any]] = {
        "cartpole": (cc.CartPoleBatch, cc.CartPoleEnv),
        "mountain_car": (cc.MountainCarBatch, cc.MountainCarEnv),
        "continuous_mountain_car": (
            cc.ContinuousMountainCarBatch,
            cc.Continuous_MountainCarEnv,
        ),
        "pendulum": (cc.PendulumBatch, cc.PendulumEnv),
        "acrobot": (cc.AcrobotBatch, cc.AcrobotEnv),
    }
    batch_cls, env_cls = classes[kind]
    return _build(
        batch_cls, env_cls, num_envs, max_episode_steps, render_mode, vector_kwargs, env_kwargs
    )


# kind -> (batch class, env class) in palaestra.envs.toy_text
_TOY_TEXT = {
    "frozen_lake": ("FrozenLakeBatch", "FrozenLakeEnv"),
    "cliff_walking": ("CliffWalkingBatch", "CliffWalkingEnv"),
    "taxi": ("TaxiBatch", "TaxiEnv"),
    "blackjack": ("BlackjackBatch", "BlackjackEnv"),
}


def _build(
    batch_cls: Any,
    env_cls: Any,
    num_envs: int,
    max_episode_steps: int | None,
    render_mode: str | None,
    vector_kwargs: dict[str, Any],
    env_kwargs: dict[str, Any],
) -> EngineVectorEnv:
    if render_mode is not None:
        # Native batches do not draw: envs that must render run as real envs, in a loop.
        return _rendering_envs(
            env_cls, num_envs, max_episode_steps, render_mode, vector_kwargs, env_kwargs
        )
    batch = batch_cls(num_envs, **env_kwargs)
    return BatchedVectorEnv(batch, max_episode_steps, metadata=env_cls.metadata, **vector_kwargs)


def _rendering_envs(
    env_cls: Any,
    num_envs: int,
    max_episode_steps: int | None,
    render_mode: str,
    vector_kwargs: dict[str, Any],
    env_kwargs: dict[str, Any],
) -> EngineVectorEnv:
    from palaestra.vector.sync_vector_env import SyncVectorEnv
    from palaestra.wrappers.common import OrderEnforcing, PassiveEnvChecker, TimeLimit

    def one() -> Any:
        env = OrderEnforcing(PassiveEnvChecker(env_cls(render_mode=render_mode, **env_kwargs)))
        return env if max_episode_steps is None else TimeLimit(env, max_episode_steps)

    return SyncVectorEnv([one] * num_envs, **vector_kwargs)


def _entry_point(kind: str) -> Any:
    def make(
        num_envs: int = 1,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        copy: bool = True,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        **kwargs: Any,
    ) -> EngineVectorEnv:
        vector_kwargs = {"copy": copy, "autoreset_mode": autoreset_mode}
        return _make(kind, num_envs, max_episode_steps, render_mode, vector_kwargs, kwargs)

    make.__name__ = make.__qualname__ = kind
    make.__doc__ = f"The {kind} native batch as a vector env (a ``vector_entry_point``)."
    return make


cartpole = _entry_point("cartpole")
mountain_car = _entry_point("mountain_car")
continuous_mountain_car = _entry_point("continuous_mountain_car")
pendulum = _entry_point("pendulum")
acrobot = _entry_point("acrobot")
frozen_lake = _entry_point("frozen_lake")
cliff_walking = _entry_point("cliff_walking")
taxi = _entry_point("taxi")
blackjack = _entry_point("blackjack")
