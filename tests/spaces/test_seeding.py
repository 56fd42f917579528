"""Seeding: constructor seeds, composite seed formats and their errors, as in gymnasium."""

from __future__ import annotations

import re
from typing import Any

import gymnasium.spaces
import numpy as np
import pytest

import palaestra.spaces
from palaestra import error

from .cases import assert_same

SEEDED: dict[str, Any] = {
    "box": lambda S: S.Box(0, 1, (3,), seed=42),
    "discrete": lambda S: S.Discrete(5, seed=42),
    "multi_discrete": lambda S: S.MultiDiscrete([2, 3], seed=42),
    "multi_binary": lambda S: S.MultiBinary(3, seed=42),
    "text": lambda S: S.Text(5, seed=42),
    "tuple": lambda S: S.Tuple((S.Discrete(2), S.Box(0, 1)), seed=42),
    "tuple_list_seed": lambda S: S.Tuple((S.Discrete(2), S.Box(0, 1)), seed=[3, 4]),
    "dict": lambda S: S.Dict({"a": S.Discrete(2), "b": S.Box(0, 1)}, seed=42),
    "dict_dict_seed": lambda S: S.Dict(
        {"a": S.Discrete(2), "b": S.Box(0, 1)}, seed={"a": 1, "b": 2}
    ),
    "oneof": lambda S: S.OneOf((S.Discrete(2), S.Box(0, 1)), seed=42),
    "oneof_tuple_seed": lambda S: S.OneOf((S.Discrete(2), S.Box(0, 1)), seed=(1, 2, 3)),
    "sequence": lambda S: S.Sequence(S.Discrete(4), seed=42),
    "sequence_pair_seed": lambda S: S.Sequence(S.Discrete(4), seed=(5, 6)),
    "graph": lambda S: S.Graph(S.Box(0, 1, (2,)), S.Discrete(3), seed=42),
    "graph_no_edges": lambda S: S.Graph(S.Box(0, 1, (2,)), None, seed=42),
    "graph_triple_seed": lambda S: S.Graph(S.Box(0, 1, (2,)), S.Discrete(3), seed=(1, 2, 3)),
}


@pytest.mark.parametrize("name", list(SEEDED))
def test_constructor_seed_matches_gymnasium(name: str) -> None:
    ours, theirs = SEEDED[name](palaestra.spaces), SEEDED[name](gymnasium.spaces)
    for _ in range(3):
        assert_same(ours.sample(), theirs.sample())


@pytest.mark.parametrize(
    ("recipe", "seed"),
    [
        (lambda S: S.Tuple((S.Discrete(2), S.Tuple((S.Discrete(3), S.Box(0, 1))))), [1, [2, 3]]),
        (lambda S: S.Dict(a=S.Discrete(2), b=S.Dict(c=S.Discrete(3))), {"a": 1, "b": {"c": 2}}),
        (lambda S: S.OneOf((S.Discrete(2), S.Discrete(3))), 123),
        (lambda S: S.Sequence(S.Tuple((S.Discrete(2), S.Discrete(3)))), (1, [2, 3])),
        (lambda S: S.Graph(S.Discrete(2), None), [7, 8]),
        (lambda S: S.Dict(a=S.Tuple((S.Discrete(2), S.Discrete(2))), b=S.Box(0, 1)), 99),
    ],
)
def test_nested_seed_return_values_match(recipe: Any, seed: Any) -> None:
    ours, theirs = recipe(palaestra.spaces), recipe(gymnasium.spaces)
    assert ours.seed(seed) == theirs.seed(seed)
    assert_same(ours.sample(), theirs.sample())


def test_int_and_tuple_seeding_leave_oneof_in_same_state() -> None:
    space = palaestra.spaces.OneOf((palaestra.spaces.Discrete(2), palaestra.spaces.Discrete(3)))
    seeds = space.seed(10)
    first = [space.sample() for _ in range(5)]
    space.seed(seeds)
    assert [space.sample() for _ in range(5)] == first


@pytest.mark.parametrize(
    ("recipe", "seed", "exc", "match"),
    [
        (lambda S: S.Tuple((S.Discrete(2),)), [1, 2], ValueError, "number of subspaces"),
        (lambda S: S.Tuple((S.Discrete(2),)), 1.5, TypeError, "list, tuple, int or None"),
        (lambda S: S.Dict(a=S.Discrete(2)), {"b": 1}, ValueError, "not identical to space keys"),
        (lambda S: S.Dict(a=S.Discrete(2)), "x", TypeError, "dict, int or None"),
        (lambda S: S.OneOf((S.Discrete(2),)), (1,), ValueError, "number of subspaces + 1"),
        (lambda S: S.OneOf((S.Discrete(2),)), 1.5, TypeError, "None, int, or tuple"),
        (lambda S: S.Sequence(S.Discrete(2)), (1, 2, 3), ValueError, "two elements"),
        (lambda S: S.Sequence(S.Discrete(2)), 1.5, TypeError, "None, int, tuple of ints"),
        (lambda S: S.Graph(S.Discrete(2), None), (1, 2, 3), ValueError, "two values"),
        (lambda S: S.Graph(S.Discrete(2), S.Discrete(2)), (1, 2), ValueError, "three values"),
        (lambda S: S.Graph(S.Discrete(2), None), 1.5, TypeError, "int or tuple of ints"),
    ],
)
def test_bad_composite_seeds(recipe: Any, seed: Any, exc: type, match: str) -> None:
    with pytest.raises(exc, match=re.escape(match)):
        recipe(gymnasium.spaces).seed(seed)
    with pytest.raises(exc, match=re.escape(match)):
        recipe(palaestra.spaces).seed(seed)


@pytest.mark.parametrize("seed", [-1, 1.5, "3"])
def test_bad_simple_seed_raises_palaestra_error(seed: Any) -> None:
    with pytest.raises(error.Error, match="Seed must be"):
        palaestra.spaces.Discrete(3).seed(seed)


def test_seed_returns_the_seed_and_reseeding_repeats() -> None:
    space = palaestra.spaces.Box(-1, 1, (4,))
    assert space.seed(17) == 17
    first = space.sample()
    space.seed(17)
    np.testing.assert_array_equal(space.sample(), first)
    assert isinstance(space.seed(), int)


def test_unseeded_composite_still_samples() -> None:
    space = palaestra.spaces.Tuple([palaestra.spaces.Discrete(2)])
    assert isinstance(space.np_random, np.random.Generator)
    assert space.sample() in space
