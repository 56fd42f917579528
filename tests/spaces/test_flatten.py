"""Flatten utilities against gymnasium.spaces.utils, plus round trips and error cases."""

from __future__ import annotations

import re
import warnings
from typing import Any

import gymnasium.spaces
import gymnasium.spaces.utils as gym_utils
import numpy as np
import pytest

import palaestra.spaces
from palaestra.spaces import Box, Discrete, Graph, MultiDiscrete, Sequence, Text, Tuple, utils

from .cases import FLATTENABLE, SPACES, assert_same, build


@pytest.fixture(autouse=True)
def _quiet() -> object:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


@pytest.mark.parametrize("name", FLATTENABLE)
def test_flatdim_and_flatten_space_match(name: str) -> None:
    ours, theirs = build(name)
    assert utils.flatdim(ours) == gym_utils.flatdim(theirs)
    flat_ours, flat_theirs = utils.flatten_space(ours), gym_utils.flatten_space(theirs)
    assert repr(flat_ours) == repr(flat_theirs)
    np.testing.assert_array_equal(flat_ours.low, flat_theirs.low)
    np.testing.assert_array_equal(flat_ours.high, flat_theirs.high)


@pytest.mark.parametrize("name", FLATTENABLE)
def test_flatten_matches_and_round_trips(name: str) -> None:
    ours, theirs = build(name)
    ours.seed(4)
    theirs.seed(4)
    flat_space = utils.flatten_space(ours)
    for _ in range(3):
        sample, twin = ours.sample(), theirs.sample()
        flat = utils.flatten(ours, sample)
        assert_same(flat, gym_utils.flatten(theirs, twin))
        assert flat in flat_space
        assert flat.shape == (utils.flatdim(ours),)
        back = utils.unflatten(ours, flat)
        assert_same(back, gym_utils.unflatten(theirs, gym_utils.flatten(theirs, twin)))
        assert back in ours


@pytest.mark.parametrize("name", [n for n in SPACES if n not in FLATTENABLE])
def test_non_flattenable_spaces_match(name: str) -> None:
    ours, theirs = build(name)
    assert repr(utils.flatten_space(ours)) == repr(gym_utils.flatten_space(theirs))
    with pytest.raises(ValueError):
        gym_utils.flatdim(theirs)
    with pytest.raises(ValueError):
        utils.flatdim(ours)
    ours.seed(8)
    theirs.seed(8)
    sample, twin = ours.sample(), theirs.sample()
    flat = utils.flatten(ours, sample)
    assert_same(flat, gym_utils.flatten(theirs, twin))
    assert flat in utils.flatten_space(ours)
    assert_same(
        utils.unflatten(ours, flat), gym_utils.unflatten(theirs, gym_utils.flatten(theirs, twin))
    )


@pytest.mark.parametrize(
    "recipe",
    [
        lambda S: S.Tuple((S.Discrete(2), S.Sequence(S.Box(0, 1)))),
        lambda S: S.Dict(a=S.Discrete(2), g=S.Graph(S.Box(0, 1, (2,)), None)),
        lambda S: S.Sequence(S.Dict(a=S.Discrete(3), b=S.Box(0, 1, (2,))), stack=True),
    ],
)
def test_partly_flattenable_containers_match(recipe: Any) -> None:
    ours, theirs = recipe(palaestra.spaces), recipe(gymnasium.spaces)
    assert repr(utils.flatten_space(ours)) == repr(gym_utils.flatten_space(theirs))
    ours.seed(2)
    theirs.seed(2)
    sample, twin = ours.sample(), theirs.sample()
    flat = utils.flatten(ours, sample)
    assert_same(flat, gym_utils.flatten(theirs, twin))
    assert_same(utils.unflatten(ours, flat), sample)


def test_known_values() -> None:
    assert utils.flatten(Discrete(3, start=-1), -1).tolist() == [1, 0, 0]
    assert utils.flatten(MultiDiscrete([2, 3]), np.array([1, 2])).tolist() == [0, 1, 0, 0, 1]
    assert utils.flatten(Text(4, charset="ab"), "ba").tolist() == [1, 0, 2, 2]
    assert utils.unflatten(Text(4, charset="ab"), np.array([1, 0, 2, 2])) == "ba"
    assert utils.flatdim(Box(0, 1, (2, 3, 4))) == 24
    assert utils.flat_dtype(Tuple([Discrete(2), Box(0, 1)])) == np.float64


def test_oneof_flat_dtype_grows_to_hold_the_index() -> None:
    ours = palaestra.spaces.OneOf([palaestra.spaces.Box(0, 1, (1,), np.bool_)] * 3)
    theirs = gymnasium.spaces.OneOf([gymnasium.spaces.Box(0, 1, (1,), np.bool_)] * 3)
    assert repr(utils.flatten_space(ours)) == repr(gym_utils.flatten_space(theirs))
    flat = utils.flatten(ours, (2, np.array([True])))
    assert flat.tolist() == [2, 1]
    assert utils.unflatten(ours, flat)[0] == 2


@pytest.mark.parametrize(
    ("call", "exc", "match"),
    [
        (lambda: utils.unflatten(Discrete(3), np.zeros(3)), ValueError, "not a valid one-hot"),
        (
            lambda: utils.unflatten(MultiDiscrete([2]), np.zeros(2)),
            ValueError,
            "one-hot encoded vectors",
        ),
        (
            lambda: utils.unflatten(Tuple([Discrete(2)]), (np.array([1, 0]),)),
            AssertionError,
            "only unflatten numpy arrays",
        ),
        (
            lambda: utils.unflatten(Tuple([Sequence(Discrete(2))]), np.zeros(2)),
            TypeError,
            "only unflatten tuples",
        ),
        (
            lambda: utils.unflatten(palaestra.spaces.Dict(a=Discrete(2)), {"a": 1}),
            TypeError,
            "must be a numpy array",
        ),
        (
            lambda: utils.flatdim(Graph(Discrete(2), None)),
            ValueError,
            "Graph Space has a dynamic size",
        ),
        (
            lambda: utils.flatdim(Sequence(Discrete(2))),
            ValueError,
            "cannot be flattened to a numpy array",
        ),
        (lambda: utils.flatdim(Tuple([Sequence(Discrete(2))])), ValueError, "cannot be flattened"),
        (lambda: utils.flatten(palaestra.spaces.Space(), 1), NotImplementedError, "Unknown space"),
        (
            lambda: utils.flatten_space(palaestra.spaces.Space()),
            NotImplementedError,
            "Unknown space",
        ),
        (
            lambda: utils.unflatten(palaestra.spaces.Space(), 1),
            NotImplementedError,
            "Unknown space",
        ),
    ],
)
def test_flatten_errors(call: Any, exc: type, match: str) -> None:
    with pytest.raises(exc, match=re.escape(match)):
        call()


EQUIV = [
    (lambda S: S.Box(0, 1, (2,)), lambda S: S.Box(-3, 3, (2,))),
    (lambda S: S.Box(0, 1, (2,)), lambda S: S.Box(0, 1, (3,))),
    (lambda S: S.Box(0, 1, (2,)), lambda S: S.Box(0, 1, (2,), np.float64)),
    (lambda S: S.Discrete(2), lambda S: S.Discrete(7, start=3)),
    (lambda S: S.Discrete(2), lambda S: S.MultiDiscrete([2])),
    (lambda S: S.Text(3), lambda S: S.Text(3, min_length=0)),
    (lambda S: S.Text(3), lambda S: S.Text(3, charset="ab")),
    (lambda S: S.Dict(a=S.Discrete(2)), lambda S: S.Dict(a=S.Discrete(5))),
    (lambda S: S.Dict(a=S.Discrete(2)), lambda S: S.Dict(b=S.Discrete(2))),
    (lambda S: S.Tuple([S.Discrete(2)]), lambda S: S.Tuple([S.Discrete(3), S.Discrete(3)])),
    (lambda S: S.OneOf([S.MultiBinary(2)]), lambda S: S.OneOf([S.MultiBinary(2)])),
    (lambda S: S.Graph(S.Discrete(2), None), lambda S: S.Graph(S.Discrete(3), None)),
    (lambda S: S.Graph(S.Discrete(2), None), lambda S: S.Graph(S.Discrete(2), S.Discrete(2))),
    (lambda S: S.Sequence(S.Discrete(2)), lambda S: S.Sequence(S.Discrete(2), stack=True)),
]


@pytest.mark.parametrize(("first", "second"), EQUIV)
def test_is_space_dtype_shape_equiv_matches(first: Any, second: Any) -> None:
    ours = utils.is_space_dtype_shape_equiv(first(palaestra.spaces), second(palaestra.spaces))
    theirs = gym_utils.is_space_dtype_shape_equiv(first(gymnasium.spaces), second(gymnasium.spaces))
    assert ours == theirs
