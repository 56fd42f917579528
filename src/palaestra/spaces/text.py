"""`Text`: strings of bounded length over a character set."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space

alphanumeric: frozenset[str] = frozenset(
    "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
)

LengthAndMask = tuple[int | None, npt.NDArray[Any] | None]


class Text(Space[str]):
    """Strings of ``min_length`` to ``max_length`` characters drawn from ``charset``.

    >>> Text(5)
    Text(1, 5, charset=0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz)
    >>> Text(10, min_length=0, charset="abc")
    Text(0, 10, charset=abc)
    """

    def __init__(
        self,
        max_length: int,
        *,
        min_length: int = 1,
        charset: frozenset[str] | str = alphanumeric,
        seed: int | np.random.Generator | None = None,
    ) -> None:
        """Build the space; a set charset is sorted so sampling is independent of hash order."""
        if not np.issubdtype(type(min_length), np.integer):
            raise TypeError(
                f"Expects the min_length to be an integer, actual type: {type(min_length)}"
            )
        if not np.issubdtype(type(max_length), np.integer):
            raise TypeError(
                f"Expects the max_length to be an integer, actual type: {type(max_length)}"
            )
        if min_length < 0:
            raise ValueError(
                f"Minimum text length must be non-negative, actual value: {min_length}"
            )
        if min_length > max_length:
            raise ValueError(
                "The min_length must be less than or equal to the max_length, "
                f"min_length: {min_length}, max_length: {max_length}"
            )
        if max_length >= np.iinfo(np.int64).max:  # sample draws lengths as int64
            raise ValueError(f"Text max_length must fit int64, actual value: {max_length}")
        self.min_length = int(min_length)
        self.max_length = int(max_length)

        if isinstance(charset, (set, frozenset)):
            char_list = sorted(charset)
        else:
            char_list = list(dict.fromkeys(charset))  # keep order, drop duplicates
        if not char_list:
            # Gymnasium accepts an empty charset and then fails when sampling.
            raise ValueError("Text charset must contain at least one character, actual: empty")
        invalid = [char for char in char_list if len(char) != 1]
        if invalid:
            # A multi-character element would make samples longer than max_length.
            raise ValueError(
                "Expects all charset elements to be a single character, actual invalid "
                f"elements: {invalid}"
            )
        self._char_set = frozenset(char_list)
        self._char_list = tuple(char_list)
        self._char_index = {char: np.int32(i) for i, char in enumerate(char_list)}
        self._char_str = "".join(sorted(char_list))
        super().__init__(dtype=str, seed=seed)

    def sample(
        self, mask: LengthAndMask | None = None, probability: LengthAndMask | None = None
    ) -> str:
        """Draw a length, then characters; ``mask``/``probability`` is ``(length, char_mask)``.

        An all-zero character mask gives ``""`` if ``min_length == 0`` and raises otherwise.
        """
        length: int | None
        char_p: npt.NDArray[Any] | None
        if mask is not None and probability is not None:
            raise ValueError(
                "Only one of `mask` or `probability` can be provided, "
                f"actual values: mask={mask}, probability={probability}"
            )
        if mask is not None:
            length, char_p = self._validate(mask, np.int8, "mask", InvalidMask)
            if char_p is not None:
                if not ((char_p == 0) | (char_p == 1)).all():
                    raise InvalidMask(f"Expects all mask values to 0 or 1, actual values: {char_p}")
                if char_p.sum() > 0:
                    char_p = char_p / char_p.sum()
        elif probability is not None:
            length, char_p = self._validate(
                probability, np.float64, "probability", InvalidProbabilityMask
            )
            if char_p is not None:
                if not ((char_p >= 0) & (char_p <= 1)).all():
                    raise InvalidProbabilityMask(
                        "Expects all probability mask values to be within 0 and 1, "
                        f"actual values: {char_p}"
                    )
                if not np.isclose(char_p.sum(), 1):
                    raise InvalidProbabilityMask(
                        "Expects the sum of the probability mask to be 1, "
                        f"actual sum: {char_p.sum()}"
                    )
        else:
            length = char_p = None

        if length is None:
            length = int(self.np_random.integers(self.min_length, self.max_length + 1))
        if char_p is None:
            char_p = np.ones(len(self._char_list)) / len(self._char_list)
        if not char_p.any():
            if self.min_length == 0:
                return ""
            raise ValueError(
                "Trying to sample with a minimum length > 0 (actual minimum length="
                f"{self.min_length}) but the character mask is all zero meaning that no "
                "character could be sampled."
            )
        return "".join(self.np_random.choice(self._char_list, size=length, p=char_p))

    def _validate(
        self, mask: Any, dtype: type, name: str, exc: type[Exception]
    ) -> tuple[int | None, npt.NDArray[Any] | None]:
        if not isinstance(mask, tuple):
            raise exc(f"Expects the `{name}` type to be a tuple, actual type: {type(mask)}")
        if len(mask) != 2:
            raise exc(f"Expects the `{name}` length to be two, actual length: {len(mask)}")
        length, char_mask = mask
        if length is not None:
            if not np.issubdtype(type(length), np.integer):
                raise exc(
                    f"Expects the Text sample length to be an integer, actual type: {type(length)}"
                )
            if not self.min_length <= length <= self.max_length:
                raise exc(
                    f"Expects the Text sample length be between {self.min_length} and "
                    f"{self.max_length}, actual length: {length}"
                )
        if char_mask is not None:
            if not isinstance(char_mask, np.ndarray):
                raise exc(
                    f"Expects the Text sample `{name}` to be an np.ndarray, "
                    f"actual type: {type(char_mask)}"
                )
            if char_mask.dtype != dtype:
                raise exc(
                    f"Expects the Text sample `{name}` to be type {dtype}, "
                    f"actual dtype: {char_mask.dtype}"
                )
            if char_mask.shape != (len(self._char_list),):
                raise exc(
                    f"expects the Text sample `{name}` to be {(len(self._char_list),)}, "
                    f"actual shape: {char_mask.shape}"
                )
        return length, char_mask

    def contains(self, x: Any) -> bool:
        """Whether ``x`` is a string of valid length made only of charset characters."""
        return (
            isinstance(x, str)
            and self.min_length <= len(x) <= self.max_length
            and all(c in self._char_set for c in x)
        )

    def __repr__(self) -> str:
        return f"Text({self.min_length}, {self.max_length}, charset={self.characters})"

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, Text)
            and self.min_length == other.min_length
            and self.max_length == other.max_length
            and self._char_set == other._char_set
        )

    @property
    def character_set(self) -> frozenset[str]:
        """The allowed characters."""
        return self._char_set

    @property
    def character_list(self) -> tuple[str, ...]:
        """The allowed characters in sampling (and flattening) order."""
        return self._char_list

    def character_index(self, char: str) -> np.int32:
        """The index of ``char`` in :attr:`character_list`."""
        return self._char_index[char]

    @property
    def characters(self) -> str:
        """All allowed characters, sorted, as one string."""
        return self._char_str

    @property
    def is_np_flattenable(self) -> bool:
        """Flattens to one int per character, padded to ``max_length``."""
        return True
