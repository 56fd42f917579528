"""Statistics over seeds fit for few seeds: the interquartile mean and its bootstrap interval.

Agarwal et al. (NeurIPS 2021, "Deep RL at the Edge of the Statistical Precipice") recommend,
for the handful of seeds deep-RL experiments afford, the interquartile mean (IQM: the mean of
the middle 50% of runs, robust to one outlier seed yet using more runs than the median) with a
stratified percentile-bootstrap confidence interval. Their library rliable computes the IQM as
``scipy.stats.trim_mean(scores, 0.25)`` over all runs and resamples runs within each task; a
``compare`` variant is one task (one env), so the stratified bootstrap is the plain bootstrap
over its seeds, which ``scipy.stats.bootstrap`` computes (percentile method, as rliable).

Why percentile and not a t-interval or BCa: every resample's IQM is a mean of returns that
occurred, so it lies in ``[min, max]`` of the per-seed values, and so do percentiles of those
IQMs: the interval never contains an impossible return (a t-interval over two CartPole seeds
reached -1,500 for returns in [0, 500]). BCa needs a jackknife that two seeds cannot give and
returns NaN on degenerate data. The bootstrap is seeded, so the same runs give the same
interval.

The paper's performance profile (rliable's ``create_performance_profile`` with score
distributions) is, at each threshold tau, the fraction of runs whose score is above tau, with a
percentile-bootstrap band over runs at each tau. For one task, a bootstrap resample's count
above tau is Binomial(n, k / n) (n runs, k of them above tau), so the band is computed exactly
from binomial quantiles (``scipy.stats.binom``) rather than by resampling (rliable draws 2,000
resamples): it is the limit of the resampled band, the same every time, inside [0, 1], and it
contains the fraction itself (a binomial whose mean n * (k / n) = k is an integer has median k).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from palaestra.error import dependency_not_installed

__all__ = [
    "CONFIDENCE_LEVEL",
    "INTERVAL_METHOD",
    "PROFILE_INTERVAL_METHOD",
    "PROFILE_STATISTIC",
    "RESAMPLES",
    "STATISTIC",
    "Estimate",
    "Profile",
    "iqm",
    "iqm_interval",
    "method_note",
    "performance_profile",
    "profile_thresholds",
    "score_distribution",
]

STATISTIC = "interquartile mean (25% trimmed mean; the plain mean below 4 seeds)"
INTERVAL_METHOD = "percentile bootstrap over seeds (scipy.stats.bootstrap)"
CONFIDENCE_LEVEL = 0.95
RESAMPLES = 9999  # scipy's default; rliable's 50,000 changes the 2nd decimal at most
BOOTSTRAP_SEED = 0  # a fixed generator: the same per-seed values give the same interval
PROFILE_STATISTIC = "fraction of runs (seeds) whose final return is above the threshold"
PROFILE_INTERVAL_METHOD = (
    "percentile bootstrap over runs at each threshold, exact (a resample's count above it is "
    "binomial: scipy.stats.binom quantiles)"
)


class Estimate(NamedTuple):
    """A statistic over seeds and its confidence interval (None, None below 2 seeds)."""

    value: float
    low: float | None
    high: float | None


def method_note() -> str:
    """What a table's IQM and CI are, in the words ``compare``'s table and the examples print.

    >>> method_note()[:44]
    'IQM: interquartile mean (25% trimmed mean; t'
    """
    return (
        f"IQM: {STATISTIC}, over seeds; CI: {INTERVAL_METHOD}, {RESAMPLES:,} resamples, "
        "none with one seed"
    )


def _scipy_stats() -> Any:
    try:
        from scipy import stats
    except ImportError:
        raise dependency_not_installed(
            "scipy", "render", "compare's statistics (interquartile mean, bootstrap interval)"
        ) from None
    return stats


def _values(values: Sequence[float] | np.ndarray) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 1 or not len(array):
        raise ValueError(f"expected a non-empty list of per-seed values, got {values!r}")
    if not np.isfinite(array).all():
        raise ValueError(f"per-seed values must be finite numbers, got {values!r}")
    return array


def iqm(values: Sequence[float] | np.ndarray) -> float:
    """Interquartile mean: the mean of the values left after cutting ``floor(n / 4)`` from
    each end (``scipy.stats.trim_mean(x, 0.25)``, rliable's ``aggregate_iqm``); below 4 values
    nothing is cut. Rounding cannot take it outside the values' range.

    >>> iqm([1.0, 2.0, 3.0, 100.0]), iqm([10.0, 20.0])
    (2.5, 15.0)
    """
    array = _values(values)
    value = float(_scipy_stats().trim_mean(array, 0.25))
    # The exact trimmed mean lies in [min, max]; a float sum can step one ulp past it
    # (0.1 + 0.1 + 0.1 > 0.3), which would put it outside the seeds' range.
    return float(np.clip(value, array.min(), array.max()))


def iqm_interval(
    values: Sequence[float] | np.ndarray,
    level: float = CONFIDENCE_LEVEL,
    resamples: int = RESAMPLES,
    seed: int = BOOTSTRAP_SEED,
) -> Estimate:
    """The IQM of per-seed ``values`` and its percentile-bootstrap confidence interval at
    ``level``; one value has no interval (``low``, ``high`` None), identical values have
    ``[v, v]``. The interval lies inside ``[min(values), max(values)]``.

    >>> iqm_interval([20.0, 40.0])
    Estimate(value=30.0, low=20.0, high=40.0)
    >>> iqm_interval([7.0, 7.0, 7.0])
    Estimate(value=7.0, low=7.0, high=7.0)
    >>> iqm_interval([5.0])
    Estimate(value=5.0, low=None, high=None)
    """
    if not 0.0 < level < 1.0:
        raise ValueError(f"confidence level must be in (0, 1), got {level!r}")
    array = _values(values)
    value = iqm(array)
    if len(array) < 2:
        return Estimate(value, None, None)
    lo, hi = float(array.min()), float(array.max())
    if lo == hi:  # every resample is [v, ..., v]: scipy would compute the same, or NaN (BCa)
        return Estimate(value, lo, hi)
    stats = _scipy_stats()
    result = stats.bootstrap(
        (array,),
        lambda x, axis: stats.trim_mean(x, 0.25, axis=axis),
        vectorized=True,
        n_resamples=resamples,
        confidence_level=level,
        method="percentile",
        rng=np.random.default_rng(seed),
    )
    low, high = result.confidence_interval
    if not (math.isfinite(low) and math.isfinite(high)):  # not expected from the percentile method
        raise ValueError(f"the bootstrap of {values!r} gave no interval ({low}, {high})")
    # Percentiles of resampled IQMs lie in [min, max]; the clip only undoes float rounding.
    return Estimate(value, float(np.clip(low, lo, hi)), float(np.clip(high, lo, hi)))


class Profile(NamedTuple):
    """A performance profile: at each threshold the fraction of runs above it, and its
    confidence band (``low``, ``high`` None below 2 runs)."""

    thresholds: np.ndarray  # [T]
    fraction: np.ndarray  # [T] in [0, 1]
    low: np.ndarray | None  # [T]
    high: np.ndarray | None  # [T]
    seeds: int


def _thresholds(thresholds: Sequence[float] | np.ndarray) -> np.ndarray:
    array = np.asarray(thresholds, dtype=np.float64)
    if array.ndim != 1 or not len(array) or not np.isfinite(array).all():
        raise ValueError(f"expected a non-empty list of finite thresholds, got {thresholds!r}")
    return array


def score_distribution(
    values: Sequence[float] | np.ndarray, thresholds: Sequence[float] | np.ndarray
) -> np.ndarray:
    """At each threshold tau, the fraction of ``values`` strictly above tau (rliable's
    ``run_score_deviation``).

    >>> score_distribution([1.0, 2.0, 3.0, 4.0], [0.0, 2.0, 2.5, 4.0]).tolist()
    [1.0, 0.5, 0.5, 0.0]
    """
    array, taus = _values(values), _thresholds(thresholds)
    return (array[:, None] > taus[None, :]).mean(axis=0)


def profile_thresholds(values: Sequence[float] | np.ndarray) -> np.ndarray:
    """Thresholds at which a profile of ``values`` is exact: every distinct value (where the
    fraction steps down) and one point 5% of their range below the lowest (every run above it)
    and above the highest (none), so a step plot shows the whole profile.

    >>> profile_thresholds([40.0, 20.0, 20.0]).tolist()
    [19.0, 20.0, 40.0, 41.0]
    """
    array = _values(values)
    lo, hi = float(array.min()), float(array.max())
    margin = 0.05 * ((hi - lo) or max(abs(lo), 1.0))
    return np.concatenate([[lo - margin], np.unique(array), [hi + margin]])


def performance_profile(
    values: Sequence[float] | np.ndarray,
    thresholds: Sequence[float] | np.ndarray,
    level: float = CONFIDENCE_LEVEL,
) -> Profile:
    """The score distribution of per-seed ``values`` at ``thresholds`` with its ``level``
    percentile-bootstrap band over runs, exact (see the module docstring); one value has no
    band. The band lies in [0, 1] and contains the fraction.

    >>> profile = performance_profile([1.0, 2.0, 3.0, 4.0, 5.0], [1.0, 4.0])
    >>> profile.fraction.tolist(), profile.low.tolist(), profile.high.tolist()
    ([0.8, 0.2], [0.4, 0.0], [1.0, 0.6])
    """
    if not 0.0 < level < 1.0:
        raise ValueError(f"confidence level must be in (0, 1), got {level!r}")
    array, taus = _values(values), _thresholds(thresholds)
    fraction = score_distribution(array, taus)
    n = len(array)
    if n < 2:
        return Profile(taus, fraction, None, None, n)
    binom = _scipy_stats().binom
    tail = (1.0 - level) / 2.0
    # With k of n runs above tau (fraction k / n), a resample's count above it is
    # Binomial(n, k / n); ppf is the percentile bootstrap's quantile of it.
    low = binom.ppf(tail, n, fraction) / n
    high = binom.ppf(1.0 - tail, n, fraction) / n
    return Profile(taus, fraction, low, high, n)
