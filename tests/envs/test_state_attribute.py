"""`env.unwrapped.state` reads like Gymnasium's and cannot be changed by a silent in-place write."""

import numpy as np
import pytest

import palaestra as gym

IDS = ["CartPole-v1", "MountainCar-v0", "MountainCarContinuous-v0", "Pendulum-v1", "Acrobot-v1"]


@pytest.mark.parametrize("env_id", IDS)
def test_in_place_write_raises_and_assignment_works(env_id: str) -> None:
    env = gym.make(env_id)
    env.reset(seed=0)
    state = env.unwrapped.state
    with pytest.raises(ValueError, match="read-only"):
        state[0] = 0.1
    new = np.full_like(state, 0.01)  # off every equilibrium: the next step moves it
    env.unwrapped.state = new
    np.testing.assert_array_equal(env.unwrapped.state, new)
    env.step(env.action_space.sample())
    assert not np.array_equal(env.unwrapped.state, new)
