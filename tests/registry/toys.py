"""A toy environment written once and built for both palaestra and gymnasium.

The registry, wrapper and checker tests register it under their own ids, so that they need
none of the built-in environments and can compare palaestra's behaviour with gymnasium's.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any, ClassVar

import gymnasium
import numpy as np

import palaestra


def toy_class(lib: ModuleType) -> type:
    """``ToyEnv`` subclassing ``lib.Env``: a seeded 2-D walk with rgb_array and ansi rendering."""

    class ToyEnv(lib.Env):  # type: ignore[name-defined,misc]
        metadata: ClassVar[dict[str, Any]] = {
            "render_modes": ["rgb_array", "ansi"],
            "render_fps": 4,
        }

        def __init__(self, render_mode: str | None = None, size: int = 2) -> None:
            self.observation_space = lib.spaces.Box(-1.0, 1.0, (size,), np.float32)
            self.action_space = lib.spaces.Discrete(2)
            self.render_mode = render_mode
            self.size = size
            self.closed = 0
            self._state = np.zeros(size, np.float32)

        def reset(
            self, *, seed: int | None = None, options: dict[str, Any] | None = None
        ) -> tuple[np.ndarray, dict[str, Any]]:
            super().reset(seed=seed)
            self._state = self.np_random.uniform(-0.5, 0.5, self.size).astype(np.float32)
            return self._state.copy(), {}

        def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
            delta = 0.1 if action == 1 else -0.1
            self._state = np.clip(self._state + delta, -1.0, 1.0).astype(np.float32)
            return self._state.copy(), 1.0, False, False, {}

        def render(self) -> Any:
            if self.render_mode == "rgb_array":
                return np.zeros((4, 4, 3), np.uint8)
            if self.render_mode == "ansi":
                return str(self._state)
            return None

        def close(self) -> None:
            self.closed += 1

    return ToyEnv


PalToy = toy_class(palaestra)
GymToy = toy_class(gymnasium)
# Let pickle find the classes by name.
PalToy.__qualname__, GymToy.__qualname__ = "PalToy", "GymToy"


class ScaleReward(palaestra.Wrapper, palaestra.utils.RecordConstructorArgs):  # type: ignore[misc]
    """A wrapper that records its kwargs, so that ``make(env.spec)`` can rebuild it."""

    def __init__(self, env: palaestra.Env, scale: float = 1.0) -> None:  # type: ignore[type-arg]
        palaestra.utils.RecordConstructorArgs.__init__(self, scale=scale)
        palaestra.Wrapper.__init__(self, env)
        self.scale = scale

    def step(self, action: Any) -> Any:
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, self.scale * reward, terminated, truncated, info


class Unrecorded(palaestra.Wrapper):  # type: ignore[misc]
    """A wrapper without RecordConstructorArgs: its spec has ``kwargs=None``."""


def prewrapped_toy(**kwargs: Any) -> palaestra.Env:  # type: ignore[type-arg]
    """An entry point that applies a wrapper itself."""
    return ScaleReward(PalToy(**kwargs), scale=3.0)
