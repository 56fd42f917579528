"""`OneOf`: the direct sum of spaces; an element is ``(index, member of spaces[index])``."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space, require_spaces


class OneOf(Space[tuple[int, Any]]):
    """Exactly one of several spaces, chosen uniformly when sampling.

    >>> from palaestra.spaces import Box, Discrete
    >>> space = OneOf((Discrete(2), Box(-1, 1, shape=(2,))), seed=123)
    >>> space.sample()
    (np.int64(0), np.int64(0))
    >>> space.sample()
    (np.int64(1), array([-0.00711833, -0.7257502 ], dtype=float32))
    """

    spaces: tuple[Space[Any], ...]

    def __init__(
        self, spaces: Iterable[Space[Any]], seed: int | np.random.Generator | None = None
    ) -> None:
        """Build the direct sum of the (non-empty) ``spaces``."""
        if not isinstance(spaces, Iterable):
            raise TypeError(f"{spaces} is not an iterable")
        self.spaces = tuple(spaces)
        if len(self.spaces) == 0:
            raise ValueError("Empty `OneOf` spaces are not supported.")
        require_spaces(self.spaces)
        super().__init__(None, None, seed)

    @property
    def is_np_flattenable(self) -> bool:
        """Whether every subspace is flattenable."""
        return all(space.is_np_flattenable for space in self.spaces)

    def seed(self, seed: int | tuple[int, ...] | list[int] | None = None) -> tuple[Any, ...]:
        """Seed this space (which picks the index) and then each subspace.

        An int seeds this space, derives one seed per subspace, then re-seeds this space so
        that int and tuple seeding leave it in the same state (Gymnasium's behaviour).
        """
        if seed is None:
            return (super().seed(None), *(space.seed(None) for space in self.spaces))
        if isinstance(seed, int):
            super_seed = super().seed(seed)
            subseeds = self.np_random.integers(np.iinfo(np.int32).max, size=len(self.spaces))
            super().seed(seed)
            return (
                super_seed,
                *(space.seed(int(s)) for space, s in zip(self.spaces, subseeds)),
            )
        if isinstance(seed, (tuple, list)):
            if len(seed) != len(self.spaces) + 1:
                raise ValueError(
                    "Expects that the subspaces of seeds equals the number of subspaces + 1. "
                    f"Actual length of seeds: {len(seed)}, length of subspaces: {len(self.spaces)}"
                )
            return (
                super().seed(seed[0]),
                *(space.seed(s) for space, s in zip(self.spaces, seed[1:])),
            )
        raise TypeError(f"Expected None, int, or tuple of ints, actual type: {type(seed)}")

    def sample(
        self, mask: tuple[Any, ...] | None = None, probability: tuple[Any, ...] | None = None
    ) -> tuple[Any, Any]:
        """Pick a subspace uniformly, then sample it with its entry of ``mask``/``probability``."""
        # Gymnasium draws the index before validating the arguments; keep that order.
        index = self.np_random.integers(0, len(self.spaces), dtype=np.int64)
        subspace = self.spaces[index]
        if mask is not None and probability is not None:
            raise ValueError(
                "Only one of `mask` or `probability` can be provided, "
                f"actual values: mask={mask}, probability={probability}"
            )
        if mask is not None:
            self._check_masks(mask, "mask", InvalidMask)
            return index, subspace.sample(mask=mask[index])
        if probability is not None:
            self._check_masks(probability, "probability", InvalidProbabilityMask)
            return index, subspace.sample(probability=probability[index])
        return index, subspace.sample()

    def _check_masks(self, masks: Any, name: str, exc: type[Exception]) -> None:
        if not isinstance(masks, tuple):
            raise exc(f"Expected type of `{name}` is tuple, actual type: {type(masks)}")
        if len(masks) != len(self.spaces):
            raise exc(
                f"Expected length of `{name}` is {len(self.spaces)}, actual length: {len(masks)}"
            )

    def contains(self, x: Any) -> bool:
        """Whether ``x`` is ``(i, value)`` with ``value`` in ``spaces[i]``."""
        return bool(
            isinstance(x, tuple)
            and len(x) == 2
            and isinstance(x[0], (np.int64, int))
            and 0 <= x[0] < len(self.spaces)
            and self.spaces[x[0]].contains(x[1])
        )

    def __repr__(self) -> str:
        return "OneOf(" + ", ".join(str(s) for s in self.spaces) + ")"

    def to_jsonable(self, sample_n: Iterable[tuple[int, Any]]) -> list[list[Any]]:
        """Each sample as ``[index, jsonable value]``."""
        return [[int(i), self.spaces[i].to_jsonable([value])[0]] for i, value in sample_n]

    def from_jsonable(self, sample_n: list[list[Any]]) -> list[tuple[Any, Any]]:
        """``[index, value]`` pairs back to ``(np.int64 index, sample)`` tuples."""
        return [(np.int64(i), self.spaces[i].from_jsonable([value])[0]) for i, value in sample_n]

    def __getitem__(self, index: int) -> Space[Any]:
        return self.spaces[index]

    def __len__(self) -> int:
        return len(self.spaces)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, OneOf) and self.spaces == other.spaces
