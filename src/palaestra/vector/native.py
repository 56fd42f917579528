"""``BatchedVectorEnv``: a built-in env's native batch behind the Gymnasium vector API.

``make_vec("CartPole-v1", n)`` returns one by default: the id's ``vector_entry_point`` names its
native batch (``CartPoleBatch``) and :func:`batched_vector_env` runs it. It steps all ``n`` envs
with one array op each and matches ``n`` single envs row for row: row i of ``reset(seed=s)`` is
the env ``make(id)`` reset with ``seed=s + i``. Batches do not draw: with a ``render_mode``
``make_vec`` builds a ``SyncVectorEnv`` of real envs instead. This module never
imports the env packages: the registry hands it the classes.

The toy-text batches (FrozenLake, CliffWalking, Taxi, Blackjack) plug in the same way; they
also report infos (``prob``, Taxi's ``action_mask``) as arrays.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from palaestra.vector.engine_env import EngineVectorEnv
from palaestra.vector.native_engine import NativeEngine
from palaestra.vector.vector_env import AutoresetMode

if TYPE_CHECKING:
    from palaestra.vector.native_engine import NativeBatch

__all__ = ["BatchedVectorEnv", "batched_vector_env"]


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


def batched_vector_env(
    batch_cls: Any,
    env_cls: Any,
    num_envs: int = 1,
    max_episode_steps: int | None = None,
    render_mode: str | None = None,
    copy: bool = True,
    autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
    **kwargs: Any,
) -> BatchedVectorEnv:
    """``num_envs`` rows of ``batch_cls`` as a vector env (what ``make_vec`` builds for an id
    whose ``vector_entry_point`` names a native batch); ``env_cls`` is the id's single env,
    whose metadata the vector env reports. ``kwargs`` go to the batch (the env's own arguments);
    a ``render_mode`` is refused (``make_vec`` builds real envs for one)."""
    if render_mode is not None:
        raise ValueError(
            f"native batches do not render (render_mode={render_mode!r}): "
            "make_vec builds real envs for a render_mode"
        )
    batch = batch_cls(num_envs, **kwargs)
    return BatchedVectorEnv(
        batch, max_episode_steps, copy, autoreset_mode, metadata=env_cls.metadata
    )
