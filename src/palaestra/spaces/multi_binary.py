"""`MultiBinary`: int8 arrays of 0s and 1s with a fixed shape."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space


class MultiBinary(Space[npt.NDArray[np.int8]]):
    """Binary arrays of shape ``(n,)`` or ``n`` (a sequence of dimensions).

    >>> space = MultiBinary(5, seed=42)
    >>> space
    MultiBinary(5)
    >>> space.sample()
    array([1, 0, 1, 0, 1], dtype=int8)
    """

    dtype: np.dtype
    n: int | tuple[int, ...]

    def __init__(
        self,
        n: npt.NDArray[np.integer] | Sequence[int] | int,
        seed: int | np.random.Generator | None = None,
    ) -> None:
        """Build the space of binary arrays with shape ``n``."""
        if isinstance(n, np.ndarray) and n.ndim == 0 and n.dtype.kind in "iu":
            n = n.item()  # a 0-d integer array is an int
        if isinstance(n, (int, np.integer)):
            self.n = int(n)
            shape: tuple[int, ...] = (self.n,)
        elif (isinstance(n, Sequence) and not isinstance(n, (str, bytes))) or (
            isinstance(n, np.ndarray) and n.ndim == 1
        ):
            if not all(isinstance(i, (int, np.integer)) for i in n):
                # Gymnasium casts with int(): "3" parses, 2.5 becomes 2, "0;" fails inside int.
                raise ValueError(f"Expected n to be an int or a sequence of ints, actual: {n!r}")
            self.n = shape = tuple(int(i) for i in n)
        else:
            raise ValueError(
                f"Expected n to be an int or a sequence of ints, actual type: {type(n)}"
            )
        if not all(dim > 0 for dim in shape):
            raise ValueError(f"n (counts) have to be positive, got {n}")
        if math.prod(shape) > np.iinfo(np.intp).max:  # no array that large can exist
            raise ValueError(f"MultiBinary n={n!r} has more elements than an array can hold")
        super().__init__(shape, np.int8, seed)

    @property
    def shape(self) -> tuple[int, ...]:
        """The shape of the binary arrays (never ``None``)."""
        return self._shape  # type: ignore[return-value]

    @property
    def is_np_flattenable(self) -> Literal[True]:
        """Flattens to itself, raveled."""
        return True

    def sample(
        self,
        mask: npt.NDArray[np.int8] | None = None,
        probability: npt.NDArray[np.float64] | None = None,
    ) -> npt.NDArray[np.int8]:
        """Fair coins; ``mask`` fixes entries (0/1, 2 = random); ``probability`` gives P(1)."""
        if mask is not None and probability is not None:
            raise ValueError(
                "Only one of `mask` or `probability` can be provided, "
                f"actual values: mask={mask}, probability={probability}"
            )
        if mask is not None:
            self._check(mask, np.int8, "mask", InvalidMask)
            if not ((mask == 0) | (mask == 1) | (mask == 2)).all():
                raise InvalidMask(
                    f"All values of a mask should be 0, 1 or 2, actual values: {mask}"
                )
            # The full-size draw happens even where the mask fixes the value, as in Gymnasium,
            # so that masked and unmasked sampling consume the generator identically.
            coins = self.np_random.integers(low=0, high=2, size=self.n, dtype=self.dtype)
            return np.where(mask == 2, coins, mask.astype(self.dtype))
        if probability is not None:
            self._check(probability, np.float64, "probability", InvalidProbabilityMask)
            if not ((probability >= 0) & (probability <= 1)).all():
                raise InvalidProbabilityMask(
                    "All values of the sample probability should be between 0 and 1, "
                    f"actual values: {probability}"
                )
            return (self.np_random.random(size=self.shape) <= probability).astype(self.dtype)
        return self.np_random.integers(low=0, high=2, size=self.n, dtype=self.dtype)

    def _check(self, mask: Any, dtype: type, name: str, exc: type[Exception]) -> None:
        if not isinstance(mask, np.ndarray):
            raise exc(f"The expected type of the {name} is np.ndarray, actual type: {type(mask)}")
        if mask.dtype != dtype:
            raise exc(
                f"The expected dtype of the {name} is np.{np.dtype(dtype)}, "
                f"actual dtype: {mask.dtype}"
            )
        if mask.shape != self.shape:
            raise exc(
                f"The expected shape of the {name} is {self.shape}, actual shape: {mask.shape}"
            )

    def contains(self, x: Any) -> bool:
        """Whether ``x`` has the space's shape and only 0/1 entries (any numeric dtype)."""
        if isinstance(x, Sequence):
            try:
                x = np.array(x)
            except ValueError:  # ragged nesting: not an array, so not a member
                return False
        return bool(
            isinstance(x, np.ndarray) and x.shape == self.shape and ((x == 0) | (x == 1)).all()
        )

    def to_jsonable(self, sample_n: Iterable[np.ndarray]) -> list[Any]:
        """Samples as nested lists."""
        return np.array(list(sample_n)).tolist()

    def from_jsonable(self, sample_n: Iterable[Any]) -> list[np.ndarray]:
        """Nested lists back to int8 arrays."""
        return [np.asarray(sample, self.dtype) for sample in sample_n]

    def __repr__(self) -> str:
        return f"MultiBinary({self.n})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, MultiBinary) and self.n == other.n
