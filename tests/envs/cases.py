"""The classic-control ids, their classes, and deterministic action rules for parity runs.

The rules mix seeded random actions with simple controllers so that the episodes in a
1000-step run actually terminate (random MountainCar/Acrobot play never does), and the
continuous ones include out-of-range values, which both libraries clip.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from palaestra.envs.classic_control import (
    AcrobotBatch,
    AcrobotEnv,
    CartPoleBatch,
    CartPoleEnv,
    Continuous_MountainCarEnv,
    ContinuousMountainCarBatch,
    MountainCarBatch,
    MountainCarEnv,
    PendulumBatch,
    PendulumEnv,
)

CLASSIC_IDS = [
    "CartPole-v0",
    "CartPole-v1",
    "MountainCar-v0",
    "MountainCarContinuous-v0",
    "Pendulum-v1",
    "Acrobot-v1",
]

# id -> (single env class, batched engine class)
CLASSES: dict[str, tuple[type, type]] = {
    "CartPole-v1": (CartPoleEnv, CartPoleBatch),
    "MountainCar-v0": (MountainCarEnv, MountainCarBatch),
    "MountainCarContinuous-v0": (Continuous_MountainCarEnv, ContinuousMountainCarBatch),
    "Pendulum-v1": (PendulumEnv, PendulumBatch),
    "Acrobot-v1": (AcrobotEnv, AcrobotBatch),
}

Policy = Callable[[np.random.Generator, np.ndarray], Any]


def _cartpole(rng: np.random.Generator, obs: np.ndarray) -> int:
    return int(rng.integers(2))


def _mountain_car(rng: np.random.Generator, obs: np.ndarray) -> int:
    if rng.random() < 0.8:  # push along the velocity: reaches the flag in ~100 steps
        return 2 if obs[1] >= 0 else 0
    return int(rng.integers(3))


def _continuous_mountain_car(rng: np.random.Generator, obs: np.ndarray) -> np.ndarray:
    if rng.random() < 0.7:
        force = (1.0 if obs[1] >= 0 else -1.0) * rng.uniform(0.5, 1.3)  # some beyond +-1
    else:
        force = rng.uniform(-1.5, 1.5)
    return np.array([force], dtype=np.float32)


def _pendulum(rng: np.random.Generator, obs: np.ndarray) -> np.ndarray:
    return rng.uniform(-2.5, 2.5, size=(1,)).astype(np.float32)  # some beyond +-2


def _acrobot(rng: np.random.Generator, obs: np.ndarray) -> int:
    if rng.random() < 0.9:  # torque against the first joint's motion pumps energy in
        return 0 if obs[4] > 0 else 2
    return int(rng.integers(3))


POLICIES: dict[str, Policy] = {
    "CartPole-v0": _cartpole,
    "CartPole-v1": _cartpole,
    "MountainCar-v0": _mountain_car,
    "MountainCarContinuous-v0": _continuous_mountain_car,
    "Pendulum-v1": _pendulum,
    "Acrobot-v1": _acrobot,
}


def batch_actions(env_id: str, rng: np.random.Generator, obs: np.ndarray) -> np.ndarray:
    """One action per row of ``obs [N, d]``, from the same rules."""
    policy = POLICIES[env_id]
    acts = [policy(rng, row) for row in obs]
    return np.array(acts, dtype=np.int64) if isinstance(acts[0], int) else np.stack(acts)
