"""batch_space, batch_differing_spaces, iterate, concatenate and create_empty_array vs gymnasium."""

from __future__ import annotations

import re
import warnings
from typing import Any

import gymnasium.spaces
import gymnasium.vector.utils as gym_vec
import numpy as np
import pytest

import palaestra.spaces
from palaestra.error import CustomSpaceError
from palaestra.spaces import Box, Dict, Discrete, Tuple, batching

from .cases import SPACES, assert_same, build

NAMES = list(SPACES)


@pytest.fixture(autouse=True)
def _quiet() -> object:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("n", [1, 3])
def test_batch_space_matches(name: str, n: int) -> None:
    ours, theirs = build(name)
    ours.seed(10)
    theirs.seed(10)
    batched, twin = batching.batch_space(ours, n), gym_vec.batch_space(theirs, n)
    assert repr(batched) == repr(twin)
    # The batched space starts from a copy of the original's generator, as in gymnasium.
    for _ in range(2):
        assert_same(batched.sample(), twin.sample())
    assert_same(ours.sample(), theirs.sample())


@pytest.mark.parametrize("name", NAMES)
def test_concatenate_iterate_and_empty_arrays_match(name: str) -> None:
    ours, theirs = build(name)
    ours.seed(3)
    theirs.seed(3)
    items = [ours.sample() for _ in range(3)]
    twins = [theirs.sample() for _ in range(3)]
    for fn in (np.zeros, np.ones):
        assert_same(
            batching.create_empty_array(ours, 3, fn), gym_vec.create_empty_array(theirs, 3, fn)
        )
    stacked = batching.concatenate(ours, items, batching.create_empty_array(ours, 3))
    stacked_twin = gym_vec.concatenate(theirs, twins, gym_vec.create_empty_array(theirs, 3))
    assert_same(stacked, stacked_twin)
    batched = batching.batch_space(ours, 3)
    assert stacked in batched
    unstacked = list(batching.iterate(batched, stacked))
    assert_same(unstacked, list(gym_vec.iterate(gym_vec.batch_space(theirs, 3), stacked_twin)))
    assert all(item in ours for item in unstacked)


def test_discrete_cannot_be_iterated() -> None:
    with pytest.raises(TypeError, match="Unable to iterate over a space of type `Discrete`"):
        batching.iterate(Discrete(3), np.array([0, 1]))
    with pytest.raises(TypeError, match="Unable to iterate over the following elements: 5"):
        batching.iterate(Box(0, 1), 5)


def test_concatenate_writes_into_out() -> None:
    space = Dict(a=Box(0, 1, (2,)), b=Tuple([Discrete(3), Discrete(2)]))
    out = batching.create_empty_array(space, 2, np.empty)
    items = [space.sample() for _ in range(2)]
    result = batching.concatenate(space, items, out)
    assert result["a"] is out["a"] and result["b"][0] is out["b"][0]
    np.testing.assert_array_equal(out["a"][1], items[1]["a"])


@pytest.mark.parametrize(
    "item",
    [
        np.array([0.5, -1.0], dtype=np.float64),  # cast to the space's float32, as np.stack
        np.array([0.25, 0.75], dtype=np.float32),
    ],
)
def test_concatenate_one_row_is_np_stack(item: np.ndarray) -> None:
    """The one-row fast path writes what np.stack writes, into ``out``."""
    space = Box(-2, 2, (2,))
    out = batching.create_empty_array(space, 1, np.empty)
    result = batching.concatenate(space, [item], out)
    assert result is out
    expected = np.stack([item], axis=0, out=np.empty((1, 2), np.float32))
    np.testing.assert_array_equal(out, expected)
    assert out.dtype == np.float32


def test_concatenate_one_row_keeps_np_stack_errors() -> None:
    int_box = Box(0, 9, (2,), dtype=np.int64)
    out = batching.create_empty_array(int_box, 1)
    with pytest.raises(TypeError, match="Cannot cast array data from dtype\\('float64'\\)"):
        batching.concatenate(int_box, [np.array([1.5, 2.0])], out)
    box_out = batching.create_empty_array(Box(0, 1, (2,)), 1)
    with pytest.raises(ValueError, match="Output array is the wrong shape"):
        batching.concatenate(Box(0, 1, (2,)), [np.zeros(3, np.float32)], box_out)


DIFFERING: list[Any] = [
    lambda S: [S.Discrete(3), S.Discrete(5, start=2), S.Discrete(4, dtype=np.int32)],
    lambda S: [S.Box(0, 1, (2,)), S.Box(-1, 3, (2,))],
    lambda S: [S.MultiDiscrete([2, 3]), S.MultiDiscrete([4, 5], start=[1, 1])],
    lambda S: [S.MultiBinary(3), S.MultiBinary(3)],
    lambda S: [S.Tuple((S.Discrete(2), S.Box(0, 1))), S.Tuple((S.Discrete(4), S.Box(0, 2)))],
    lambda S: [S.Dict(a=S.Discrete(2)), S.Dict(a=S.Discrete(6))],
    lambda S: [S.Text(3), S.Text(4)],
    lambda S: [S.Sequence(S.Discrete(2)), S.Sequence(S.Discrete(3))],
    lambda S: [S.OneOf([S.Discrete(2)]), S.OneOf([S.Discrete(3)])],
    lambda S: [S.Graph(S.Discrete(2), None), S.Graph(S.Discrete(3), None)],
]


@pytest.mark.parametrize("recipe", DIFFERING)
def test_batch_differing_spaces_matches(recipe: Any) -> None:
    ours = batching.batch_differing_spaces(recipe(palaestra.spaces))
    theirs = gym_vec.batch_differing_spaces(recipe(gymnasium.spaces))
    assert repr(ours) == repr(theirs)
    assert ours.sample() in ours


BAD_DIFFERING: list[tuple[Any, type[Exception], str]] = [
    (lambda S: [], ValueError, "non-empty list of spaces"),
    (lambda S: [S.Discrete(2), S.Box(0, 1)], TypeError, "same type"),
    (lambda S: [S.Box(0, 1, (2,)), S.Box(0, 1, (3,))], ValueError, "Box.low shape to be equal"),
    (lambda S: [S.Box(0, 1), S.Box(0, 1, dtype=np.float64)], ValueError, "dtypes to be equal"),
    (
        lambda S: [S.MultiDiscrete([2]), S.MultiDiscrete([2, 2])],
        ValueError,
        "MultiDiscrete.nvec shape",
    ),
    (lambda S: [S.MultiBinary(2), S.MultiBinary(3)], ValueError, "MultiBinary shapes to be equal"),
    (lambda S: [S.Dict(a=S.Discrete(2)), S.Dict(b=S.Discrete(2))], ValueError, "same keys"),
    (lambda S: [S.Space(), S.Space()], TypeError, "registered `batch_differing_space`"),
]


@pytest.mark.parametrize(("recipe", "exc", "match"), BAD_DIFFERING)
def test_batch_differing_spaces_errors(recipe: Any, exc: type, match: str) -> None:
    with pytest.raises(exc, match=re.escape(match)):
        gym_vec.batch_differing_spaces(recipe(gymnasium.spaces))
    with pytest.raises(exc, match=re.escape(match)):
        batching.batch_differing_spaces(recipe(palaestra.spaces))


@pytest.mark.parametrize("fn", ["batch_space", "concatenate", "create_empty_array", "iterate"])
def test_non_spaces_are_rejected(fn: str) -> None:
    args: tuple[Any, ...] = {"batch_space": (5, 2), "concatenate": (5, [], None)}.get(fn, (5, 2))
    with pytest.raises(TypeError, match="is not a palaestra Space instance"):
        getattr(batching, fn)(*args)


def test_custom_space_fallbacks() -> None:
    class Custom(palaestra.spaces.Space[int]):
        def sample(self, mask: Any = None, probability: Any = None) -> int:
            return int(self.np_random.integers(10))

    space = Custom(seed=1)
    batched = batching.batch_space(space, 2)
    assert isinstance(batched, Tuple) and len(batched) == 2
    assert batching.create_empty_array(space, 2) is None
    assert batching.concatenate(space, [1, 2], None) == (1, 2)
    with pytest.raises(CustomSpaceError, match="doesn't have an registered `iterate` function"):
        batching.iterate(space, [1, 2])
    assert list(batching.iterate(Tuple([space, space]), (1, 2))) == [1, 2]
