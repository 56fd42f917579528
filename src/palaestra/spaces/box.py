"""`Box`: a (possibly unbounded) box in R^n, with per-coordinate bounds."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Literal, SupportsFloat

import numpy as np
import numpy.typing as npt

from palaestra import error, logger
from palaestra.spaces.space import Space, can_cast

BoundLike = SupportsFloat | np.ndarray


def array_short_repr(arr: np.ndarray) -> str:
    """Gymnasium's bound repr: the scalar if every entry is equal, else the whole array.

    >>> array_short_repr(np.full((2, 2), 1.5, dtype=np.float32))
    '1.5'
    >>> array_short_repr(np.array([-1.2, -0.07], dtype=np.float32))
    '[-1.2  -0.07]'
    """
    if arr.size != 0 and np.min(arr) == np.max(arr):
        return str(np.min(arr))
    return str(arr)


def _is_scalar(value: object) -> bool:
    """Python or numpy int/float, not bool (``Box(False, True)`` needs an explicit shape)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


class Box(Space[npt.NDArray[Any]]):
    """The Cartesian product of closed intervals ``[low[i], high[i]]`` (either end may be inf).

    >>> Box(low=-1.0, high=2.0, shape=(3, 4), dtype=np.float32)
    Box(-1.0, 2.0, (3, 4), float32)
    >>> Box(np.array([-1.2, -0.07], np.float32), np.array([0.6, 0.07], np.float32))
    Box([-1.2  -0.07], [0.6  0.07], (2,), float32)
    >>> Box(0, 255, (210, 160, 3), np.uint8)
    Box(0, 255, (210, 160, 3), uint8)
    """

    dtype: np.dtype
    _shape: tuple[int, ...]

    def __init__(
        self,
        low: BoundLike,
        high: BoundLike,
        shape: Sequence[int] | None = None,
        dtype: npt.DTypeLike = np.float32,
        seed: int | np.random.Generator | None = None,
    ) -> None:
        """Build a box; scalar bounds are broadcast to ``shape`` (default ``(1,)``)."""
        if dtype is None:
            raise ValueError("Box dtype must be explicitly provided, cannot be None.")
        self.dtype = np.dtype(dtype)
        if self.dtype.kind not in ("i", "u", "f", "b"):
            raise ValueError(
                f"Invalid Box dtype ({self.dtype}), must be an integer, floating, or bool dtype"
            )
        self._shape = self._infer_shape(low, high, shape)

        dtype_min: float
        dtype_max: float
        if self.dtype.kind == "b":
            dtype_min, dtype_max = 0, 1
        elif self.dtype.kind == "f":
            finfo = np.finfo(self.dtype)
            dtype_min, dtype_max = float(finfo.min), float(finfo.max)
        else:
            iinfo = np.iinfo(self.dtype)
            dtype_min, dtype_max = int(iinfo.min), int(iinfo.max)

        self.low, self.bounded_below = self._cast_bound(low, "low", dtype_min)
        self.high, self.bounded_above = self._cast_bound(high, "high", dtype_max)
        for name, bound in (("low", self.low), ("high", self.high)):
            if bound.shape != self._shape:
                raise ValueError(
                    f"Box {name}.shape doesn't match provided shape, "
                    f"{name}.shape={bound.shape}, shape={self._shape}"
                )
        if self.dtype.kind == "f":
            # -0.0 + 0.0 is +0.0: numpy's uniform refuses high=-0.0 over low=0.0 ("high - low
            # < 0") although the bounds are equal (Gymnasium's sample raises there).
            self.high += 0.0
        if np.any(self.low > self.high):
            raise ValueError(
                "Box all low values must be less than or equal to high (some values break this), "
                f"low={self.low}, high={self.high}"
            )
        self.low_repr: str | None = None
        self.high_repr: str | None = None
        self._cache_sampling_layout()
        super().__init__(self._shape, self.dtype, seed)

    @staticmethod
    def _infer_shape(
        low: BoundLike, high: BoundLike, shape: Sequence[int] | None
    ) -> tuple[int, ...]:
        if shape is not None:
            if not isinstance(shape, Iterable):
                raise TypeError(f"Expected Box shape to be an iterable, actual type={type(shape)}")
            if not all(isinstance(dim, (int, np.integer)) for dim in shape):
                raise TypeError(
                    "Expected all Box shape elements to be integer, "
                    f"actual type={tuple(type(dim) for dim in shape)}"
                )
            if any(dim < 0 for dim in shape):
                raise ValueError(f"Box shape dimensions must be non-negative, shape={shape}")
            if math.prod(int(dim) for dim in shape) > np.iinfo(np.intp).max:
                # numpy's own message ("Maximum allowed dimension exceeded") names nothing.
                raise ValueError(f"Box shape={shape} has more elements than an array can hold")
            return tuple(int(dim) for dim in shape)
        if isinstance(low, np.ndarray) and isinstance(high, np.ndarray):
            if low.shape != high.shape:
                raise ValueError(
                    "Box low.shape and high.shape don't match, "
                    f"low.shape={low.shape}, high.shape={high.shape}"
                )
            return low.shape
        if isinstance(low, np.ndarray):
            return low.shape
        if isinstance(high, np.ndarray):
            return high.shape
        if _is_scalar(low) and _is_scalar(high):
            return (1,)
        raise ValueError(
            "Box shape is not specified, therefore inferred from low and high. Expected low and "
            f"high to be np.ndarray, integer, or float.Actual types low={type(low)}, "
            f"high={type(high)}"
        )

    def _cast_bound(
        self, value: BoundLike, name: Literal["low", "high"], dtype_limit: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Validate one bound and cast it to ``self.dtype``; also return where it is finite.

        NaN and out-of-range checks run before the cast, since casting to an integer dtype
        would silently turn them into valid-looking numbers.
        """
        is_low = name == "low"
        if _is_scalar(value):
            return self._cast_scalar_bound(value, name, dtype_limit)
        if not isinstance(value, np.ndarray):
            raise ValueError(
                f"Box {name} must be a np.ndarray, integer, or float, actual type={type(value)}"
            )
        if value.dtype.kind not in ("f", "i", "u", "b"):
            raise ValueError(
                f"Box {name} must be a floating, integer, or bool dtype, actual dtype={value.dtype}"
            )
        if value.dtype.kind == "f" and np.isnan(value).any():
            raise ValueError(f"No {name} value can be equal to `np.nan`, {name}={value}")

        infinite = np.isneginf(value) if is_low else np.isposinf(value)
        if infinite.any():
            if self.dtype.kind in ("u", "b"):
                inf_name = "-np.inf" if is_low else "np.inf"
                raise ValueError(
                    f"Box unsigned int dtype don't support `{inf_name}`, {name}={value}"
                )
            if self.dtype.kind == "i":
                # A signed-int box is "unbounded" at the dtype limit. Build the result in the
                # target dtype (float(2**63 - 1) would overflow int64) and never write into
                # the caller's array.
                finite = np.where(infinite, 0, value).astype(self.dtype)
                return np.where(infinite, self.dtype.type(dtype_limit), finite), ~infinite
        elif value.dtype != self.dtype and (
            (value < dtype_limit).any() if is_low else (value > dtype_limit).any()
        ):
            self._raise_out_of_range(value, name, dtype_limit)
        self._refuse_wrap_around(value, name)
        if value.dtype.kind == "f" and self.dtype.kind == "f":
            if np.finfo(self.dtype).precision < np.finfo(value.dtype).precision:
                logger.warn(
                    f"Box {name}'s precision lowered by casting to {self.dtype}, "
                    f"current {name}.dtype={value.dtype}"
                )
        return value.astype(self.dtype), ~infinite

    def _cast_scalar_bound(
        self, value: Any, name: Literal["low", "high"], dtype_limit: float
    ) -> tuple[np.ndarray, np.ndarray]:
        is_low = name == "low"
        if np.isnan(value):
            raise ValueError(f"No {name} value can be equal to `np.nan`, {name}={value}")
        infinite = bool(np.isneginf(value) if is_low else np.isposinf(value))
        if infinite:
            if self.dtype.kind in ("u", "b"):
                inf_name = "-np.inf" if is_low else "np.inf"
                raise ValueError(
                    f"Box unsigned int dtype don't support `{inf_name}`, {name}={value}"
                )
            if self.dtype.kind == "i":
                value = dtype_limit
        elif value < dtype_limit if is_low else value > dtype_limit:
            self._raise_out_of_range(value, name, dtype_limit)
        self._refuse_wrap_around(np.asarray(value), name)
        return np.full(self._shape, value, dtype=self.dtype), np.full(self._shape, not infinite)

    def _refuse_wrap_around(self, value: np.ndarray, name: str) -> None:
        """An integer box's bound must lie in its dtype, at both ends: Gymnasium checks only
        ``low >= min`` and ``high <= max``, so ``high=-254`` becomes 2 in int8."""
        if self.dtype.kind not in "iu" or value.dtype == self.dtype:
            return
        info = np.iinfo(self.dtype)
        if ((value < info.min) | (value > info.max)).any():
            raise ValueError(
                f"Box {name} is out of bounds of the dtype range, {name}={value}, "
                f"{self.dtype} holds [{info.min}, {info.max}]"
            )

    @staticmethod
    def _raise_out_of_range(value: Any, name: str, dtype_limit: float) -> None:
        kind = "min" if name == "low" else "max"
        raise ValueError(
            f"Box {name} is out of bounds of the dtype range, {name}={value}, "
            f"{kind} dtype={dtype_limit}"
        )

    def _cache_sampling_layout(self) -> None:
        # Most boxes are fully bounded; remembering that lets `sample` skip the masked writes.
        # For the others, keep only the non-empty interval kinds, in Gymnasium's draw order.
        below, above = self.bounded_below, self.bounded_above
        self._all_bounded = bool(below.all() and above.all())
        kinds = [
            ("normal", ~below & ~above),
            ("exponential", below & ~above),
            ("negative_exponential", ~below & above),
            ("uniform", below & above),
        ]
        self._interval_kinds = [(kind, mask, int(mask.sum())) for kind, mask in kinds if mask.any()]

    @property
    def shape(self) -> tuple[int, ...]:
        """The shape of the box's elements (never ``None``)."""
        return self._shape

    @property
    def is_np_flattenable(self) -> Literal[True]:
        """A box is always flattenable."""
        return True

    def is_bounded(self, manner: Literal["both", "below", "above"] = "both") -> bool:
        """Whether every coordinate is bounded ``"below"``, ``"above"`` or on ``"both"`` sides."""
        below = bool(np.all(self.bounded_below))
        above = bool(np.all(self.bounded_above))
        if manner == "both":
            return below and above
        if manner == "below":
            return below
        if manner == "above":
            return above
        raise ValueError(f"manner is not in {{'below', 'above', 'both'}}, actual value: {manner}")

    def sample(self, mask: None = None, probability: None = None) -> npt.NDArray[Any]:
        """Draw a point: uniform on [a, b], shifted exponential on half-lines, normal on R.

        The draw order (normal, exponential, negative exponential, uniform) is Gymnasium's, so a
        seeded box gives the same samples.

        >>> Box(-1.0, 1.0, (2,), seed=42).sample()
        array([ 0.5479121 , -0.12224312], dtype=float32)
        """
        if mask is not None:
            raise error.Error(f"Box.sample cannot be provided a mask, actual value: {mask}")
        if probability is not None:
            raise error.Error(
                f"Box.sample cannot be provided a probability mask, actual value: {probability}"
            )
        rng = self.np_random
        # Integer boxes draw from [low, high + 1) and floor, so `high` itself can be drawn.
        high = self.high if self.dtype.kind == "f" else self.high.astype(np.int64) + 1
        if self._all_bounded:
            sample = rng.uniform(low=self.low, high=high, size=self._shape)
        else:
            sample = self._sample_mixed(rng, high)
        if self.dtype.kind == "f":
            return sample.astype(self.dtype, copy=False)  # sample is fresh; float64 needs no copy

        sample = np.floor(sample)
        if self.dtype.kind != "b":
            iinfo = np.iinfo(self.dtype)
            lo, hi = int(iinfo.min), int(iinfo.max)
            if self.dtype == np.int64:
                # float64 cannot represent the int64 limits exactly; keep a margin so the cast
                # below cannot wrap around.
                lo, hi = lo + 2, hi - 2
            sample = sample.clip(lo, hi)
        sample = sample.astype(self.dtype)
        if self.dtype == np.int64:
            sample = sample.clip(self.low, self.high)
        return sample

    def _sample_mixed(self, rng: np.random.Generator, high: np.ndarray) -> np.ndarray:
        sample = np.empty(self._shape)  # float64, cast to the box dtype by the caller
        for kind, mask, count in self._interval_kinds:
            if kind == "normal":
                sample[mask] = rng.normal(size=count)
            elif kind == "exponential":
                sample[mask] = rng.exponential(size=count) + self.low[mask]
            elif kind == "negative_exponential":
                sample[mask] = -rng.exponential(size=count) + high[mask]
            else:
                sample[mask] = rng.uniform(low=self.low[mask], high=high[mask], size=count)
        return sample

    def contains(self, x: Any) -> bool:
        """Whether ``x`` has the box's shape, a dtype that casts safely, and lies within bounds."""
        if not isinstance(x, np.ndarray):
            logger.warn("Casting input x to numpy array.")
            try:
                x = np.asarray(x, dtype=self.dtype)
            except (ValueError, TypeError, OverflowError):
                return False
        # Cheapest checks first; NaN fails both comparisons, so it is never contained.
        return bool(
            x.shape == self._shape
            and can_cast(x.dtype, self.dtype)
            and ((x >= self.low) & (x <= self.high)).all()
        )

    def to_jsonable(self, sample_n: Iterable[np.ndarray]) -> list[Any]:
        """Samples as nested lists."""
        return [sample.tolist() for sample in sample_n]

    def from_jsonable(self, sample_n: Iterable[Any]) -> list[np.ndarray]:
        """Nested lists back to arrays of the box dtype."""
        return [np.asarray(sample, dtype=self.dtype) for sample in sample_n]

    def __repr__(self) -> str:
        if self.low_repr is None:
            self.low_repr = array_short_repr(self.low)
        if self.high_repr is None:
            self.high_repr = array_short_repr(self.high)
        return f"Box({self.low_repr}, {self.high_repr}, {self._shape}, {self.dtype})"

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, Box)
            and self._shape == other._shape
            and self.dtype == other.dtype
            and np.allclose(self.low, other.low)
            and np.allclose(self.high, other.high)
        )

    def __getstate__(self) -> dict[str, Any]:
        # The sampling layout is derived from the bounds; keep pickles to Gymnasium's fields.
        state = self.__dict__.copy()
        state.pop("_all_bounded", None)
        state.pop("_interval_kinds", None)
        return state

    def __setstate__(self, state: Iterable[tuple[str, Any]] | Mapping[str, Any]) -> None:
        super().__setstate__(state)
        # Pickles from before the repr cache existed lack these attributes.
        if not hasattr(self, "low_repr"):
            self.low_repr = array_short_repr(self.low)
        if not hasattr(self, "high_repr"):
            self.high_repr = array_short_repr(self.high)
        self._cache_sampling_layout()
