"""``NormalizeReward``: scale rewards by the running std of a discounted return (Gymnasium 1.x)."""

from __future__ import annotations

from typing import Any, SupportsFloat

import numpy as np

from palaestra.core import ActType, Env, ObsType, Wrapper
from palaestra.error import InvalidBound
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.running_mean_std import RunningMeanStd

__all__ = ["NormalizeReward"]


class NormalizeReward(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Divide each reward by the running standard deviation of the discounted return.

    The mean is not subtracted (openai/baselines#538). Set :attr:`update_running_mean` to
    ``False`` to freeze the statistics, e.g. during evaluation.
    """

    def __init__(
        self, env: Env[ObsType, ActType], gamma: float = 0.99, epsilon: float = 1e-8
    ) -> None:
        # gamma > 1 makes the accumulator diverge, gamma < 0 flips its sign every step.
        if not 0 <= gamma <= 1:
            raise InvalidBound(f"`gamma` should be in the interval [0, 1]. Received {gamma}")
        if not epsilon > 0:
            raise InvalidBound(f"`epsilon` should be strictly positive. Received {epsilon}")
        RecordConstructorArgs.__init__(self, gamma=gamma, epsilon=epsilon)
        Wrapper.__init__(self, env)
        self.return_rms = RunningMeanStd(shape=())
        self.discounted_reward = np.array([0.0])  # [1] float64, the running discounted return
        self.gamma = gamma
        self.epsilon = epsilon
        self._update_running_mean = True

    @property
    def update_running_mean(self) -> bool:
        """Whether each step still updates the return statistics."""
        return self._update_running_mean

    @update_running_mean.setter
    def update_running_mean(self, setting: bool) -> None:
        self._update_running_mean = setting

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner env and return the scaled reward."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        # Gymnasium keeps the return (not the reward) in the statistics and resets it only on
        # termination; kept as is so normalized rewards match (openai/gym#3154).
        self.discounted_reward = self.discounted_reward * self.gamma * (1 - terminated) + float(
            reward
        )
        if self._update_running_mean:
            self.return_rms.update_one(self.discounted_reward[0])
        normalized = reward / np.sqrt(self.return_rms.var + self.epsilon)
        return obs, normalized, terminated, truncated, info
