"""DQN's exploration draws: one env takes scalar draws from the generator (a fifth of the cost
of the [1] arrays), which must be the same numbers the array draws give, so that one-env runs
act and learn exactly as before."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import palaestra
from palaestra import spaces
from palaestra.algos import DQN
from palaestra.wrappers import TimeLimit


def _reference_explore(model: DQN, rng: np.random.Generator) -> np.ndarray:
    """``DQN._explore`` as written for any number of envs, on ``rng``."""
    n, high, start = model.n_envs, int(model.action_space.n), int(model.action_space.start)
    if model.num_timesteps < model.learning_starts:
        return rng.integers(0, high, size=n) + start
    explore = rng.random(n) < model.exploration_rate
    random_actions = rng.integers(0, high, size=n) + start
    if explore.all():
        return random_actions
    return np.where(explore, random_actions, model._greedy(model._last_obs))


@pytest.mark.parametrize("warm", [False, True])
def test_one_env_explore_draws_as_arrays(warm: bool) -> None:
    env = palaestra.make("CartPole-v1")
    model = DQN("MlpPolicy", env, learning_starts=50, seed=3)
    model.learn(60 if warm else 10)
    model.exploration_rate = 0.4  # both branches, often
    rng = copy.deepcopy(model._rng)
    for _ in range(200):
        expected = _reference_explore(model, rng)
        actions = model._explore()
        np.testing.assert_array_equal(actions, expected)
        assert actions.shape == (1,) and actions.dtype == expected.dtype
    assert model._rng.bit_generator.state == rng.bit_generator.state


def test_one_env_random_actions_keep_the_start() -> None:
    env = TimeLimit(palaestra.make("CartPole-v1").unwrapped, 50)
    env.action_space = spaces.Discrete(5, start=-2)
    model = DQN("MlpPolicy", env, seed=0)
    rng = copy.deepcopy(model._rng)
    drawn = np.concatenate([model._random_actions(1) for _ in range(300)])
    np.testing.assert_array_equal(drawn, rng.integers(0, 5, size=300) - 2)
    assert set(drawn.tolist()) == {-2, -1, 0, 1, 2}
