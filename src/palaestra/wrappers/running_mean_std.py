"""Running mean and variance of a stream of arrays (Chan et al.'s parallel update).

The numbers match ``gymnasium.wrappers.utils.RunningMeanStd`` exactly, including the tiny
initial ``count`` that keeps the first update from dividing by zero, so a normalizer trained on
palaestra gives the same statistics as one trained on Gymnasium.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def update_mean_var_count_from_moments(
    mean: Any, var: Any, count: Any, batch_mean: Any, batch_var: Any, batch_count: Any
) -> tuple[Any, Any, Any]:
    """Merge the moments of a batch into running moments; returns ``(mean, var, count)``.

    https://en.wikipedia.org/wiki/Algorithms_for_calculating_variance#Parallel_algorithm

    >>> [float(x) for x in update_mean_var_count_from_moments(0.0, 1.0, 1.0, 2.0, 0.0, 1)]
    [1.0, 1.5, 2.0]
    """
    delta = batch_mean - mean
    total = count + batch_count
    new_mean = mean + delta * batch_count / total
    m2 = var * count + batch_var * batch_count + np.square(delta) * count * batch_count / total
    return new_mean, m2 / total, total


class RunningMeanStd:
    """Tracks the mean, variance and count of the values passed to :meth:`update`.

    >>> rms = RunningMeanStd(shape=(2,))
    >>> rms.update(np.array([[1.0, 2.0], [3.0, 6.0]]))
    >>> rms.mean.round(2), rms.var.round(2)  # the 1e-4 pseudo-count of the prior barely shows
    (array([2., 4.]), array([1., 4.]))
    """

    RUN_STATE = ("mean", "var", "count")  # exact resume (utils.run_state)

    def __init__(
        self, epsilon: float = 1e-4, shape: tuple[int, ...] = (), dtype: Any = np.float64
    ) -> None:
        self.mean = np.zeros(shape, dtype=dtype)
        self.var = np.ones(shape, dtype=dtype)
        # epsilon is a pseudo-count for the initial (mean 0, var 1) prior, as in Gymnasium.
        self.count: Any = epsilon

    def copy(self) -> RunningMeanStd:
        """An independent copy (SB3's ``RunningMeanStd.copy``)."""
        new = RunningMeanStd(shape=self.mean.shape, dtype=self.mean.dtype)
        new.mean, new.var, new.count = self.mean.copy(), self.var.copy(), float(self.count)
        return new

    def combine(self, other: RunningMeanStd) -> None:
        """Fold in the statistics of ``other`` (SB3's ``RunningMeanStd.combine``): the result is
        what one object updated with both streams would hold."""
        self.update_from_moments(other.mean, other.var, other.count)

    def update(self, x: np.ndarray) -> None:
        """Fold in a batch of samples stacked along axis 0."""
        self.update_from_moments(np.mean(x, axis=0), np.var(x, axis=0), x.shape[0])

    def update_one(self, x: Any) -> None:
        """Fold in one sample; the same numbers as ``update(x[None])``, minus the reductions.

        >>> a, b = RunningMeanStd(shape=(2,)), RunningMeanStd(shape=(2,))
        >>> x = np.array([0.5, -2.0])
        >>> a.update(x[None]); b.update_one(x)
        >>> bool(np.array_equal(a.mean, b.mean) and np.array_equal(a.var, b.var))
        True
        """
        x = np.asarray(x)
        if x.dtype.kind != "f" or x.dtype.itemsize < 4:
            # np.mean of ints is float64 and of float16 goes through float32: let numpy decide
            self.update(x[None])
            return
        # One row's mean is the row; its variance is (x - x)**2: 0, or NaN where x is not
        # finite, exactly what np.var gives.
        diff = x - x
        self.update_from_moments(x[()] if x.ndim == 0 else x, diff * diff, 1)

    def update_from_moments(self, batch_mean: Any, batch_var: Any, batch_count: Any) -> None:
        """Fold in a batch given by its mean, variance and size."""
        self.mean, self.var, self.count = update_mean_var_count_from_moments(
            self.mean, self.var, self.count, batch_mean, batch_var, batch_count
        )
