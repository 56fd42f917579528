"""`MultiDiscrete`: a product of `Discrete` spaces laid out as an integer array."""

from __future__ import annotations

import copy
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from palaestra import logger
from palaestra.spaces.discrete import Discrete
from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space


def _integer_array(values: npt.ArrayLike, dtype: np.dtype, name: str) -> np.ndarray:
    """``values`` as a new array of ``dtype``: whole numbers that fit it, or a clear error.

    A scalar gives shape ``()``, as in Gymnasium. Gymnasium silently truncates fractions
    (``MultiDiscrete([2.5])`` is ``MultiDiscrete([2])``), casts complex values, parses strings
    and wraps integers that do not fit; each is refused here.
    """
    try:
        raw = np.asarray(values)
    except ValueError:  # ragged nesting
        raise ValueError(
            f"MultiDiscrete {name} must be a rectangular array of integers, got {values!r}"
        ) from None
    if raw.dtype.kind == "O" and raw.size and all(type(v) is int for v in raw.flat):
        raise ValueError(f"MultiDiscrete {name} {values!r} do not fit dtype {dtype}")
    if raw.dtype.kind not in "iuf":
        raise TypeError(
            f"MultiDiscrete {name} must be integers, got {values!r} "
            f"({type(values).__name__} of {raw.dtype})"
        )
    if raw.dtype.kind == "f" and not (np.isfinite(raw) & (raw == np.floor(raw))).all():
        raise ValueError(f"MultiDiscrete {name} must be whole numbers, actual values: {values!r}")
    info = np.iinfo(dtype)
    if raw.size and (raw.min() < info.min or raw.max() > info.max):
        raise ValueError(f"MultiDiscrete {name} {values!r} do not fit dtype {dtype}")
    return np.array(raw, dtype=dtype, copy=True)


class MultiDiscrete(Space[npt.NDArray[np.integer]]):
    """Independent categorical variables: entry ``i`` is in ``start[i] .. start[i]+nvec[i]-1``.

    >>> space = MultiDiscrete([5, 2, 2], seed=42)
    >>> space
    MultiDiscrete([5 2 2])
    >>> space.sample()
    array([3, 0, 1])
    >>> space[0]
    Discrete(5)
    """

    dtype: np.dtype
    nvec: npt.NDArray[np.integer]
    start: npt.NDArray[np.integer]

    def __init__(
        self,
        nvec: npt.ArrayLike,
        dtype: npt.DTypeLike = np.int64,
        seed: int | np.random.Generator | None = None,
        start: npt.ArrayLike | None = None,
    ) -> None:
        """Build the product of ``Discrete(nvec[i], start=start[i])`` (``start`` defaults to 0)."""
        if dtype is None:
            raise ValueError("MultiDiscrete dtype must be explicitly provided, cannot be None.")
        self.dtype = np.dtype(dtype)
        if not np.issubdtype(self.dtype, np.integer):
            raise ValueError(
                f"Invalid MultiDiscrete dtype ({self.dtype}), must be an integer dtype"
            )
        self.nvec = _integer_array(nvec, self.dtype, "nvec")
        if start is None:
            self.start = np.zeros(self.nvec.shape, dtype=self.dtype)
        else:
            self.start = _integer_array(start, self.dtype, "start")
        if self.start.shape != self.nvec.shape:
            raise ValueError(
                "start and nvec (counts) should have the same shape, "
                f"got {self.start.shape} and {self.nvec.shape}"
            )
        if not (self.nvec > 0).all():
            raise ValueError(f"nvec (counts) have to be positive, actual values: {nvec!r}")
        # Python ints cannot overflow; Gymnasium accepts spaces whose samples wrap around.
        largest = self.start.astype(object) + self.nvec.astype(object) - 1
        dtype_max = int(np.iinfo(self.dtype).max)
        if np.any(largest > dtype_max):
            raise ValueError(
                f"MultiDiscrete largest elements start + nvec - 1 = {largest} "
                f"do not fit dtype {self.dtype} (max {dtype_max}); use a wider dtype"
            )
        super().__init__(self.nvec.shape, self.dtype, seed)

    @property
    def shape(self) -> tuple[int, ...]:
        """The shape of ``nvec`` (never ``None``)."""
        return self._shape  # type: ignore[return-value]

    @property
    def is_np_flattenable(self) -> Literal[True]:
        """Flattens to concatenated one-hot vectors."""
        return True

    def sample(
        self,
        mask: tuple[Any, ...] | None = None,
        probability: tuple[Any, ...] | None = None,
    ) -> npt.NDArray[np.integer]:
        """Draw every entry; ``mask``/``probability`` are nested tuples with one array per entry.

        An entry whose mask is all zero takes its ``start`` value, as in Gymnasium.
        """
        if mask is not None and probability is not None:
            raise ValueError(
                "Only one of `mask` or `probability` can be provided, "
                f"actual values: mask={mask}, probability={probability}"
            )
        # Shape (): one entry, masked like a Discrete (its mask is one array, not a tuple).
        nvec, start = (
            (self.nvec.item(), self.start.item())
            if self.nvec.ndim == 0
            else (
                self.nvec,
                self.start,
            )
        )
        if mask is not None:
            return np.array(self._apply_mask(mask, nvec, start, "mask"), dtype=self.dtype)
        if probability is not None:
            return np.array(
                self._apply_mask(probability, nvec, start, "probability"), dtype=self.dtype
            )
        draw = (self.np_random.random(self.nvec.shape) * self.nvec).astype(self.dtype)
        return np.asarray(draw + self.start)  # an array for shape () too (numpy gives a scalar)

    def _apply_mask(self, sub_mask: Any, sub_nvec: Any, sub_start: Any, mask_type: str) -> Any:
        """Sample one (nested) entry; recursion follows the axes of ``nvec``."""
        exc = InvalidMask if mask_type == "mask" else InvalidProbabilityMask
        if isinstance(sub_nvec, np.ndarray):
            if not isinstance(sub_mask, tuple):
                raise exc(
                    f"Expects the mask to be a tuple for sub_nvec ({sub_nvec}), "
                    f"actual type: {type(sub_mask)}"
                )
            if len(sub_mask) != len(sub_nvec):
                raise exc(
                    "Expects the mask length to be equal to the number of actions, "
                    f"mask length: {len(sub_mask)}, nvec length: {len(sub_nvec)}"
                )
            return [
                self._apply_mask(m, n, s, mask_type)
                for m, n, s in zip(sub_mask, sub_nvec, sub_start)
            ]
        if not isinstance(sub_mask, np.ndarray):
            raise exc(f"Expects the sub mask to be np.ndarray, actual type: {type(sub_mask)}")
        if sub_mask.shape != (sub_nvec,):
            raise exc(
                "Expects the mask length to be equal to the number of actions, "
                f"mask length: {len(sub_mask)}, action: {sub_nvec}"
            )
        if mask_type == "mask":
            if sub_mask.dtype != np.int8:
                raise exc(f"Expects the mask dtype to be np.int8, actual dtype: {sub_mask.dtype}")
            valid = sub_mask == 1
            if not (valid | (sub_mask == 0)).all():
                raise exc(f"Expects all masks values to 0 or 1, actual values: {sub_mask}")
            if valid.any():
                return self.np_random.choice(np.flatnonzero(valid)) + sub_start
            return sub_start

        if sub_mask.dtype != np.float64:
            raise exc(f"Expects the mask dtype to be np.float64, actual dtype: {sub_mask.dtype}")
        valid = (sub_mask > 0) & (sub_mask <= 1)
        if not (valid | (sub_mask == 0)).all():
            raise exc(f"Expects all masks values to be between 0 and 1, actual values: {sub_mask}")
        total = sub_mask.sum()
        if not np.isclose(total, 1):
            raise exc(f"Expects the sum of all mask values to be 1, actual sum: {total}")
        # Renormalising (as Gymnasium does) keeps draws identical for sums within isclose of 1.
        normalized = sub_mask / total
        return self.np_random.choice(np.flatnonzero(valid), p=normalized[valid]) + sub_start

    def contains(self, x: Any) -> bool:
        """Whether ``x`` has the right shape, a castable dtype and every entry in range."""
        if isinstance(x, (Sequence, int, np.integer)) and not isinstance(x, str):
            try:  # lists, tuples and (for shape ()) integers are checked like arrays
                x = np.array(x)
            except ValueError:  # ragged nesting: not an array, so not a member
                return False
        # Compare with the largest element rather than computing `x - start`, which can
        # overflow small dtypes; `start + nvec - 1` always fits a valid space's dtype.
        return bool(
            isinstance(x, np.ndarray)
            and x.shape == self.shape
            and np.can_cast(x.dtype, self.dtype)
            and (self.start <= x).all()
            and (x <= self.start + (self.nvec - 1)).all()
        )

    def to_jsonable(self, sample_n: Iterable[np.ndarray]) -> list[Any]:
        """Samples as nested lists of ints."""
        return [sample.tolist() for sample in sample_n]

    def from_jsonable(self, sample_n: Iterable[Any]) -> list[np.ndarray]:
        """Nested lists back to arrays of the space dtype."""
        return [np.array(sample, dtype=self.dtype) for sample in sample_n]

    def __repr__(self) -> str:
        if np.any(self.start != 0):
            return f"MultiDiscrete({self.nvec}, start={self.start})"
        return f"MultiDiscrete({self.nvec})"

    def __getitem__(self, index: int | tuple[int, ...] | slice) -> Discrete | MultiDiscrete:
        """The sub-space at ``index``; it continues this space's random stream (a copy)."""
        nvec, start = self.nvec[index], self.start[index]
        subspace: Discrete | MultiDiscrete
        if nvec.ndim == 0:
            subspace = Discrete(nvec.item(), start=start.item(), dtype=self.dtype)
        else:
            subspace = MultiDiscrete(nvec, start=start, dtype=self.dtype)
        subspace.np_random = copy.deepcopy(self.np_random)
        return subspace

    def __len__(self) -> int:
        if self.nvec.ndim == 0:
            raise TypeError(f"{self} has shape (): it has no length")
        if self.nvec.ndim >= 2:
            logger.warn("Getting the length of a multi-dimensional MultiDiscrete space.")
        return len(self.nvec)

    def __eq__(self, other: object) -> bool:
        return bool(
            isinstance(other, MultiDiscrete)
            and self.dtype == other.dtype
            and self.shape == other.shape
            and np.all(self.nvec == other.nvec)
            and np.all(self.start == other.start)
        )

    def __setstate__(self, state: Iterable[tuple[str, Any]] | Mapping[str, Any]) -> None:
        state = dict(state)
        if "start" not in state:  # pickles from before `start` existed
            state["start"] = np.zeros(state["_shape"], dtype=state["dtype"])
        super().__setstate__(state)
