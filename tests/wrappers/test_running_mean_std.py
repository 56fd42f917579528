"""``RunningMeanStd`` gives Gymnasium's numbers bit for bit and the right moments."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.wrappers.utils import RunningMeanStd as GymRMS

from palaestra.wrappers.running_mean_std import RunningMeanStd


@pytest.mark.parametrize("shape", [(), (3,), (2, 4)])
def test_matches_gymnasium_bit_for_bit(shape: tuple[int, ...]) -> None:
    rng = np.random.default_rng(0)
    ours, theirs = RunningMeanStd(shape=shape), GymRMS(shape=shape)
    for size in (1, 5, 1, 32, 7):
        batch = rng.normal(3.0, 2.0, (size, *shape))
        ours.update(batch)
        theirs.update(batch)
        np.testing.assert_array_equal(ours.mean, theirs.mean)
        np.testing.assert_array_equal(ours.var, theirs.var)
        assert ours.count == theirs.count


def test_float32_dtype_is_kept() -> None:
    rms = RunningMeanStd(shape=(2,), dtype=np.float32)
    rms.update(np.ones((4, 2), dtype=np.float32))
    assert rms.mean.dtype == np.float32 and rms.var.dtype == np.float32


def test_moments_approach_the_data() -> None:
    rng = np.random.default_rng(1)
    data = rng.normal(-1.5, 0.5, (1000, 3))
    rms = RunningMeanStd(shape=(3,))
    for chunk in np.array_split(data, 17):
        rms.update(chunk)
    np.testing.assert_allclose(rms.mean, data.mean(axis=0), rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(rms.var, data.var(axis=0), rtol=1e-5, atol=1e-6)
    assert rms.count == pytest.approx(1000 + 1e-4)


@pytest.mark.parametrize(
    "sample",
    [
        np.array([0.25, -3.0, 7.5], dtype=np.float32),
        np.array([1.0, np.inf, np.nan]),
        np.array([3, -1, 2], dtype=np.int64),
        np.array([0.5, 2.0, -1.0], dtype=np.float16),
    ],
    ids=["float32", "non-finite", "int64", "float16"],
)
@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")  # inf - inf, on purpose
def test_update_one_equals_a_batch_of_one(sample: np.ndarray) -> None:
    one, batch = RunningMeanStd(shape=(3,)), RunningMeanStd(shape=(3,))
    for k in range(3):
        one.update_one(sample * (k + 1))
        batch.update((sample * (k + 1))[None])
        np.testing.assert_array_equal(one.mean, batch.mean)
        np.testing.assert_array_equal(one.var, batch.var)
        assert one.mean.dtype == batch.mean.dtype and one.count == batch.count


def test_update_one_on_scalars_keeps_numpy_scalar_types() -> None:
    one, batch = RunningMeanStd(), RunningMeanStd()
    for value in (1.5, -0.25, 4.0):
        one.update_one(np.float64(value))
        batch.update(np.array([value]))
    assert type(one.mean) is type(batch.mean) and one.mean == batch.mean
    assert type(one.var) is type(batch.var) and one.var == batch.var
