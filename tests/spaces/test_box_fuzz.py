"""Randomised Box configurations: repr, bounds, draws and contains all equal gymnasium's."""

from __future__ import annotations

import warnings
from typing import Any

import gymnasium.spaces
import numpy as np
import pytest

from palaestra.spaces import Box

DTYPES = [np.float16, np.float32, np.float64, np.int8, np.int16, np.int32, np.int64, np.uint8]


def _random_box_args(rng: np.random.Generator) -> dict[str, Any]:
    dtype = np.dtype(DTYPES[rng.integers(len(DTYPES))])
    shape = tuple(int(d) for d in rng.integers(1, 4, size=rng.integers(0, 3)))
    if dtype.kind == "f":
        low = rng.normal(size=shape) * 10
        high = low + rng.exponential(size=shape) * 5
        low = np.where(rng.random(shape) < 0.3, -np.inf, low)
        high = np.where(rng.random(shape) < 0.3, np.inf, high)
    else:
        info = np.iinfo(dtype)
        low = rng.integers(max(info.min, -50), 50, size=shape)
        high = low + rng.integers(0, 20, size=shape)
        high = np.minimum(high, info.max)
        if dtype.kind == "i" and rng.random() < 0.5:
            low = np.where(rng.random(shape) < 0.4, -np.inf, low)
    if rng.random() < 0.3 and shape:  # scalar bounds broadcast to the shape
        return {
            "low": float(np.min(low)),
            "high": float(np.max(high)),
            "shape": shape,
            "dtype": dtype,
        }
    return {"low": np.asarray(low), "high": np.asarray(high), "dtype": dtype}


@pytest.mark.parametrize("case", range(60))
def test_random_boxes_match_gymnasium(case: int) -> None:
    args = _random_box_args(np.random.default_rng(case))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        theirs = gymnasium.spaces.Box(
            **{k: v.copy() if isinstance(v, np.ndarray) else v for k, v in args.items()}, seed=case
        )
        ours = Box(**args, seed=case)
        assert repr(ours) == repr(theirs)
        np.testing.assert_array_equal(ours.low, theirs.low)
        np.testing.assert_array_equal(ours.high, theirs.high)
        np.testing.assert_array_equal(ours.bounded_below, theirs.bounded_below)
        np.testing.assert_array_equal(ours.bounded_above, theirs.bounded_above)
        for _ in range(3):
            sample, twin = ours.sample(), theirs.sample()
            assert sample.dtype == twin.dtype
            np.testing.assert_array_equal(sample, twin)
            assert sample in ours and ours.contains(twin) == theirs.contains(twin)
            shifted = sample.astype(np.float64) + 1e6
            assert ours.contains(shifted) == theirs.contains(shifted)
