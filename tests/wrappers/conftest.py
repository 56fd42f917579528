"""Toy environments written once and built twice (palaestra and gymnasium), plus parity helpers.

Every toy draws from ``self.np_random`` so that a seeded palaestra toy and a seeded gymnasium
toy produce the same stream; the wrappers under test are then compared step by step.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable
from types import SimpleNamespace
from typing import Any

import gymnasium
import gymnasium.envs.registration
import numpy as np

# name -> submodule of palaestra.wrappers, the entries proposed for wrappers/__init__.py's _LAZY
WRAPPER_MODULES: dict[str, str] = {
    "Autoreset": "episode_stats",
    "RecordEpisodeStatistics": "episode_stats",
    "TransformObservation": "transform_observation",
    "FilterObservation": "transform_observation",
    "FlattenObservation": "transform_observation",
    "GrayscaleObservation": "transform_observation",
    "ReshapeObservation": "transform_observation",
    "RescaleObservation": "transform_observation",
    "DtypeObservation": "transform_observation",
    "DiscretizeObservation": "discretize",
    "ResizeObservation": "resize",
    "TransformAction": "transform_action",
    "ClipAction": "transform_action",
    "RescaleAction": "transform_action",
    "DiscretizeAction": "discretize",
    "TransformReward": "transform_reward",
    "ClipReward": "transform_reward",
    "DelayObservation": "stateful_observation",
    "TimeAwareObservation": "stateful_observation",
    "NormalizeObservation": "stateful_observation",
    "MaxAndSkipObservation": "stateful_observation",
    "FrameStackObservation": "frame_stack",
    "StickyAction": "stateful_action",
    "RepeatAction": "stateful_action",
    "NormalizeReward": "stateful_reward",
    "Monitor": "monitor",
}


def _wrappers() -> SimpleNamespace:
    """``palaestra.wrappers`` as it will read once the lead adds the entries above."""
    return SimpleNamespace(
        **{
            name: getattr(importlib.import_module(f"palaestra.wrappers.{module}"), name)
            for name, module in WRAPPER_MODULES.items()
        }
    )


def _lib(name: str) -> SimpleNamespace:
    if name == "gymnasium":
        return SimpleNamespace(
            name=name,
            Env=gymnasium.Env,
            spaces=gymnasium.spaces,
            W=gymnasium.wrappers,
            EnvSpec=gymnasium.envs.registration.EnvSpec,
        )
    import palaestra.spaces
    from palaestra.envs.env_spec import EnvSpec

    return SimpleNamespace(
        name=name, Env=palaestra.core.Env, spaces=palaestra.spaces, W=_wrappers(), EnvSpec=EnvSpec
    )


GYM = _lib("gymnasium")


def pal() -> SimpleNamespace:
    return _lib("palaestra")


def _toys(lib: SimpleNamespace) -> dict[str, type]:
    sp, base = lib.spaces, lib.Env

    class ToyContinuous(base):  # type: ignore[misc,valid-type]
        """3-D drifting point pushed by a 2-D action; ends when |x0| > 2 or after max_steps."""

        def __init__(self, max_steps: int = 30) -> None:
            self.observation_space = sp.Box(-5.0, 5.0, (3,), np.float32)
            self.action_space = sp.Box(-1.0, 1.0, (2,), np.float32)
            self.max_steps = max_steps

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            self.state = self.np_random.uniform(-1, 1, 3).astype(np.float32)
            self.t = 0
            return self.state.copy(), {"t": 0}

        def step(self, action):
            a = np.asarray(action, dtype=np.float32)
            push = np.array([a[0], a[1], a[0] - a[1]], dtype=np.float32)
            noise = 0.1 * self.np_random.standard_normal(3)
            self.state = np.clip(self.state + 0.4 * push + noise, -5, 5).astype(np.float32)
            self.t += 1
            reward = float(self.state[0] - 0.1 * np.abs(a).sum())
            terminated = bool(abs(self.state[0]) > 2.0)
            return self.state.copy(), reward, terminated, self.t >= self.max_steps, {"t": self.t}

    class ToyChain(base):  # type: ignore[misc,valid-type]
        """Slippery walk on 0..9 (Discrete obs and actions); ends at either end."""

        def __init__(self, max_steps: int = 20) -> None:
            self.observation_space = sp.Discrete(10)
            self.action_space = sp.Discrete(3)
            self.max_steps = max_steps

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            self.pos = int(self.np_random.integers(2, 6))
            self.t = 0
            return self.pos, {}

        def step(self, action):
            move = int(action) - 1
            if self.np_random.uniform() < 0.2:
                move = -move
            self.pos = min(max(self.pos + move, 0), 9)
            self.t += 1
            terminated = self.pos in (0, 9)
            reward = 1.0 if self.pos == 9 else -0.1
            return self.pos, reward, terminated, self.t >= self.max_steps, {"pos": self.pos}

    class ToyDict(base):  # type: ignore[misc,valid-type]
        """Dict observation (two Boxes and a counter), Discrete(2) actions."""

        def __init__(self, max_steps: int = 15) -> None:
            self.observation_space = sp.Dict(
                {
                    "pos": sp.Box(-5.0, 5.0, (2,), np.float32),
                    "vel": sp.Box(-1.0, 1.0, (2,), np.float32),
                    "count": sp.Discrete(100),
                }
            )
            self.action_space = sp.Discrete(2)
            self.max_steps = max_steps

        def _obs(self):
            return {"pos": self.pos.copy(), "vel": self.vel.copy(), "count": self.t}

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            self.pos = self.np_random.uniform(-1, 1, 2).astype(np.float32)
            self.vel = np.zeros(2, dtype=np.float32)
            self.t = 0
            return self._obs(), {}

        def step(self, action):
            self.vel = np.clip(
                self.vel + (0.3 if action else -0.3) + 0.1 * self.np_random.standard_normal(2),
                -1,
                1,
            ).astype(np.float32)
            self.pos = np.clip(self.pos + self.vel, -5, 5).astype(np.float32)
            self.t += 1
            terminated = bool(np.abs(self.pos).max() >= 4.0)
            return (
                self._obs(),
                float(-np.abs(self.pos).sum()),
                terminated,
                self.t >= self.max_steps,
                {},
            )

    class ToyTuple(base):  # type: ignore[misc,valid-type]
        """Tuple observation (Box, Discrete, Box), Discrete(2) actions."""

        def __init__(self, max_steps: int = 12) -> None:
            self.observation_space = sp.Tuple(
                (
                    sp.Box(-1.0, 1.0, (2,), np.float32),
                    sp.Discrete(4),
                    sp.Box(0.0, 1.0, (1,), np.float32),
                )
            )
            self.action_space = sp.Discrete(2)
            self.max_steps = max_steps

        def _obs(self):
            x = self.np_random.uniform(-1, 1, 2).astype(np.float32)
            return (x, int(self.t % 4), np.array([self.t / self.max_steps], dtype=np.float32))

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            self.t = 0
            return self._obs(), {}

        def step(self, action):
            self.t += 1
            return self._obs(), float(action), False, self.t >= self.max_steps, {}

    class ToyImage(base):  # type: ignore[misc,valid-type]
        """(6, 5, 3) uint8 random images, Discrete(2) actions."""

        def __init__(self, max_steps: int = 10) -> None:
            self.observation_space = sp.Box(0, 255, (6, 5, 3), np.uint8)
            self.action_space = sp.Discrete(2)
            self.max_steps = max_steps

        def _obs(self):
            return self.np_random.integers(0, 256, (6, 5, 3), dtype=np.uint8)

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            self.t = 0
            return self._obs(), {}

        def step(self, action):
            self.t += 1
            return self._obs(), 1.0, False, self.t >= self.max_steps, {}

    return {cls.__name__: cls for cls in (ToyContinuous, ToyChain, ToyDict, ToyTuple, ToyImage)}


_CACHE: dict[str, dict[str, type]] = {}


def make_toy(lib: SimpleNamespace, name: str, **kwargs: Any) -> Any:
    """A fresh instance of toy ``name`` built on ``lib`` (gymnasium or palaestra)."""
    if lib.name not in _CACHE:
        _CACHE[lib.name] = _toys(lib)
    return _CACHE[lib.name][name](**kwargs)


def sample_action(space: Any, rng: np.random.Generator) -> Any:
    """An action drawn from ``rng`` that means the same for both libraries' spaces."""
    kind = type(space).__name__
    if kind == "Box":
        low = np.where(np.isfinite(space.low), space.low, -2.0)
        high = np.where(np.isfinite(space.high), space.high, 2.0)
        # draw a little outside finite bounds too, so clipping wrappers have work to do
        return rng.uniform(low - 0.2, high + 0.2).astype(space.dtype)
    if kind == "Discrete":
        return int(rng.integers(space.start, space.start + space.n))
    if kind == "MultiDiscrete":
        return rng.integers(space.start, space.start + space.nvec).astype(space.dtype)
    raise TypeError(f"no sampler for {space}")


def rollout(
    lib: SimpleNamespace,
    toy: str,
    wrap: Callable[[Any, SimpleNamespace], Any],
    *,
    steps: int = 60,
    seed: int = 7,
    manual_reset: bool = True,
    toy_kwargs: dict[str, Any] | None = None,
) -> tuple[Any, list[tuple[Any, ...]]]:
    """Reset with ``seed`` and step with seeded random actions; returns the env and every
    ``("reset", obs, info)`` / ``("step", obs, reward, terminated, truncated, info)``."""
    env = wrap(make_toy(lib, toy, **(toy_kwargs or {})), lib)
    rng = np.random.default_rng(seed + 1000)
    obs, info = env.reset(seed=seed)
    records: list[tuple[Any, ...]] = [("reset", obs, info)]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(sample_action(env.action_space, rng))
        records.append(("step", obs, reward, terminated, truncated, info))
        if manual_reset and (terminated or truncated):
            records.append(("reset", *env.reset()))
    return env, records


def assert_same(a: Any, b: Any, path: str = "") -> None:
    """Equal values *and* types, recursively (arrays: dtype, shape and elements, NaN == NaN)."""
    if isinstance(b, np.ndarray):
        assert isinstance(a, np.ndarray), f"{path}: {type(a)} vs ndarray"
        assert a.dtype == b.dtype and a.shape == b.shape, (
            f"{path}: {a.dtype}{a.shape} vs {b.dtype}{b.shape}"
        )
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), f"{path}: {a} vs {b}"
    elif isinstance(b, dict):
        assert isinstance(a, dict) and list(a) == list(b), f"{path}: keys {a!r} vs {b!r}"
        for key in b:
            assert_same(a[key], b[key], f"{path}[{key!r}]")
    elif isinstance(b, (tuple, list)):
        assert type(a) is type(b) and len(a) == len(b), f"{path}: {a!r} vs {b!r}"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{path}[{i}]")
    else:
        assert type(a) is type(b), f"{path}: {type(a)} vs {type(b)} ({a!r} vs {b!r})"
        if isinstance(b, float) and math.isnan(b):
            assert math.isnan(a), path
        else:
            assert a == b, f"{path}: {a!r} vs {b!r}"
