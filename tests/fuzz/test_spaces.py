"""Spaces built from random (often wrong) arguments: a clear error, or a space whose samples are
members and whose ``contains`` answers a bool for anything."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from tests.fuzz.strategies import (
    BUDGETS,
    clear,
    counts,
    dtypes_junk,
    fuzz_settings,
    junk,
    sizes,
)

from palaestra import spaces

pytestmark = pytest.mark.timeout(600)

shapes = st.one_of(st.none(), sizes, st.lists(sizes, max_size=3).map(tuple), junk)
bounds = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-300, 300),
    st.lists(st.floats(-5, 5), min_size=1, max_size=3).map(np.array),
    junk,
)
simple_spaces = st.sampled_from(
    [spaces.Discrete(3), spaces.Box(-1, 1, (2,)), spaces.MultiBinary(2), spaces.Text(3)]
)
children = st.one_of(simple_spaces, junk)


def recipe(cls: type, required: dict[str, Any], optional: dict[str, Any] | None = None) -> Any:
    """``(cls, kwargs)`` with each argument drawn from its strategy (right or wrong)."""
    return st.tuples(st.just(cls), st.fixed_dictionaries(required, optional=optional or {}))


int_lists = st.one_of(sizes, st.lists(sizes, max_size=3))
# (constructor, keyword arguments) for every space type.
recipes = st.one_of(
    recipe(spaces.Box, {"low": bounds, "high": bounds}, {"shape": shapes, "dtype": dtypes_junk}),
    recipe(spaces.Discrete, {"n": counts}, {"start": counts, "dtype": dtypes_junk}),
    recipe(
        spaces.MultiDiscrete,
        {"nvec": st.one_of(int_lists, junk)},
        {"start": int_lists, "dtype": dtypes_junk},
    ),
    recipe(spaces.MultiBinary, {"n": st.one_of(int_lists, junk)}),
    recipe(
        spaces.Text,
        {"max_length": sizes},
        {"min_length": sizes, "charset": st.one_of(st.text(max_size=4), junk)},
    ),
    recipe(spaces.Tuple, {"spaces": st.lists(children, max_size=3)}),
    recipe(
        spaces.Dict,
        {"spaces": st.one_of(st.dictionaries(st.text(max_size=2), children, max_size=3), junk)},
    ),
    recipe(spaces.Sequence, {"space": children}, {"stack": st.booleans()}),
    recipe(spaces.OneOf, {"spaces": st.lists(children, max_size=3)}),
    recipe(spaces.Graph, {"node_space": children, "edge_space": st.none() | children}),
)
# What contains() is asked about: anything, including graph-shaped junk.
members = st.one_of(junk, st.builds(spaces.GraphInstance, junk, junk, junk))


def _check_space(cls: type, kwargs: dict[str, Any], value: Any, seed: int) -> None:
    space = clear(lambda: cls(**kwargs), *kwargs.values())
    if space is None:
        return
    space.seed(seed)
    sample = space.sample()
    assert space.contains(sample), f"{space!r}.sample() = {sample!r} is not in it"
    answer = space.contains(value)
    assert isinstance(answer, bool), f"{space!r}.contains({value!r}) = {answer!r}"
    repr(space)


@BUDGETS
def test_space_constructors_sample_and_contains(budget: str) -> None:
    @fuzz_settings(budget, fast=150, slow=4000)
    @given(recipes, members, st.integers(0, 2**32 - 1))
    def prop(recipe: tuple[type, dict[str, Any]], value: Any, seed: int) -> None:
        _check_space(*recipe, value, seed)

    prop()
