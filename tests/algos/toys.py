"""Tiny envs covering the spaces the algorithms accept (not vector envs: plain ``Env``s)."""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra import spaces
from palaestra.core import Env


class Toy(Env[Any, Any]):
    """Episodes of ``horizon`` steps (truncated); reward 1 when the action 'matches' the obs.

    ``obs`` picks the observation space: "box", "image" (HWC uint8), "image_chw", "dict";
    ``action`` picks the action space: "discrete", "box", "multidiscrete", "multibinary".
    """

    def __init__(self, obs: str = "box", action: str = "discrete", horizon: int = 10) -> None:
        self.kind, self.horizon = obs, horizon
        self.observation_space = {
            "box": spaces.Box(-1, 1, (3,)),
            "image": spaces.Box(0, 255, (36, 36, 1), np.uint8),
            "image_chw": spaces.Box(0, 255, (1, 36, 36), np.uint8),
            "dict": spaces.Dict(
                {
                    "img": spaces.Box(0, 255, (1, 36, 36), np.uint8),
                    "vec": spaces.Box(-1, 1, (2,)),
                    "flag": spaces.MultiBinary(1),
                }
            ),
        }[obs]
        self.action_space = {
            "discrete": spaces.Discrete(2),
            "box": spaces.Box(-1, 1, (2,)),
            "multidiscrete": spaces.MultiDiscrete([2, 3]),
            "multibinary": spaces.MultiBinary(2),
        }[action]
        self.t, self.bit = 0, 0

    def _obs(self) -> Any:
        self.bit = int(self.np_random.integers(2))
        sign = 1.0 if self.bit else -1.0
        if self.kind == "box":
            return np.array([sign, 0.5, -0.5], dtype=np.float32)
        if self.kind.startswith("image"):
            shape = self.observation_space.shape
            return np.full(shape, 255 * self.bit, dtype=np.uint8)
        return {
            "img": np.full((1, 36, 36), 255 * self.bit, np.uint8),
            "vec": np.array([sign, 0.0], np.float32),
            "flag": np.array([self.bit], np.int8),
        }

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        self.t = 0
        return self._obs(), {}

    def step(self, action: Any) -> Any:
        first = float(np.asarray(action).reshape(-1)[0])
        reward = float((first > 0.5) == bool(self.bit))
        self.t += 1
        return self._obs(), reward, False, self.t >= self.horizon, {}
