"""Wrapper base classes: fall-through, overrides, attribute helpers, no implicit forwarding."""

from __future__ import annotations

import numpy as np
import pytest
from tests.core.test_env import Counter

from palaestra.core import ActionWrapper, ObservationWrapper, RewardWrapper, Wrapper
from palaestra.spaces import Discrete


class Plus(ObservationWrapper):
    def observation(self, observation):
        return observation + 100


class Double(RewardWrapper):
    def reward(self, reward):
        return 2 * reward


class Flip(ActionWrapper):
    def __init__(self, env):
        super().__init__(env)
        self.action_space = Discrete(2, start=5)

    def action(self, action):
        return action - 5


def test_template_methods_apply() -> None:
    env = Flip(Double(Plus(Counter())))
    obs, _ = env.reset(seed=0)
    assert obs[0] >= 100
    obs, reward, terminated, truncated, _ = env.step(6)
    assert obs[0] == 101 and reward == 2.0 and not terminated and not truncated
    assert env.action_space == Discrete(2, start=5)
    assert env.env.action_space == Discrete(2)


def test_spaces_and_metadata_fall_through_until_set() -> None:
    inner = Counter()
    env = Wrapper(inner)
    assert env.observation_space is inner.observation_space
    assert env.metadata is inner.metadata
    env.metadata = {"render_modes": []}
    assert inner.metadata == {"render_modes": ["ansi"]}


def test_render_mode_np_random_and_seed_come_from_inner() -> None:
    inner = Counter(render_mode="ansi")
    env = Wrapper(Wrapper(inner))
    env.reset(seed=3)
    assert env.render_mode == "ansi"
    assert env.np_random is inner.np_random
    assert env.np_random_seed == 3
    env.np_random = np.random.default_rng(0)
    assert inner.np_random_seed == -1
    with pytest.raises(AttributeError, match="Can't access `_np_random` of a wrapper"):
        _ = env._np_random


def test_no_implicit_attribute_forwarding() -> None:
    env = Wrapper(Counter())
    with pytest.raises(AttributeError):
        _ = env.t  # type: ignore[attr-defined]
    assert env.get_wrapper_attr("t") == 0
    assert env.unwrapped.t == 0  # type: ignore[attr-defined]


def test_set_wrapper_attr_sets_where_defined() -> None:
    inner = Counter()
    env = Wrapper(Wrapper(inner))
    assert env.set_wrapper_attr("t", 9)
    assert inner.t == 9 and "t" not in vars(env)
    assert env.set_wrapper_attr("fresh", 1)
    assert vars(env)["fresh"] == 1
    assert not env.set_wrapper_attr("other", 1, force=False)


def test_get_wrapper_attr_error_names_wrapper() -> None:
    with pytest.raises(AttributeError, match="wrapper Plus has no attribute 'missing'"):
        Plus(Counter()).get_wrapper_attr("missing")


def test_str_and_repr_nest() -> None:
    env = Double(Plus(Counter()))
    assert str(env) == repr(env) == "<Double<Plus<Counter instance>>>"


def test_wrapping_a_non_env_is_a_type_error() -> None:
    with pytest.raises(
        TypeError, match=r"Expected env to be a `palaestra\.Env` but got <class 'int'>"
    ):
        Wrapper(3)  # type: ignore[arg-type]


def test_close_and_render_reach_inner() -> None:
    inner = Counter(render_mode="ansi")
    env = Plus(inner)
    env.reset()
    assert env.render() == "t=0"
    env.close()
    assert inner.closed == 1


def test_base_template_methods_raise_not_implemented() -> None:
    with pytest.raises(NotImplementedError):
        ObservationWrapper(Counter()).observation(0)
    with pytest.raises(NotImplementedError):
        RewardWrapper(Counter()).reward(0)
    with pytest.raises(NotImplementedError):
        ActionWrapper(Counter()).action(0)
