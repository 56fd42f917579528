"""`Tuple`: the Cartesian product of spaces; elements are Python tuples."""

from __future__ import annotations

import typing
from collections.abc import Iterable
from typing import Any

import numpy as np

from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space, require_spaces


class Tuple(Space[tuple[Any, ...]], typing.Sequence[Any]):
    """A tuple of spaces, sampled independently.

    >>> from palaestra.spaces import Box, Discrete
    >>> space = Tuple((Discrete(2), Box(-1, 1, shape=(2,))), seed=42)
    >>> space
    Tuple(Discrete(2), Box(-1.0, 1.0, (2,), float32))
    >>> space.sample()
    (np.int64(0), array([-0.3991573 ,  0.21649833], dtype=float32))
    """

    spaces: tuple[Space[Any], ...]

    def __init__(
        self, spaces: Iterable[Space[Any]], seed: int | np.random.Generator | None = None
    ) -> None:
        """Build the product of ``spaces``; an int ``seed`` derives one seed per subspace."""
        self.spaces = require_spaces(spaces)
        super().__init__(None, None, seed)

    @property
    def is_np_flattenable(self) -> bool:
        """Whether every subspace is flattenable."""
        return all(space.is_np_flattenable for space in self.spaces)

    def seed(self, seed: int | typing.Sequence[int] | None = None) -> tuple[Any, ...]:
        """Seed the subspaces: ``None`` randomly, an int via derived seeds, a sequence one each.

        >>> from palaestra.spaces import Discrete
        >>> Tuple([Discrete(2), Discrete(3)]).seed(42)
        (191664963, 1662057957)
        """
        if seed is None:
            return tuple(space.seed(None) for space in self.spaces)
        if isinstance(seed, int):
            super().seed(seed)
            # Gymnasium draws the subseeds below int32 max; the same draw gives the same seeds.
            subseeds = self.np_random.integers(np.iinfo(np.int32).max, size=len(self.spaces))
            return tuple(space.seed(int(subseed)) for space, subseed in zip(self.spaces, subseeds))
        if isinstance(seed, (tuple, list)):
            if len(seed) != len(self.spaces):
                raise ValueError(
                    "Expects that the subspaces of seeds equals the number of subspaces. "
                    f"Actual length of seeds: {len(seed)}, length of subspaces: {len(self.spaces)}"
                )
            return tuple(space.seed(subseed) for subseed, space in zip(seed, self.spaces))
        raise TypeError(f"Expected seed type: list, tuple, int or None, actual type: {type(seed)}")

    def sample(
        self, mask: tuple[Any, ...] | None = None, probability: tuple[Any, ...] | None = None
    ) -> tuple[Any, ...]:
        """Sample each subspace, passing it the matching entry of ``mask`` or ``probability``."""
        if mask is not None and probability is not None:
            raise ValueError(
                "Only one of `mask` or `probability` can be provided, "
                f"actual values: mask={mask}, probability={probability}"
            )
        if mask is not None:
            self._check_masks(mask, "mask", InvalidMask)
            return tuple(space.sample(mask=m) for space, m in zip(self.spaces, mask))
        if probability is not None:
            self._check_masks(probability, "probability", InvalidProbabilityMask)
            return tuple(space.sample(probability=p) for space, p in zip(self.spaces, probability))
        return tuple(space.sample() for space in self.spaces)

    def _check_masks(self, masks: Any, name: str, exc: type[Exception]) -> None:
        if not isinstance(masks, tuple):
            raise exc(f"Expected type of `{name}` to be tuple, actual type: {type(masks)}")
        if len(masks) != len(self.spaces):
            raise exc(
                f"Expected length of `{name}` to be {len(self.spaces)}, actual length: {len(masks)}"
            )

    def contains(self, x: Any) -> bool:
        """Whether ``x`` (a tuple, list or array) has one member of each subspace, in order."""
        if isinstance(x, list) or (isinstance(x, np.ndarray) and x.ndim > 0):
            x = tuple(x)  # (a 0-d array holds no parts: it stays, and is not a member)
        return (
            isinstance(x, tuple)
            and len(x) == len(self.spaces)
            and all(space.contains(part) for space, part in zip(self.spaces, x))
        )

    def __repr__(self) -> str:
        return "Tuple(" + ", ".join(str(s) for s in self.spaces) + ")"

    def to_jsonable(self, sample_n: Iterable[tuple[Any, ...]]) -> list[Any]:
        """One JSON list per subspace (column-wise), as Gymnasium stores it."""
        sample_n = list(sample_n)
        return [
            space.to_jsonable([sample[i] for sample in sample_n])
            for i, space in enumerate(self.spaces)
        ]

    def from_jsonable(self, sample_n: list[Any]) -> list[tuple[Any, ...]]:
        """Columns from ``to_jsonable`` back to a list of tuples."""
        columns = [space.from_jsonable(sample_n[i]) for i, space in enumerate(self.spaces)]
        return list(zip(*columns))

    @typing.overload
    def __getitem__(self, index: int) -> Space[Any]: ...
    @typing.overload
    def __getitem__(self, index: slice) -> tuple[Space[Any], ...]: ...
    def __getitem__(self, index: int | slice) -> Space[Any] | tuple[Space[Any], ...]:
        return self.spaces[index]

    def __len__(self) -> int:
        return len(self.spaces)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Tuple) and self.spaces == other.spaces
