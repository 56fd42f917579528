"""`Discrete`: the integers ``{start, ..., start + n - 1}``."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space, can_cast


class Discrete(Space[np.integer]):
    """A finite set of consecutive integers.

    >>> Discrete(3)
    Discrete(3)
    >>> space = Discrete(3, start=-1, seed=42)
    >>> space
    Discrete(3, start=-1)
    >>> space.sample()
    np.int64(-1)
    >>> space.sample(mask=np.array([0, 0, 1], dtype=np.int8))
    np.int64(1)
    """

    dtype: np.dtype
    n: np.integer
    start: np.integer

    def __init__(
        self,
        n: int | np.integer,
        seed: int | np.random.Generator | None = None,
        start: int | np.integer = 0,
        dtype: npt.DTypeLike = np.int64,
    ) -> None:
        """Build ``{start, ..., start + n - 1}`` with elements of integer ``dtype``."""
        if not np.issubdtype(type(n), np.integer):
            raise TypeError(f"Expects `n` to be an integer, actual dtype: {type(n)}")
        if n <= 0:
            raise ValueError(f"n (counts) have to be positive, actual value: {n}")
        if not np.issubdtype(type(start), np.integer):
            raise TypeError(f"Expects `start` to be an integer, actual type: {type(start)}")
        if dtype is None:
            raise TypeError(f"Invalid Discrete dtype, cannot be {dtype}.")
        self.dtype = np.dtype(dtype)
        if not np.issubdtype(self.dtype, np.integer):
            raise TypeError(f"Invalid Discrete dtype ({self.dtype}), must be an integer dtype")
        info = np.iinfo(self.dtype)
        largest, dtype_max = int(start) + int(n) - 1, int(info.max)
        if largest > dtype_max:
            # Gymnasium accepts this, then samples wrap around to values outside the space.
            raise ValueError(
                f"Discrete largest element start + n - 1 = {largest} does not fit dtype "
                f"{self.dtype} (max {dtype_max}); use a wider dtype or a smaller start/n"
            )
        for name, value in (("n", n), ("start", start)):
            if not info.min <= int(value) <= dtype_max:  # numpy would raise OverflowError
                raise ValueError(f"Discrete {name}={value!r} does not fit dtype {self.dtype}")
        self.n = self.dtype.type(n)  # type: ignore[assignment]
        self.start = self.dtype.type(start)  # type: ignore[assignment]
        self._cache_bounds()
        super().__init__((), self.dtype, seed)

    def _cache_bounds(self) -> None:
        # `contains` is on the step hot path: precompute the accepted integer range instead of
        # calling np.iinfo per call (clipped to the dtype for spaces unpickled from Gymnasium,
        # which allows ranges past the dtype).
        iinfo = np.iinfo(self.dtype)
        self._lo = max(int(self.start), int(iinfo.min))
        self._hi = min(int(self.start) + int(self.n), int(iinfo.max) + 1)  # exclusive

    @property
    def is_np_flattenable(self) -> Literal[True]:
        """A discrete space flattens to a one-hot vector."""
        return True

    def sample(
        self, mask: npt.NDArray[np.int8] | None = None, probability: npt.NDArray[Any] | None = None
    ) -> np.integer:
        """Draw uniformly, uniformly among ``mask == 1`` entries, or by ``probability``.

        An all-zero ``mask`` returns ``start``, as in Gymnasium.
        """
        if mask is not None and probability is not None:
            raise ValueError(
                "Only one of `mask` or `probability` can be provided, "
                f"actual values: mask={mask}, probability={probability}"
            )
        if mask is not None:
            valid = self._check_mask(mask)
            if valid.any():
                return self.start + self.dtype.type(self.np_random.choice(np.flatnonzero(valid)))
            return self.start
        if probability is not None:
            self._check_probability(probability)
            return self.start + self.np_random.choice(
                np.arange(self.n, dtype=self.dtype), p=probability
            )
        return self.start + self.np_random.integers(self.n, dtype=self.dtype.type)

    def _check_mask(self, mask: Any) -> np.ndarray:
        if not isinstance(mask, np.ndarray):
            raise InvalidMask(
                f"The expected type of the sample mask is np.ndarray, actual type: {type(mask)}"
            )
        if mask.dtype != np.int8:
            raise InvalidMask(
                f"The expected dtype of the sample mask is np.int8, actual dtype: {mask.dtype}"
            )
        if mask.shape != (self.n,):
            raise InvalidMask(
                f"The expected shape of the sample mask is {(int(self.n),)}, "
                f"actual shape: {mask.shape}"
            )
        valid = mask == 1
        if not (valid | (mask == 0)).all():
            raise InvalidMask(
                f"All values of the sample mask should be 0 or 1, actual values: {mask}"
            )
        return valid

    def _check_probability(self, probability: Any) -> None:
        if not isinstance(probability, np.ndarray):
            raise InvalidProbabilityMask(
                "The expected type of the sample probability is np.ndarray, "
                f"actual type: {type(probability)}"
            )
        if probability.dtype != np.float64:
            raise InvalidProbabilityMask(
                "The expected dtype of the sample probability is np.float64, "
                f"actual dtype: {probability.dtype}"
            )
        if probability.shape != (self.n,):
            raise InvalidProbabilityMask(
                f"The expected shape of the sample probability is {(int(self.n),)}, "
                f"actual shape: {probability.shape}"
            )
        if not ((probability >= 0) & (probability <= 1)).all():
            raise InvalidProbabilityMask(
                "All values of the sample probability should be between 0 and 1, "
                f"actual values: {probability}"
            )
        if not np.isclose(probability.sum(), 1):
            raise InvalidProbabilityMask(
                "The sum of the sample probability should be equal to 1, "
                f"actual sum: {probability.sum()}"
            )

    def contains(self, x: Any) -> bool:
        """Whether ``x`` is an in-range int, or 0-d integer numpy value of a safely castable dtype.

        >>> 2 in Discrete(3), 3 in Discrete(3), np.int32(1) in Discrete(3), 1.0 in Discrete(3)
        (True, False, True, False)
        """
        if isinstance(x, int):  # includes bool, as in Gymnasium
            return self._lo <= x < self._hi
        if isinstance(x, (np.generic, np.ndarray)) and x.shape == () and x.dtype.kind in "iu":
            return can_cast(x.dtype, self.dtype) and self._lo <= int(x) < self._hi
        return False

    def __repr__(self) -> str:
        info = [str(self.n)]
        if self.start != 0:
            info.append(f"start={self.start}")
        if self.dtype != np.int64:
            info.append(f"dtype={self.dtype}")
        return f"Discrete({', '.join(info)})"

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, Discrete)
            and self.n == other.n
            and self.start == other.start
            and self.dtype == other.dtype
        )

    def __getstate__(self) -> dict[str, Any]:
        # The cached bounds are derived data; keep pickles to Gymnasium's attribute set.
        state = self.__dict__.copy()
        for key in ("_lo", "_hi"):
            state.pop(key, None)
        return state

    def __setstate__(self, state: Iterable[tuple[str, Any]] | Mapping[str, Any]) -> None:
        state = dict(state)
        if "start" not in state:  # pickles from before openai/gym#2470
            state["start"] = np.int64(0)
        super().__setstate__(state)
        self._cache_bounds()

    def to_jsonable(self, sample_n: Iterable[Any]) -> list[int]:
        """Samples as Python ints."""
        return [int(x) for x in sample_n]

    def from_jsonable(self, sample_n: list[int]) -> list[np.integer]:
        """Ints back to numpy scalars of the space dtype."""
        return [self.dtype.type(x) for x in sample_n]
