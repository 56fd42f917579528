"""MountainCarContinuous steps that hit its float32/float64 corner cases, against Gymnasium.

Random trajectories rarely clip the velocity near the goal or start from a float64 state with
an out-of-range action; these crafted states do, for goal velocities on both sides of the
float32 roundings of 0 and +-max_speed (where Gymnasium's Python-float velocity compares
differently from a float32 one). The batch steps the same states in its rows.
"""

from __future__ import annotations

import itertools
from typing import Any

import gymnasium
import numpy as np
import pytest

from palaestra.envs.classic_control import Continuous_MountainCarEnv, ContinuousMountainCarBatch

F32_SPEED = float(np.float32(0.07))  # 0.07000000029802322
GOALS = [0, 1e-50, -1e-50, 0.07, -0.07, 0.0700000001, -0.0700000001, 0.06999999999]
GOALS += [-0.06999999999, F32_SPEED, -F32_SPEED, 0.1, -0.1]
STATES = [  # (position, velocity): near the goal fast, at the walls, at rest
    (0.44, 0.0699),
    (0.44, F32_SPEED),
    (0.59, 0.069),
    (0.6, -0.0699),
    (0.46, -0.0001),
    (0.45, 0.0),
    (-1.19, -0.0699),
    (-1.2, 0.0),
    (-0.5, 0.0),
]
ACTIONS = [1.0, -1.0, 0.5, 1.7, -3.0, 0.0]


def _gym_step(goal: float, state: np.ndarray, action: float) -> tuple[Any, ...]:
    env: Any = gymnasium.make("MountainCarContinuous-v0", goal_velocity=goal).unwrapped
    env.reset(seed=0)
    env.state = state.copy()
    obs, reward, terminated, _, _ = env.step(np.array([action], dtype=np.float32))
    return np.asarray(obs, dtype=np.float32).tobytes(), float(reward), bool(terminated)


@pytest.mark.parametrize("goal", GOALS)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_crafted_steps_match_gymnasium(goal: float, dtype: type) -> None:
    """Single env and batch rows equal Gymnasium's step from each crafted state and action."""
    cases = list(itertools.product(STATES, ACTIONS))
    states: list[np.ndarray] = [np.array(s, dtype=dtype) for s, _ in cases]
    actions = np.array([[a] for _, a in cases], dtype=np.float32)
    expected = [_gym_step(goal, s, float(a[0])) for s, a in zip(states, actions)]

    env = Continuous_MountainCarEnv(goal_velocity=goal)
    env.reset(seed=0)
    for state, action, want in zip(states, actions, expected):
        env.state = state
        obs, reward, terminated, _, _ = env.step(action)
        assert (obs.tobytes(), reward, terminated) == want, (goal, state, action)

    batch = ContinuousMountainCarBatch(len(cases), goal_velocity=goal)
    batch.reset(seed=0)
    batch._state[:] = np.array(states, dtype=np.float64)  # the float32 or float64 values
    batch._fresh[:] = dtype is np.float64  # a float64 state is the one a reset leaves
    obs, rewards, dones = batch.step(actions)
    got = [(o.tobytes(), float(r), bool(t)) for o, r, t in zip(obs, rewards, dones)]
    assert got == expected
