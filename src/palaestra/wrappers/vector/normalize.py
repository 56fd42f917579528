"""``NormalizeObservation`` and ``NormalizeReward`` for vector envs (Gymnasium's arithmetic)."""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.error import InvalidBound
from palaestra.spaces import Box
from palaestra.spaces.batching import batch_space
from palaestra.vector.vector_env import (
    AutoresetMode,
    StepReturn,
    VectorEnv,
    VectorObservationWrapper,
    VectorWrapper,
)
from palaestra.wrappers.running_mean_std import RunningMeanStd


class NormalizeObservation(VectorObservationWrapper[np.ndarray, Any, np.ndarray]):
    """Observations shifted and scaled by running statistics over all sub-envs (NEXT_STEP only).

    ``update_running_mean = False`` freezes the statistics (for evaluation).
    """

    def __init__(self, env: VectorEnv[Any, Any, Any], epsilon: float = 1e-8) -> None:
        if epsilon <= 0:
            raise InvalidBound(f"`epsilon` should be strictly positive. Received {epsilon}")
        super().__init__(env)
        mode = env.metadata.get("autoreset_mode")
        if mode is not None and mode is not AutoresetMode.NEXT_STEP:
            raise ValueError(
                f"Expected env.metadata['autoreset_mode'] to be AutoresetMode.NEXT_STEP, got {mode}"
            )
        single = Box(-np.inf, np.inf, shape=self.single_observation_space.shape, dtype=np.float32)
        self.single_observation_space = single
        self.observation_space = batch_space(single, self.num_envs)
        self.obs_rms = RunningMeanStd(shape=single.shape, dtype=single.dtype)
        self.epsilon = epsilon
        self.update_running_mean = True

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset (partial resets are refused: the statistics cover whole batches)."""
        if options is not None and "reset_mask" in options and not np.all(options["reset_mask"]):
            raise ValueError(
                "NormalizeObservation does not support partial resets. The 'reset_mask' must "
                "contain all True values."
            )
        return super().reset(seed=seed, options=options)

    def observations(self, observations: np.ndarray) -> np.ndarray:
        """``(obs - mean) / sqrt(var + eps)`` as float32."""
        if self.update_running_mean:
            self.obs_rms.update(observations)
        scaled = (observations - self.obs_rms.mean) / np.sqrt(self.obs_rms.var + self.epsilon)
        return scaled.astype(np.float32)


class NormalizeReward(VectorWrapper[Any, Any, np.ndarray]):
    """Rewards divided by the running std of the discounted return (Gymnasium's scheme)."""

    def __init__(
        self, env: VectorEnv[Any, Any, Any], gamma: float = 0.99, epsilon: float = 1e-8
    ) -> None:
        if not 0 <= gamma <= 1:
            raise InvalidBound(f"`gamma` should be in the interval [0, 1]. Received {gamma}")
        if epsilon <= 0:
            raise InvalidBound(f"`epsilon` should be strictly positive. Received {epsilon}")
        super().__init__(env)
        self.return_rms = RunningMeanStd(shape=())
        self.accumulated_reward = np.zeros(self.num_envs, dtype=np.float32)  # [N]
        self.gamma, self.epsilon = gamma, epsilon
        self.update_running_mean = True
        self._prev_dones = np.zeros(self.num_envs, dtype=bool)  # [N]
        self._autoreset_mode = env.metadata.get("autoreset_mode", AutoresetMode.NEXT_STEP)

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset and forget the accumulated returns."""
        self.accumulated_reward[:] = 0
        self._prev_dones[:] = False
        return self.env.reset(seed=seed, options=options)

    def step(self, actions: Any) -> StepReturn:
        """Step; rewards scaled by ``1 / sqrt(return var + eps)``."""
        obs, reward, terminated, truncated, info = self.env.step(actions)
        if self._autoreset_mode is AutoresetMode.SAME_STEP:
            active = np.ones(self.num_envs, dtype=bool)
        else:
            active = ~self._prev_dones  # NEXT_STEP: a reset step is not part of any return
        self.accumulated_reward[active] = (
            self.accumulated_reward[active] * self.gamma * (1 - terminated[active]) + reward[active]
        )
        if self.update_running_mean and active.any():
            self.return_rms.update(self.accumulated_reward[active])
        self._prev_dones = np.logical_or(terminated, truncated)
        if self._autoreset_mode is AutoresetMode.SAME_STEP:
            self.accumulated_reward[self._prev_dones] = 0
        return (
            obs,
            reward / np.sqrt(self.return_rms.var + self.epsilon),
            terminated,
            truncated,
            info,
        )
