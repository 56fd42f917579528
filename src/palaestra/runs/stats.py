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

``confidence_interval`` (the Student-t interval, without scipy) stays for
``examples/reward_shaping.py``; ``compare`` does not use it.
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
    "RESAMPLES",
    "STATISTIC",
    "Estimate",
    "confidence_interval",
    "iqm",
    "iqm_interval",
    "t_cdf",
    "t_quantile",
]

STATISTIC = "interquartile mean (25% trimmed mean; the plain mean below 4 seeds)"
INTERVAL_METHOD = "percentile bootstrap over seeds (scipy.stats.bootstrap)"
CONFIDENCE_LEVEL = 0.95
RESAMPLES = 9999  # scipy's default; rliable's 50,000 changes the 2nd decimal at most
BOOTSTRAP_SEED = 0  # a fixed generator: the same per-seed values give the same interval


class Estimate(NamedTuple):
    """A statistic over seeds and its confidence interval (None, None below 2 seeds)."""

    value: float
    low: float | None
    high: float | None


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


# The Student-t interval, without scipy (for examples/reward_shaping.py; compare uses the IQM).
# The t quantile inverts the t CDF by bisection; the CDF is the regularized incomplete beta
# function, evaluated with its continued fraction (modified Lentz method, as in Numerical
# Recipes §6.4).


def _betacf(a: float, b: float, x: float) -> float:
    tiny = 1e-300
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 500):
        m2 = 2 * m
        # Each iteration applies the even and the odd term of the continued fraction.
        for coef in (
            m * (b - m) * x / ((qam + m2) * (a + m2)),
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
        ):
            d = 1.0 + coef * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + coef / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < 1e-15:
            break
    return h


def _betainc(a: float, b: float, x: float) -> float:
    """Regularized incomplete beta ``I_x(a, b)``."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    log_front = (
        math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    )
    front = math.exp(log_front)
    # The continued fraction converges fast only on this side of the mean; use the symmetry
    # I_x(a, b) = 1 - I_{1-x}(b, a) on the other.
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _betacf(a, b, x) / a
    return 1.0 - front * _betacf(b, a, 1.0 - x) / b


def t_cdf(t: float, df: float) -> float:
    """P(T <= t) for Student's t with ``df`` degrees of freedom.

    >>> round(t_cdf(0.0, 3), 6), round(t_cdf(12.7062, 1), 4)
    (0.5, 0.975)
    """
    if df <= 0:
        raise ValueError(f"degrees of freedom must be positive, got {df}")
    tail = 0.5 * _betainc(df / 2.0, 0.5, df / (df + t * t))
    return 1.0 - tail if t >= 0 else tail


def t_quantile(p: float, df: float) -> float:
    """The ``p`` quantile of Student's t (``t_quantile(0.975, 4)`` is 2.776...).

    >>> round(t_quantile(0.975, 1), 3), round(t_quantile(0.975, 9), 3)
    (12.706, 2.262)
    """
    if not 0.0 < p < 1.0:
        raise ValueError(f"p must be in (0, 1), got {p}")
    if p < 0.5:
        return -t_quantile(1.0 - p, df)
    lo, hi = 0.0, 1.0
    while t_cdf(hi, df) < p:
        lo, hi = hi, hi * 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if t_cdf(mid, df) < p:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-12 * max(1.0, hi):
            break
    return 0.5 * (lo + hi)


def confidence_interval(values: Sequence[float], level: float = 0.95) -> tuple[float, float, float]:
    """``(mean, low, high)``: the t-interval of the mean; low = high = nan below 2 values.

    >>> [round(v, 3) for v in confidence_interval([1.0, 2.0, 3.0, 4.0])]
    [2.5, 0.446, 4.554]
    """
    n = len(values)
    if n == 0:
        return float("nan"), float("nan"), float("nan")
    mean = math.fsum(values) / n
    if n < 2:
        return mean, float("nan"), float("nan")
    var = math.fsum((v - mean) ** 2 for v in values) / (n - 1)
    half = t_quantile(0.5 + level / 2.0, n - 1) * math.sqrt(var / n)
    return mean, mean - half, mean + half
