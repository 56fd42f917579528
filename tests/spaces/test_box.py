"""Box construction rules, errors, contains and sampling edge cases."""

from __future__ import annotations

import re
import warnings
from typing import Any

import gymnasium.spaces
import numpy as np
import pytest

from palaestra.spaces import Box

BAD_BOXES: list[tuple[dict[str, Any], type[Exception], str]] = [
    ({"low": 0, "high": 1, "dtype": None}, ValueError, "dtype must be explicitly provided"),
    ({"low": 0, "high": 1, "dtype": np.complex64}, ValueError, "Invalid Box dtype (complex64)"),
    ({"low": 0, "high": 1, "dtype": str}, ValueError, "must be an integer, floating, or bool"),
    ({"low": 0, "high": 1, "shape": 3}, TypeError, "shape to be an iterable"),
    ({"low": 0, "high": 1, "shape": (2.0,)}, TypeError, "shape elements to be integer"),
    ({"low": np.zeros(2), "high": np.ones(3)}, ValueError, "low.shape and high.shape don't match"),
    (
        {"low": np.zeros(2), "high": 1, "shape": (3,)},
        ValueError,
        "low.shape doesn't match provided shape",
    ),
    (
        {"low": 0, "high": np.ones(2), "shape": (3,)},
        ValueError,
        "high.shape doesn't match provided shape",
    ),
    ({"low": "0", "high": 1}, ValueError, "shape is not specified"),
    (
        {"low": [0, 0], "high": [1, 1], "shape": (2,)},
        ValueError,
        "low must be a np.ndarray, integer, or float",
    ),
    ({"low": np.nan, "high": 1}, ValueError, "No low value can be equal to `np.nan`"),
    ({"low": 0, "high": np.nan}, ValueError, "No high value can be equal to `np.nan`"),
    (
        {"low": np.array([0.0, np.nan]), "high": np.ones(2)},
        ValueError,
        "No low value can be equal to `np.nan`, low=[ 0. nan]",
    ),
    (
        {"low": np.zeros(2), "high": np.array([np.nan, 1])},
        ValueError,
        "No high value can be equal to `np.nan`",
    ),
    ({"low": 1, "high": 0}, ValueError, "low values must be less than or equal to high"),
    ({"low": np.array([0, 2]), "high": np.array([1, 1])}, ValueError, "less than or equal to high"),
    (
        {"low": -np.inf, "high": 1, "dtype": np.uint8},
        ValueError,
        "unsigned int dtype don't support `-np.inf`",
    ),
    (
        {"low": 0, "high": np.inf, "dtype": np.uint8},
        ValueError,
        "unsigned int dtype don't support `np.inf`",
    ),
    (
        {"low": 0, "high": np.array([np.inf]), "dtype": np.bool_},
        ValueError,
        "don't support `np.inf`",
    ),
    (
        {"low": -1, "high": 1, "dtype": np.uint8},
        ValueError,
        "low is out of bounds of the dtype range",
    ),
    (
        {"low": 0, "high": 256, "dtype": np.uint8},
        ValueError,
        "high is out of bounds of the dtype range",
    ),
    (
        {"low": np.array([-1.0]), "high": np.array([1.0]), "dtype": np.uint8},
        ValueError,
        "low is out of bounds",
    ),
    (
        {"low": np.array([0.0]), "high": np.array([300.0]), "dtype": np.uint8},
        ValueError,
        "high is out of bounds",
    ),
    (
        {"low": np.array(["a"]), "high": np.array([1.0])},
        ValueError,
        "low must be a floating, integer, or bool dtype",
    ),
]


@pytest.mark.parametrize(("kwargs", "exc", "match"), BAD_BOXES)
def test_invalid_boxes_raise_like_gymnasium(kwargs: dict[str, Any], exc: type, match: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(exc, match=re.escape(match)):
            gymnasium.spaces.Box(**kwargs)
        with pytest.raises(exc, match=re.escape(match)):
            Box(**kwargs)


def test_negative_shape_is_rejected_clearly() -> None:
    with pytest.raises(ValueError, match=re.escape("must be non-negative, shape=(2, -1)")):
        Box(0, 1, shape=(2, -1))


def test_inputs_are_not_modified_or_aliased() -> None:
    # gymnasium writes the int dtype limit into the caller's array; we must not.
    low = np.array([-np.inf, 0.0])
    high = np.array([5.0, np.inf])
    box = Box(low, high, dtype=np.int32)
    assert np.isinf(low[0]) and np.isinf(high[1])
    assert box.low.tolist() == [np.iinfo(np.int32).min, 0]
    assert box.high.tolist() == [5, np.iinfo(np.int32).max]
    assert box.bounded_below.tolist() == [False, True]
    assert box.bounded_above.tolist() == [True, False]
    low2 = np.zeros(3, dtype=np.float32)
    box2 = Box(low2, 1.0)
    low2[0] = -5
    assert box2.low[0] == 0


def test_int64_unbounded_gets_exact_limits() -> None:
    box = Box(-np.inf, np.array([np.inf, np.inf]), dtype=np.int64)
    info = np.iinfo(np.int64)
    assert box.low.tolist() == [info.min, info.min]
    assert box.high.tolist() == [info.max, info.max]
    assert box.sample() in box


def test_precision_warning_like_gymnasium() -> None:
    with pytest.warns(UserWarning, match="precision lowered by casting to float32"):
        Box(np.zeros(2), np.ones(2), dtype=np.float32)


def test_shape_inference_and_scalar_shape() -> None:
    assert Box(0, 1).shape == (1,)
    assert Box(np.zeros((2, 3), np.float32), 1.0).shape == (2, 3)
    assert Box(0.0, np.ones(4, np.float32)).shape == (4,)
    assert Box(0, 1, shape=[np.int64(2)]).shape == (2,)
    assert Box(0, 1, shape=()).sample().shape == ()


def test_is_bounded() -> None:
    box = Box(np.array([0.0, -np.inf]), np.array([1.0, 1.0]), dtype=np.float64)
    assert box.is_bounded("above") and not box.is_bounded("below")
    assert not box.is_bounded() and Box(0, 1).is_bounded()
    with pytest.raises(ValueError, match="manner is not in"):
        box.is_bounded("sideways")  # type: ignore[arg-type]


CONTAINS: list[Any] = [
    np.array([0.5, 0.5], np.float32),
    np.array([0.5, 0.5], np.float64),  # float64 does not cast safely to float32
    np.array([0, 1], np.int8),
    np.array([0, 1], np.int64),
    np.array([1.5, 0.0], np.float32),
    np.array([np.nan, 0.0], np.float32),
    np.array([0.5], np.float32),
    np.array([[0.5, 0.5]], np.float32),
    [0.5, 0.5],
    (0.0, 1.0),
    [0.5, "a"],
    0.5,
    None,
]


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.int32, np.uint8])
def test_contains_matches_gymnasium(dtype: Any) -> None:
    ours, theirs = Box(0, 1, (2,), dtype), gymnasium.spaces.Box(0, 1, (2,), dtype)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for x in CONTAINS:
            assert ours.contains(x) == theirs.contains(x), x
            assert (x in ours) == ours.contains(x)


def test_contains_warns_when_casting_like_gymnasium() -> None:
    with pytest.warns(UserWarning, match="Casting input x to numpy array"):
        assert [0.5] in Box(0, 1)


@pytest.mark.parametrize("dtype", [np.int8, np.uint8, np.int16, np.int32, np.int64, np.bool_])
def test_integer_box_samples_cover_both_ends(dtype: Any) -> None:
    box = Box(0, 1, (200,), dtype, seed=0)
    sample = box.sample()
    assert sample.dtype == np.dtype(dtype)
    assert sample.min() == 0 and sample.max() == 1
    assert sample in box


def test_sample_returns_fresh_arrays() -> None:
    box = Box(0, 1, (3,), seed=0)
    a = box.sample()
    b = box.sample()
    assert a is not b and not np.shares_memory(a, b)
    a[:] = 5
    assert box.low.max() == 0 and box.high.min() == 1


def test_legacy_pickle_state_is_accepted() -> None:
    box = Box(0, 1, (2,))
    state = dict(box.__dict__)
    state["shape"] = state.pop("_shape")
    state["np_random"] = state.pop("_np_random")
    state.pop("low_repr")
    state.pop("high_repr")
    state.pop("_all_bounded")  # derived caches, absent from old pickles
    state.pop("_interval_kinds")
    restored = Box.__new__(Box)
    restored.__setstate__(state)
    assert restored == box and repr(restored) == "Box(0.0, 1.0, (2,), float32)"
    assert restored.sample() in restored
