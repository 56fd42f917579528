"""Masked and probability-weighted sampling: same draws as gymnasium, and bad masks rejected."""

from __future__ import annotations

import re
from typing import Any

import gymnasium.spaces
import numpy as np
import pytest

import palaestra.spaces
from palaestra import error
from palaestra.spaces import InvalidMask, InvalidProbabilityMask

from .cases import assert_same

I8 = np.int8


def _m(*values: int) -> np.ndarray:
    return np.array(values, dtype=I8)


def _p(*values: float) -> np.ndarray:
    return np.array(values, dtype=np.float64)


# (recipe, kwargs for sample) — each drawn several times from identically seeded twins.
MASKED: dict[str, tuple[Any, dict[str, Any]]] = {
    "discrete_mask": (lambda S: S.Discrete(4, start=2), {"mask": _m(0, 1, 1, 0)}),
    "discrete_mask_empty": (lambda S: S.Discrete(4, start=2), {"mask": _m(0, 0, 0, 0)}),
    "discrete_probability": (lambda S: S.Discrete(3), {"probability": _p(0.2, 0.0, 0.8)}),
    "discrete_int32_prob": (
        lambda S: S.Discrete(3, dtype=np.int32),
        {"probability": _p(0.5, 0.5, 0.0)},
    ),
    "multi_discrete_mask": (
        lambda S: S.MultiDiscrete([3, 2]),
        {"mask": (_m(1, 0, 1), _m(0, 0))},
    ),
    "multi_discrete_prob": (
        lambda S: S.MultiDiscrete([3, 2], start=[1, -1]),
        {"probability": (_p(0.1, 0.6, 0.3), _p(0.0, 1.0))},
    ),
    "multi_discrete_2d_mask": (
        lambda S: S.MultiDiscrete([[2, 3], [2, 2]]),
        {"mask": ((_m(0, 1), _m(1, 1, 0)), (_m(1, 1), _m(0, 1)))},
    ),
    "multi_binary_mask": (lambda S: S.MultiBinary(4), {"mask": _m(0, 1, 2, 2)}),
    "multi_binary_prob": (
        lambda S: S.MultiBinary([2, 2]),
        {"probability": _p(0.1, 0.9, 1, 0).reshape(2, 2)},
    ),
    "text_mask": (lambda S: S.Text(6, charset="abcd"), {"mask": (None, _m(1, 0, 1, 0))}),
    "text_length": (lambda S: S.Text(6, charset="abcd"), {"mask": (4, None)}),
    "text_empty_mask_min0": (
        lambda S: S.Text(6, min_length=0, charset="abc"),
        {"mask": (None, _m(0, 0, 0))},
    ),
    "text_probability": (
        lambda S: S.Text(6, charset="abcd"),
        {"probability": (3, _p(0.1, 0.2, 0.3, 0.4))},
    ),
    "tuple_mask": (
        lambda S: S.Tuple((S.Discrete(3), S.MultiBinary(2), S.Box(0, 1))),
        {"mask": (_m(0, 1, 1), _m(2, 1), None)},
    ),
    "tuple_probability": (
        lambda S: S.Tuple((S.Discrete(3), S.Box(0, 1))),
        {"probability": (_p(0.5, 0.5, 0), None)},
    ),
    "dict_mask": (
        lambda S: S.Dict(a=S.Discrete(3), b=S.MultiDiscrete([2, 2])),
        {"mask": {"a": _m(1, 0, 1), "b": (_m(1, 1), _m(1, 0))}},
    ),
    "dict_probability": (
        lambda S: S.Dict(a=S.Discrete(3), b=S.Box(0, 1)),
        {"probability": {"a": _p(0, 0, 1), "b": None}},
    ),
    "oneof_mask": (
        lambda S: S.OneOf((S.Discrete(3), S.MultiBinary(2))),
        {"mask": (_m(0, 0, 1), _m(2, 0))},
    ),
    "oneof_probability": (
        lambda S: S.OneOf((S.Discrete(3), S.Discrete(2))),
        {"probability": (_p(0, 0.5, 0.5), _p(1, 0))},
    ),
    "sequence_length_int": (lambda S: S.Sequence(S.Discrete(3)), {"mask": (3, _m(1, 1, 0))}),
    "sequence_length_array": (
        lambda S: S.Sequence(S.Discrete(3), stack=True),
        {"mask": (np.array([1, 4, 6]), None)},
    ),
    "sequence_probability": (
        lambda S: S.Sequence(S.Discrete(3)),
        {"probability": (None, _p(0.3, 0.3, 0.4))},
    ),
    "graph_mask": (
        lambda S: S.Graph(S.Discrete(3), S.Discrete(4)),
        {"mask": (tuple(_m(0, 1, 1) for _ in range(4)), _m(1, 0, 0, 1)), "num_nodes": 4},
    ),
    "graph_probability_edges": (
        lambda S: S.Graph(S.Box(0, 1, (2,)), S.Discrete(2)),
        {"probability": (None, (_p(0.25, 0.75),) * 5), "num_nodes": 3, "num_edges": 5},
    ),
    "graph_defaults": (lambda S: S.Graph(S.Box(0, 1, (2,)), S.Box(-1, 0)), {}),
}


@pytest.mark.parametrize("name", list(MASKED))
def test_masked_sampling_matches_gymnasium(name: str) -> None:
    recipe, kwargs = MASKED[name]
    ours, theirs = recipe(palaestra.spaces), recipe(gymnasium.spaces)
    ours.seed(123)
    theirs.seed(123)
    for _ in range(6):
        sample = ours.sample(**kwargs)
        assert_same(sample, theirs.sample(**kwargs))


def test_masked_samples_respect_the_mask() -> None:
    space = palaestra.spaces.Discrete(5, start=10, seed=0)
    mask = _m(0, 1, 0, 1, 0)
    assert {int(space.sample(mask=mask)) for _ in range(50)} == {11, 13}
    md = palaestra.spaces.MultiDiscrete([3, 3], seed=0)
    for _ in range(20):
        first, second = md.sample(mask=(_m(0, 0, 1), _m(1, 0, 0)))
        assert (first, second) == (2, 0)
    mb = palaestra.spaces.MultiBinary(3, seed=0)
    assert all(mb.sample(mask=_m(1, 0, 1)).tolist() == [1, 0, 1] for _ in range(5))


# (recipe, sample kwargs, exception, message substring shared with gymnasium)
BAD: list[tuple[Any, dict[str, Any], type[Exception], str]] = [
    (lambda S: S.Discrete(3), {"mask": [1, 0, 1]}, InvalidMask, "type of the sample mask"),
    (
        lambda S: S.Discrete(3),
        {"mask": np.array([1, 0, 1])},
        InvalidMask,
        "dtype of the sample mask",
    ),
    (lambda S: S.Discrete(3), {"mask": _m(1, 0)}, InvalidMask, "shape of the sample mask is (3,)"),
    (lambda S: S.Discrete(3), {"mask": _m(1, 0, 2)}, InvalidMask, "should be 0 or 1"),
    (
        lambda S: S.Discrete(3),
        {"probability": _p(0.5, 0.5, 0.5)},
        InvalidProbabilityMask,
        "sum of the sample probability",
    ),
    (
        lambda S: S.Discrete(3),
        {"probability": _p(0, 0, 0)},
        InvalidProbabilityMask,
        "sum of the sample probability",
    ),
    (
        lambda S: S.Discrete(3),
        {"probability": _p(-0.5, 1.5, 0)},
        InvalidProbabilityMask,
        "between 0 and 1",
    ),
    (
        lambda S: S.Discrete(3),
        {"probability": np.ones(3, np.float32) / 3},
        InvalidProbabilityMask,
        "dtype of the sample probability",
    ),
    (
        lambda S: S.Discrete(3),
        {"probability": _p(1, 0)},
        InvalidProbabilityMask,
        "shape of the sample probability",
    ),
    (
        lambda S: S.Discrete(3),
        {"mask": _m(1, 1, 1), "probability": _p(1, 0, 0)},
        ValueError,
        "Only one of `mask` or `probability`",
    ),
    (lambda S: S.MultiDiscrete([2, 2]), {"mask": _m(1, 1)}, InvalidMask, "to be a tuple"),
    (
        lambda S: S.MultiDiscrete([2, 2]),
        {"mask": (_m(1, 1),)},
        InvalidMask,
        "mask length to be equal",
    ),
    (
        lambda S: S.MultiDiscrete([2, 2]),
        {"mask": (_m(1, 1), _m(1, 1, 1))},
        InvalidMask,
        "mask length to be equal",
    ),
    (lambda S: S.MultiDiscrete([2, 2]), {"mask": (_m(1, 1), _m(1, 3))}, InvalidMask, "0 or 1"),
    (lambda S: S.MultiDiscrete([2, 2]), {"mask": (_m(1, 1), np.ones(2))}, InvalidMask, "np.int8"),
    (
        lambda S: S.MultiDiscrete([2]),
        {"probability": (_p(0.3, 0.3),)},
        InvalidProbabilityMask,
        "sum of all mask values to be 1",
    ),
    (
        lambda S: S.MultiDiscrete([2]),
        {"probability": (_p(1.5, -0.5),)},
        InvalidProbabilityMask,
        "between 0 and 1",
    ),
    (lambda S: S.MultiBinary(2), {"mask": _m(1, 3)}, InvalidMask, "0, 1 or 2"),
    (lambda S: S.MultiBinary(2), {"mask": _m(1, 1, 1)}, InvalidMask, "shape of the mask"),
    (
        lambda S: S.MultiBinary(2),
        {"probability": _p(0.5, 2)},
        InvalidProbabilityMask,
        "between 0 and 1",
    ),
    (lambda S: S.Text(3, charset="ab"), {"mask": _m(1, 1)}, InvalidMask, "to be a tuple"),
    (
        lambda S: S.Text(3, charset="ab"),
        {"mask": (9, None)},
        InvalidMask,
        "length be between 1 and 3",
    ),
    (
        lambda S: S.Text(3, charset="ab"),
        {"mask": (None, _m(1, 1, 1))},
        InvalidMask,
        "expects the Text sample `mask` to be (2,)",
    ),
    (
        lambda S: S.Text(3, charset="ab"),
        {"mask": (None, _m(0, 0))},
        ValueError,
        "character mask is all zero",
    ),
    (
        lambda S: S.Text(3, charset="ab"),
        {"probability": (None, _p(0.2, 0.2))},
        InvalidProbabilityMask,
        "sum of the probability mask to be 1",
    ),
    (lambda S: S.Tuple((S.Discrete(2),)), {"mask": [None]}, InvalidMask, "`mask` to be tuple"),
    (
        lambda S: S.Tuple((S.Discrete(2),)),
        {"mask": (None, None)},
        InvalidMask,
        "length of `mask` to be 1",
    ),
    (lambda S: S.Dict(a=S.Discrete(2)), {"mask": (None,)}, InvalidMask, "to be a dict"),
    (
        lambda S: S.Dict(a=S.Discrete(2)),
        {"probability": {"b": None}},
        InvalidProbabilityMask,
        "keys to be same as space keys",
    ),
    (
        lambda S: S.OneOf((S.Discrete(2),)),
        {"mask": (None, None)},
        InvalidMask,
        "length of `mask` is 1",
    ),
    (
        lambda S: S.Sequence(S.Discrete(2)),
        {"mask": (-1, None)},
        InvalidMask,
        "greater than or equal to zero",
    ),
    (
        lambda S: S.Sequence(S.Discrete(2)),
        {"mask": (np.array([[1]]), None)},
        InvalidMask,
        "1-dimensional",
    ),
    (
        lambda S: S.Sequence(S.Discrete(2)),
        {"mask": (np.array([1.0]), None)},
        InvalidMask,
        "dtype of np.integer",
    ),
    (
        lambda S: S.Sequence(S.Discrete(2)),
        {"mask": (1.5, None)},
        TypeError,
        "integer or a np.ndarray",
    ),
    (lambda S: S.Graph(S.Discrete(2), None), {"num_nodes": 0}, InvalidMask, "number of nodes"),
    (lambda S: S.Box(0, 1), {"mask": _m(1)}, error.Error, "cannot be provided a mask"),
    (
        lambda S: S.Box(0, 1),
        {"probability": _p(1)},
        error.Error,
        "cannot be provided a probability mask",
    ),
]


@pytest.mark.parametrize(("recipe", "kwargs", "exc", "match"), BAD)
def test_bad_masks_raise_like_gymnasium(
    recipe: Any, kwargs: dict[str, Any], exc: type, match: str
) -> None:
    ours, theirs = recipe(palaestra.spaces), recipe(gymnasium.spaces)
    # gymnasium's checks are `assert`s; ours subclass AssertionError, so both catch the same.
    theirs_exc = AssertionError if issubclass(exc, AssertionError) else Exception
    with pytest.raises(theirs_exc, match=re.escape(match)):
        theirs.sample(**kwargs)
    with pytest.raises(exc, match=re.escape(match)):
        ours.sample(**kwargs)


def test_mask_errors_are_palaestra_errors() -> None:
    with pytest.raises(error.Error):
        palaestra.spaces.Discrete(2).sample(mask=_m(1))
    with pytest.raises(error.InvalidProbability):
        palaestra.spaces.Discrete(2).sample(probability=_p(0.1, 0.1))
