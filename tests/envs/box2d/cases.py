"""Box2D ids, the kwargs variants checked against Gymnasium, and action rules for parity runs.

Random play ends LunarLander episodes in crashes; the landing controller below (a PD rule on
tilt and descent rate, mixed with random actions) also brings the lander to rest, so the
+100 "asleep" ending and the leg-contact flags are exercised too.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

BOX2D_IDS = [
    "LunarLander-v3",
    "LunarLanderContinuous-v3",
    "BipedalWalker-v3",
    "BipedalWalkerHardcore-v3",
    "CarRacing-v3",
]
# Every CarRacing observation is a drawn frame (~0.02-0.04 s a step on the test machines):
# its whole-contract checks run with the slow tests, its short parity run in the fast suite.
SLOW_IDS = {"CarRacing-v3"}


def id_params(ids: list[str]) -> list[Any]:
    """``ids`` for ``parametrize``, the slow ones marked ``slow``."""
    return [pytest.param(i, marks=pytest.mark.slow) if i in SLOW_IDS else i for i in ids]


# (id, kwargs) pairs for parity: every documented knob of each env at least once.
LUNAR_VARIANTS: list[tuple[str, dict[str, Any]]] = [
    ("LunarLander-v3", {}),
    ("LunarLanderContinuous-v3", {}),
    ("LunarLander-v3", {"enable_wind": True}),
    ("LunarLander-v3", {"continuous": True, "enable_wind": True, "turbulence_power": 0.5}),
    ("LunarLander-v3", {"gravity": -3.5, "enable_wind": True, "wind_power": 5.0}),
    ("LunarLander-v3", {"continuous": True, "gravity": -11.9}),
]

Policy = Callable[[np.random.Generator, np.ndarray, float], Any]


def _lander_targets(obs: np.ndarray) -> tuple[float, float]:
    """How much to turn and how much to thrust: >0 turn right / push up."""
    x, y, vx, vy, angle, spin, left, right = (float(v) for v in obs)
    want_angle = min(max(0.6 * x + 0.9 * vx, -0.35), 0.35)  # lean towards the pad
    turn = 0.6 * (want_angle - angle) - 0.9 * spin
    lift = 0.5 * (0.5 * abs(x) - y) - 0.6 * vy
    if left or right:  # touching down: only brake the fall
        turn, lift = 0.0, -0.5 * vy
    return turn, lift


def lander_discrete(rng: np.random.Generator, obs: np.ndarray, explore: float = 0.15) -> int:
    """The controller, or a random action with probability ``explore``."""
    if rng.random() < explore:
        return int(rng.integers(4))
    turn, lift = _lander_targets(obs)
    if lift > abs(turn) and lift > 0.05:
        return 2
    if turn < -0.05:
        return 3
    return 1 if turn > 0.05 else 0


def lander_continuous(
    rng: np.random.Generator, obs: np.ndarray, explore: float = 0.15
) -> np.ndarray:
    """The controller's throttles (some beyond [-1, 1], which both libraries clip) or noise."""
    if rng.random() < explore:
        return rng.uniform(-1.3, 1.3, size=2).astype(np.float32)
    turn, lift = _lander_targets(obs)
    return np.array([lift * 20 - 1, -turn * 20], dtype=np.float32).clip(-1.2, 1.2)


def policy_for(env: Any) -> Policy:
    """The action rule for a made env (continuous or discrete)."""
    return lander_continuous if env.unwrapped.continuous else lander_discrete


def walker_action(rng: np.random.Generator, t: int, dtype: Any = np.float32) -> np.ndarray:
    """A rough open-loop stride (hips in antiphase, knees lagging) plus noise, some of it
    beyond [-1, 1]: it walks a few metres before falling, so contacts come and go."""
    s = np.sin(0.1 * t)
    k = np.sin(0.1 * t - 1.5)
    stride = np.array([s, k, -s, -k])
    return (stride + rng.normal(0.0, 0.4, size=4)).astype(dtype)
