"""Env base-class behaviour, checked against gymnasium.Env."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

from palaestra import error
from palaestra.core import Env
from palaestra.spaces import Box, Discrete


class Counter(Env):
    """Observation = number of steps since reset; terminates after 3 steps."""

    metadata = {"render_modes": ["ansi"]}

    def __init__(self, render_mode: str | None = None) -> None:
        self.observation_space = Box(0, 10, (1,), np.float32)
        self.action_space = Discrete(2)
        self.render_mode = render_mode
        self.t = 0
        self.closed = 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return np.array([self.np_random.uniform(0, 1)], np.float32), {}

    def step(self, action):
        self.t += 1
        return np.array([self.t], np.float32), 1.0, self.t >= 3, False, {}

    def render(self):
        return f"t={self.t}"

    def close(self):
        self.closed += 1


def test_reset_seed_draws_like_gymnasium() -> None:
    ours = Counter()
    ref = gymnasium.Env()
    obs, _ = ours.reset(seed=123)
    gymnasium.Env.reset(ref, seed=123)
    assert obs[0] == np.float32(ref.np_random.uniform(0, 1))
    assert ours.np_random_seed == ref.np_random_seed == 123


def test_reset_without_seed_keeps_generator() -> None:
    env = Counter()
    env.reset(seed=1)
    rng = env.np_random
    env.reset()
    assert env.np_random is rng
    assert env.np_random_seed == 1


def test_np_random_is_lazy_and_settable() -> None:
    env = Counter()
    assert env._np_random is None
    assert isinstance(env.np_random, np.random.Generator)
    assert env.np_random_seed >= 0
    env.np_random = np.random.default_rng(5)
    assert env.np_random_seed == -1


@pytest.mark.parametrize(
    ("seed", "message"),
    [
        (-1, "Seed must be greater or equal to zero, actual value: -1"),
        (1.5, "Seed must be a python integer, actual type: <class 'float'>"),
        ("7", "Seed must be a python integer, actual type: <class 'str'>"),
    ],
)
def test_bad_seed_matches_gymnasium(seed: object, message: str) -> None:
    with pytest.raises(error.Error) as ours:
        Counter().reset(seed=seed)  # type: ignore[arg-type]
    with pytest.raises(gymnasium.error.Error) as ref:
        gymnasium.Env.reset(gymnasium.Env(), seed=seed)  # type: ignore[arg-type]
    assert str(ours.value) == str(ref.value) == message


def test_str_context_manager_and_unwrapped() -> None:
    env = Counter()
    assert str(env) == "<Counter instance>"
    assert env.unwrapped is env
    with env as inner:
        assert inner is env
    assert env.closed == 1


def test_wrapper_attr_helpers_on_bare_env() -> None:
    env = Counter()
    assert env.has_wrapper_attr("t") and not env.has_wrapper_attr("nope")
    assert env.get_wrapper_attr("t") == 0
    assert env.set_wrapper_attr("t", 5) and env.t == 5
    assert not env.set_wrapper_attr("nope", 1, force=False)
    with pytest.raises(AttributeError):
        env.get_wrapper_attr("nope")
