"""A table of spaces built twice (palaestra and gymnasium) from one recipe, plus comparators.

Each recipe takes a spaces module (``palaestra.spaces`` or ``gymnasium.spaces``) so that the
two libraries get exactly the same constructor calls.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import gymnasium.spaces
import numpy as np

import palaestra.spaces

Recipe = Callable[[Any], Any]

F32 = np.float32


def _arr(values: list[Any], dtype: Any = np.float64) -> np.ndarray:
    return np.array(values, dtype=dtype)


SPACES: dict[str, Recipe] = {
    # Box: bounded, unbounded, half-bounded, integer, bool, scalar-shaped
    "box_mountaincar": lambda S: S.Box(_arr([-1.2, -0.07], F32), _arr([0.6, 0.07], F32)),
    "box_atari": lambda S: S.Box(0, 255, (210, 160, 3), np.uint8),
    "box_scalar_bounds": lambda S: S.Box(-1.0, 2.0, shape=(3, 4)),
    "box_unbounded": lambda S: S.Box(-np.inf, np.inf, (4,)),
    "box_mixed": lambda S: S.Box(
        _arr([-np.inf, 0, -np.inf, -2]), _arr([np.inf, np.inf, 1, 3]), dtype=np.float64
    ),
    "box_shape_empty": lambda S: S.Box(0.0, 1.0, shape=()),
    "box_int32": lambda S: S.Box(-5, 5, (2, 3), np.int32),
    "box_int_half": lambda S: S.Box(-np.inf, 5, (4,), np.int32),
    "box_int64_full": lambda S: S.Box(-np.inf, np.inf, (3,), np.int64),
    "box_uint8_arrays": lambda S: S.Box(_arr([0, 10], np.uint8), _arr([5, 200], np.uint8)),
    "box_bool": lambda S: S.Box(0, 1, (3,), np.bool_),
    "box_float16": lambda S: S.Box(-1, 1, (2,), np.float16),
    # Discrete
    "discrete": lambda S: S.Discrete(3),
    "discrete_start": lambda S: S.Discrete(3, start=-1),
    "discrete_int32": lambda S: S.Discrete(5, start=2, dtype=np.int32),
    "discrete_uint8": lambda S: S.Discrete(200, dtype=np.uint8),
    # MultiDiscrete / MultiBinary
    "multi_discrete": lambda S: S.MultiDiscrete([5, 2, 2]),
    "multi_discrete_2d": lambda S: S.MultiDiscrete(
        np.array([[1, 2], [3, 4]]), start=np.array([[-1, 0], [2, 3]])
    ),
    "multi_discrete_int8": lambda S: S.MultiDiscrete([3, 4], dtype=np.int8, start=[-3, 120]),
    "multi_binary": lambda S: S.MultiBinary(5),
    "multi_binary_2d": lambda S: S.MultiBinary([3, 2]),
    # Text
    "text": lambda S: S.Text(5),
    "text_charset": lambda S: S.Text(8, min_length=0, charset="abcd"),
    "text_set": lambda S: S.Text(4, min_length=2, charset=frozenset("xyz")),
    # Containers
    "tuple": lambda S: S.Tuple((S.Discrete(2), S.Box(-1, 1, shape=(2,)))),
    "tuple_nested": lambda S: S.Tuple(
        (S.MultiBinary(3), S.Tuple((S.Discrete(4, start=1), S.MultiDiscrete([2, 3]))))
    ),
    "dict": lambda S: S.Dict({"position": S.Box(-1, 1, shape=(2,)), "color": S.Discrete(3)}),
    "dict_unsorted": lambda S: S.Dict(
        {"z": S.Discrete(2), "a": S.Box(0, 1, (1,))}, sort_keys=False
    ),
    "dict_nested": lambda S: S.Dict(
        ext=S.MultiDiscrete([5, 2, 2]),
        inner=S.Dict(charge=S.Discrete(100), checks=S.MultiBinary(4), text=S.Text(3)),
    ),
    "oneof": lambda S: S.OneOf((S.Discrete(2), S.Box(-1, 1, shape=(2,)))),
    "oneof_three": lambda S: S.OneOf(
        (S.MultiBinary(2), S.Discrete(5, start=3), S.Box(0, 4, (3,), np.int32))
    ),
    # Variable-size
    "sequence": lambda S: S.Sequence(S.Box(0, 1)),
    "sequence_stack": lambda S: S.Sequence(S.Discrete(3), stack=True),
    "sequence_of_dict": lambda S: S.Sequence(S.Dict(a=S.Discrete(2), b=S.Box(0, 1, (2,)))),
    "graph": lambda S: S.Graph(S.Box(-100, 100, shape=(3,)), S.Discrete(3)),
    "graph_no_edges": lambda S: S.Graph(S.Discrete(4), None),
    "graph_box_edges": lambda S: S.Graph(S.Discrete(5), S.Box(0, 1, (2,))),
}

FLATTENABLE = [name for name in SPACES if not name.startswith(("sequence", "graph"))]


def build(name: str) -> tuple[Any, Any]:
    """The (palaestra, gymnasium) pair for ``name``; precision warnings are not the point."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return SPACES[name](palaestra.spaces), SPACES[name](gymnasium.spaces)


def assert_same(ours: Any, theirs: Any, path: str = "sample") -> None:
    """Assert two samples are identical: structure, Python/numpy types, dtypes and values."""
    if hasattr(theirs, "_fields"):  # GraphInstance
        assert type(ours).__name__ == type(theirs).__name__, path
        for field in theirs._fields:
            assert_same(getattr(ours, field), getattr(theirs, field), f"{path}.{field}")
        return
    if isinstance(theirs, (tuple, list)):
        assert type(ours) is type(theirs), (path, type(ours), type(theirs))
        assert len(ours) == len(theirs), path
        for i, (a, b) in enumerate(zip(ours, theirs)):
            assert_same(a, b, f"{path}[{i}]")
        return
    if isinstance(theirs, dict):
        assert isinstance(ours, dict), path
        assert list(ours) == list(theirs), path
        for key in theirs:
            assert_same(ours[key], theirs[key], f"{path}[{key!r}]")
        return
    if theirs is None or isinstance(theirs, (str, int, float, bool)):
        assert type(ours) is type(theirs) and ours == theirs, (path, ours, theirs)
        return
    assert type(ours) is type(theirs), (path, type(ours), type(theirs))
    assert ours.dtype == theirs.dtype, (path, ours.dtype, theirs.dtype)
    assert np.shape(ours) == np.shape(theirs), path
    assert np.array_equal(ours, theirs), (path, ours, theirs)
