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
