"""Wrapper behaviour users meet coming from Gymnasium (issue 16, items 2, 6, 12 and 15).

Error types checked side by side with the installed gymnasium; old names get Gymnasium's
"has been renamed" hint; ``palaestra.wrappers.vector`` imports as ``gymnasium.wrappers.vector``.
"""

from __future__ import annotations

import importlib

import gymnasium
import gymnasium.wrappers.vector
import pytest

import palaestra as gym
import palaestra.wrappers
from palaestra import error, spaces
from palaestra.wrappers import FilterObservation, StickyAction


@pytest.mark.parametrize("name", sorted(palaestra.wrappers.vector.__all__))
def test_every_vector_wrapper_imports_from_the_gymnasium_path(name):
    namespace: dict = {}
    exec(f"from palaestra.wrappers.vector import {name}", namespace)  # as users write it
    assert namespace[name] is getattr(palaestra.wrappers.vector, name)
    assert namespace[name].__module__.startswith("palaestra.wrappers.vector.")  # one definition
    assert palaestra.wrappers.vector is importlib.import_module("palaestra.wrappers.vector")


def test_vector_wrapper_names_are_gymnasiums():
    ours = set(palaestra.wrappers.vector.__all__)
    theirs = set(gymnasium.wrappers.vector.__all__)
    assert ours <= theirs | {
        "VectorizeTransformAction",
        "VectorizeTransformObservation",
        "VectorizeTransformReward",
    }, ours - theirs


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ("FrameStack", "FrameStackObservation"),
        ("AutoResetWrapper", "Autoreset"),
        ("PixelObservationWrapper", "AddRenderObservation"),
        ("VectorListInfo", "vector.DictInfoToList"),
    ],
)
def test_renamed_wrappers_say_so_as_gymnasium(old, new):
    message = f"'{old}' has been renamed with `wrappers.{new}`"
    with pytest.raises(AttributeError, match=message):
        getattr(gymnasium.wrappers, old)
    with pytest.raises(error.DeprecatedWrapper, match=message):
        getattr(palaestra.wrappers, old)
    with pytest.raises(ImportError, match=message):  # the hint survives `from ... import`
        exec(f"from palaestra.wrappers import {old}", {})


def test_unknown_wrapper_is_still_an_attribute_error():
    with pytest.raises(AttributeError, match="has no attribute 'NoSuchWrapper'"):
        palaestra.wrappers.NoSuchWrapper  # noqa: B018


def test_filter_observation_with_a_string_is_a_value_error_as_gymnasium():
    theirs_space = gymnasium.spaces.Dict({"key": gymnasium.spaces.Discrete(2)})
    theirs = gymnasium.make("CartPole-v1")
    theirs.observation_space = theirs_space
    with pytest.raises(ValueError):
        gymnasium.wrappers.FilterObservation(theirs, filter_keys="key")

    class DictEnv(gym.Env):
        observation_space = spaces.Dict({"key": spaces.Discrete(2), "other": spaces.Discrete(2)})
        action_space = spaces.Discrete(2)

    with pytest.raises(ValueError, match=r"got the string 'key'; pass \['key'\]"):
        FilterObservation(DictEnv(), filter_keys="key")
    assert list(FilterObservation(DictEnv(), ["key"]).observation_space) == ["key"]


@pytest.mark.parametrize("duration", [[1, 3], [2, 2]])
def test_sticky_action_refuses_a_list_duration_as_gymnasium(duration):
    with pytest.raises(ValueError, match="should be either an integer or a tuple"):
        gymnasium.wrappers.StickyAction(gymnasium.make("CartPole-v1"), 0.5, duration)
    with pytest.raises(ValueError, match="should be either an integer or a tuple"):
        StickyAction(gym.make("CartPole-v1"), 0.5, duration)
    StickyAction(gym.make("CartPole-v1"), 0.5, tuple(duration))  # a tuple is fine
