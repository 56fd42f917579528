"""Stateless reward wrappers: ``TransformReward`` and ``ClipReward`` (Gymnasium 1.x)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, SupportsFloat

import numpy as np

from palaestra.core import ActType, Env, ObsType, RewardWrapper
from palaestra.error import InvalidBound
from palaestra.utils.record_constructor import RecordConstructorArgs

__all__ = ["ClipReward", "TransformReward"]


class TransformReward(RewardWrapper[ObsType, ActType], RecordConstructorArgs):
    """Return ``func(reward)`` instead of the inner env's reward."""

    def __init__(
        self, env: Env[ObsType, ActType], func: Callable[[SupportsFloat], SupportsFloat]
    ) -> None:
        RecordConstructorArgs.__init__(self, func=func)
        RewardWrapper.__init__(self, env)
        if not callable(func):
            raise TypeError(f"Expected `func` to be callable, got {func!r}")
        self.func = func

    def reward(self, reward: SupportsFloat) -> SupportsFloat:
        """Return ``func(reward)``."""
        return self.func(reward)


class ClipReward(TransformReward[ObsType, ActType], RecordConstructorArgs):
    """Clip rewards into ``[min_reward, max_reward]``; either bound may be ``None`` (open)."""

    def __init__(
        self,
        env: Env[ObsType, ActType],
        min_reward: float | np.ndarray | None = None,
        max_reward: float | np.ndarray | None = None,
    ) -> None:
        if min_reward is None and max_reward is None:
            raise InvalidBound("Both `min_reward` and `max_reward` cannot be None")
        if min_reward is not None and max_reward is not None:
            if np.any(np.asarray(max_reward) < np.asarray(min_reward)):
                raise InvalidBound(
                    f"Min reward ({min_reward}) must be smaller than max reward ({max_reward})"
                )
        RecordConstructorArgs.__init__(self, min_reward=min_reward, max_reward=max_reward)

        def clip(reward: Any) -> Any:
            return np.clip(reward, min_reward, max_reward)

        TransformReward.__init__(self, env=env, func=clip)
