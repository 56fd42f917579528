"""The interquartile mean and its percentile-bootstrap interval (``palaestra.runs.stats``)
against hand computations and an exhaustive bootstrap."""

from __future__ import annotations

import itertools
import sys

import numpy as np
import pytest

from palaestra.error import DependencyNotInstalled
from palaestra.runs.stats import (
    Estimate,
    iqm,
    iqm_interval,
    performance_profile,
    profile_thresholds,
    score_distribution,
)


def _iqm_by_hand(values: list[float]) -> float:
    """Sort, cut floor(n/4) from each end, average the rest (rliable's definition)."""
    cut = len(values) // 4
    kept = sorted(values)[cut : len(values) - cut]
    return sum(kept) / len(kept)


@pytest.mark.parametrize(
    ("values", "expected"),
    [
        ([10.0, 20.0], 15.0),  # below 4 values nothing is cut: the mean
        ([0.0, 3.0, 9.0], 4.0),
        ([1.0, 2.0, 3.0, 100.0], 2.5),  # 1 cut from each end: (2 + 3) / 2
        ([1000.0, 4.0, 2.0, 3.0, 1.0], 3.0),  # 1 cut from each end of 5: (2 + 3 + 4) / 3
        ([8.0, 1.0, 7.0, 2.0, 6.0, 3.0, 5.0, 4.0], 4.5),  # 2 cut from each end: 3, 4, 5, 6
        ([-500.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0, 16.0, 17.0, 900.0], 13.5),  # cut 2, 2
    ],
)
def test_iqm_of_known_arrays(values: list[float], expected: float) -> None:
    assert iqm(values) == pytest.approx(expected, abs=1e-12)
    assert _iqm_by_hand(values) == pytest.approx(expected, abs=1e-12)


def test_two_or_three_seeds_give_the_whole_range() -> None:
    """With n <= 3 seeds a resample of all-minimum values has probability 1/n^n >= 1/27 > 2.5%,
    so the 95% percentile interval is exactly [min, max]: few seeds, wide honest interval."""
    assert iqm_interval([20.0, 40.0]) == Estimate(30.0, 20.0, 40.0)
    assert iqm_interval([0.0, 3.0, 6.0]) == Estimate(3.0, 0.0, 6.0)
    assert iqm_interval([500.0, 9.0]) == Estimate(254.5, 9.0, 500.0)


def test_interval_matches_the_exhaustive_bootstrap() -> None:
    """Five seeds: all 5^5 equally likely resamples enumerated give the exact bootstrap
    distribution of the IQM; scipy's 9,999 seeded resamples land near its 2.5% and 97.5%
    quantiles (between the 1.5% and 3.5%, and the 96.5% and 98.5% quantiles)."""
    values = [10.0, 20.0, 30.0, 40.0, 500.0]
    exact = np.sort([_iqm_by_hand(list(r)) for r in itertools.product(values, repeat=5)])
    estimate = iqm_interval(values)
    assert estimate.value == 30.0  # (20 + 30 + 40) / 3
    assert estimate.low is not None and estimate.high is not None
    q = np.quantile(exact, [0.015, 0.035, 0.965, 0.985])
    assert q[0] <= estimate.low <= q[1]
    assert q[2] <= estimate.high <= q[3]
    assert 10.0 <= estimate.low < estimate.value < estimate.high <= 500.0
    assert iqm_interval(values) == estimate  # seeded: the same runs give the same interval


def test_interval_stays_inside_the_seeds_range() -> None:
    rng = np.random.default_rng(3)
    for n in (2, 3, 4, 5, 7, 10):
        values = rng.uniform(0.0, 500.0, n).round(1)
        estimate = iqm_interval(values)
        assert estimate.low is not None and estimate.high is not None
        assert values.min() <= estimate.low <= estimate.high <= values.max(), (values, estimate)
        assert values.min() <= estimate.value <= values.max()


def test_identical_values_give_a_point_interval_never_nan() -> None:
    assert iqm_interval([7.0, 7.0, 7.0]) == Estimate(7.0, 7.0, 7.0)
    # 0.1 * 5 summed in floats is 0.5000000000000001: the IQM and its interval are still 0.1
    assert iqm_interval([0.1] * 5) == Estimate(0.1, 0.1, 0.1)
    assert iqm([0.1] * 3) == 0.1
    # nearly degenerate: one different seed out of five, the interval stays in range
    low_high = iqm_interval([0.1, 0.1, 0.1, 0.1, 0.2])
    assert low_high.low is not None and low_high.high is not None
    assert 0.1 <= low_high.low <= low_high.high <= 0.2


def test_one_seed_has_no_interval() -> None:
    assert iqm_interval([5.0]) == Estimate(5.0, None, None)


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ([], r"expected a non-empty list of per-seed values, got \[\]"),
        ([[1.0, 2.0]], r"expected a non-empty list of per-seed values, got \[\[1.0, 2.0\]\]"),
        ([1.0, float("nan")], r"per-seed values must be finite numbers, got \[1.0, nan\]"),
        ([1.0, float("inf")], r"per-seed values must be finite numbers, got \[1.0, inf\]"),
    ],
)
def test_bad_values_are_named(values: list[float], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        iqm_interval(values)


def test_bad_level_is_named() -> None:
    with pytest.raises(ValueError, match=r"confidence level must be in \(0, 1\), got 95"):
        iqm_interval([1.0, 2.0], level=95)


def test_missing_scipy_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "scipy", None)  # import scipy now raises ImportError
    with pytest.raises(DependencyNotInstalled, match=r'pip install "palaestra\[render\]"'):
        iqm_interval([1.0, 2.0])


# Performance profiles: hand-computed binomial quantiles. With n runs and k above tau, a
# bootstrap resample's count above tau is Binomial(n, k/n); for n = 5:
#   k = 4 (p = 0.8): P(X <= 1) = 0.00672, P(X <= 2) = 0.05792 -> 2.5% quantile 2 -> low 0.4;
#                    P(X <= 4) = 0.67232 < 0.975 -> 97.5% quantile 5 -> high 1.0
#   k = 3 (p = 0.6): P(X <= 0) = 0.01024, P(X <= 1) = 0.08704 -> low 0.2;
#                    P(X <= 4) = 0.92224 < 0.975 -> high 1.0
#   k = 1 (p = 0.2): P(X <= 0) = 0.32768 -> low 0.0; P(X <= 2) = 0.94208, P(X <= 3) = 0.99328
#                    -> high 0.6
#   k = 5 or 0: every resample alike -> [1, 1] or [0, 0]
def test_profile_of_known_values() -> None:
    values = [3.0, 1.0, 5.0, 2.0, 4.0]
    profile = performance_profile(values, [0.0, 1.0, 2.5, 4.0, 5.0, 6.0])
    assert profile.thresholds.tolist() == [0.0, 1.0, 2.5, 4.0, 5.0, 6.0]
    # strictly above: at tau = 1 the run scoring 1 does not count, at tau = 5 none does
    assert profile.fraction.tolist() == [1.0, 0.8, 0.6, 0.2, 0.0, 0.0]
    assert profile.low is not None and profile.high is not None
    assert profile.low.tolist() == [1.0, 0.4, 0.2, 0.0, 0.0, 0.0]
    assert profile.high.tolist() == [1.0, 1.0, 1.0, 0.6, 0.0, 0.0]
    assert profile.seeds == 5
    assert score_distribution(values, [2.0]).tolist() == [0.6]


def test_profile_of_two_seeds_and_of_one() -> None:
    """Two seeds: half above tau gives the band [0, 1] (a resample of both below, or both
    above, has probability 1/4 > 2.5%). One seed: a fraction of 0 or 1 and no band."""
    two = performance_profile([20.0, 40.0], [10.0, 20.0, 30.0, 40.0])
    assert two.fraction.tolist() == [1.0, 0.5, 0.5, 0.0]
    assert two.low is not None and two.high is not None
    assert two.low.tolist() == [1.0, 0.0, 0.0, 0.0]
    assert two.high.tolist() == [1.0, 1.0, 1.0, 0.0]
    one = performance_profile([5.0], [4.0, 5.0])
    assert one.fraction.tolist() == [1.0, 0.0] and one.low is None and one.high is None
    assert one.seeds == 1


def test_profile_band_matches_the_exhaustive_bootstrap() -> None:
    """Four runs: all 4^4 equally likely resamples enumerated give the exact bootstrap
    distribution of the fraction above each tau; its 2.5% and 97.5% quantiles (the percentile
    method: the smallest value whose CDF reaches the level) are the band, exactly."""
    values = [10.0, 20.0, 30.0, 40.0]
    taus = [5.0, 10.0, 15.0, 25.0, 35.0, 40.0]
    resamples = np.array(list(itertools.product(values, repeat=4)))  # [256, 4]
    fractions = (resamples[:, :, None] > np.array(taus)).mean(axis=1)  # [256, T]
    low = np.quantile(fractions, 0.025, axis=0, method="inverted_cdf")
    high = np.quantile(fractions, 0.975, axis=0, method="inverted_cdf")
    profile = performance_profile(values, taus)
    assert profile.low is not None and profile.high is not None
    np.testing.assert_array_equal(profile.low, low)
    np.testing.assert_array_equal(profile.high, high)
    assert profile.fraction.tolist() == [1.0, 0.75, 0.75, 0.5, 0.25, 0.0]


def test_profile_band_lies_in_0_1_and_contains_the_fraction() -> None:
    rng = np.random.default_rng(7)
    for n in (2, 3, 4, 5, 7, 10, 40):
        values = rng.uniform(0.0, 500.0, n).round(0)
        profile = performance_profile(values, profile_thresholds(values))
        assert profile.low is not None and profile.high is not None
        assert (0.0 <= profile.low).all() and (profile.high <= 1.0).all()
        assert (profile.low <= profile.fraction).all(), (values, profile)
        assert (profile.fraction <= profile.high).all(), (values, profile)
        assert (np.diff(profile.fraction) <= 0).all()  # fewer runs above a higher threshold
        # a step at every value (0.05 of the range beyond both ends): all above, then none
        assert profile.fraction[0] == 1.0 and profile.fraction[-1] == 0.0
        assert set(values) <= set(profile.thresholds.tolist())


def test_profile_thresholds() -> None:
    assert profile_thresholds([40.0, 20.0, 20.0, 30.0]).tolist() == [19.0, 20.0, 30.0, 40.0, 41.0]
    # equal values: 5% of the value's size (at least 1) either side
    assert profile_thresholds([-200.0, -200.0]).tolist() == [-210.0, -200.0, -190.0]
    assert profile_thresholds([0.0]).tolist() == [-0.05, 0.0, 0.05]


@pytest.mark.parametrize(
    ("thresholds", "message"),
    [
        ([], r"expected a non-empty list of finite thresholds, got \[\]"),
        ([1.0, float("nan")], r"expected a non-empty list of finite thresholds, got \[1.0, nan\]"),
        ([[1.0]], r"expected a non-empty list of finite thresholds, got \[\[1.0\]\]"),
    ],
)
def test_bad_thresholds_are_named(thresholds: list[float], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        performance_profile([1.0, 2.0], thresholds)


def test_profile_bad_values_and_level_are_named() -> None:
    with pytest.raises(ValueError, match=r"per-seed values must be finite numbers, got \[inf\]"):
        performance_profile([float("inf")], [1.0])
    with pytest.raises(ValueError, match=r"confidence level must be in \(0, 1\), got 1.0"):
        performance_profile([1.0, 2.0], [1.0], level=1.0)
