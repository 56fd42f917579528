"""The `Space` base class: shape, dtype, a lazily seeded generator, and the sampling contract."""

from __future__ import annotations

import functools
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Generic, TypeVar

import numpy as np
import numpy.typing as npt

from palaestra import error
from palaestra.utils import seeding

T_co = TypeVar("T_co", covariant=True)

MaskNDArray = npt.NDArray[np.int8]


class Space(Generic[T_co]):
    """The set of valid actions or observations of an environment.

    Subclasses define ``sample``, ``contains`` and ``is_np_flattenable``; composite spaces also
    override ``seed`` so that one integer seeds every subspace the way Gymnasium does.
    """

    dtype: np.dtype | None
    _shape: tuple[int, ...] | None
    _np_random: np.random.Generator | None

    def __init__(
        self,
        shape: Sequence[int] | None = None,
        dtype: npt.DTypeLike | None = None,
        seed: int | np.random.Generator | None = None,
    ) -> None:
        """Store shape and dtype; ``seed`` is an int or a ready ``np.random.Generator``."""
        self._shape = None if shape is None else tuple(shape)
        self.dtype = None if dtype is None else np.dtype(dtype)
        self._np_random = None
        if seed is not None:
            if isinstance(seed, np.random.Generator):
                self._np_random = seed
            else:
                self.seed(seed)

    @property
    def np_random(self) -> np.random.Generator:
        """The space's generator, created from fresh entropy on first use (seeding is costly)."""
        if self._np_random is None:
            self.seed()
            # Composite spaces seed only their children, so fall back to a fresh generator.
            if self._np_random is None:
                self._np_random, _ = seeding.np_random()
        return self._np_random

    @np_random.setter
    def np_random(self, value: np.random.Generator) -> None:
        self._np_random = value

    @property
    def shape(self) -> tuple[int, ...] | None:
        """The shape of the space's elements, or ``None`` if they are not fixed-shape arrays."""
        return self._shape

    @property
    def is_np_flattenable(self) -> bool:
        """Whether elements can be flattened into a fixed-size ``Box``."""
        raise NotImplementedError

    def sample(self, mask: Any | None = None, probability: Any | None = None) -> T_co:
        """Draw a random element, restricted by ``mask`` or weighted by ``probability``."""
        raise NotImplementedError

    def seed(self, seed: Any | None = None) -> Any:
        """Seed this space's generator (and its subspaces'); return the seed(s) used."""
        self._np_random, np_random_seed = seeding.np_random(seed)
        return np_random_seed

    def contains(self, x: Any) -> bool:
        """Whether ``x`` is an element of this space (same as ``x in space``)."""
        raise NotImplementedError

    def __contains__(self, x: Any) -> bool:
        return self.contains(x)

    def __setstate__(self, state: Iterable[tuple[str, Any]] | Mapping[str, Any]) -> None:
        """Restore a pickled space, accepting the attribute names of old gym pickles."""
        state = dict(state)  # never mutate the caller's state
        # openai/gym#2397 renamed `shape` to `_shape`; openai/gym#1913 `np_random` to `_np_random`.
        if "shape" in state:
            state["_shape"] = state.pop("shape")
        if "np_random" in state:
            state["_np_random"] = state.pop("np_random")
        self.__dict__.update(state)

    def to_jsonable(self, sample_n: Iterable[Any]) -> list[Any] | Any:
        """Convert a batch of samples to JSON-serialisable data (identity by default)."""
        return list(sample_n)

    def from_jsonable(self, sample_n: Any) -> list[Any]:
        """Convert JSON data from ``to_jsonable`` back to a batch of samples."""
        return sample_n


def require_spaces(spaces: Any) -> tuple[Space[Any], ...]:
    """``spaces`` as a tuple, each checked to be a :class:`Space` (Gymnasium's message)."""
    spaces = tuple(spaces)
    for space in spaces:
        if not isinstance(space, Space):
            raise TypeError(
                f"{space} does not inherit from `palaestra.spaces.Space`. "
                f"Actual Type: {type(space)}"
            )
    return spaces


@functools.lru_cache(maxsize=256)
def can_cast(from_dtype: np.dtype, to_dtype: np.dtype) -> bool:
    """``np.can_cast`` for dtypes, memoised: ``contains`` runs on every step."""
    return bool(np.can_cast(from_dtype, to_dtype))


class InvalidMask(error.Error, AssertionError):
    """A ``sample()`` argument (a mask, a length, a node count) has a wrong type, shape or value.

    Gymnasium checks masks with ``assert``; subclassing ``AssertionError`` keeps code that
    catches that working, while the check itself survives ``python -O``.
    """


class InvalidProbabilityMask(error.InvalidProbability, AssertionError):
    """A ``sample(probability=...)`` argument is not a valid distribution for the space."""


def foreign_space_hint(space: Any) -> str:
    """A sentence naming the adapter when ``space`` is another library's space, else "".

    Gymnasium's spaces look like ours but are other classes: the helpers dispatching on
    palaestra's types cannot take them, and the fix is one call.
    """
    module = type(space).__module__ or ""
    if module.split(".")[0] in ("gymnasium", "gym"):
        return (
            " It is a Gymnasium space: convert it with "
            "`palaestra.compat.from_gymnasium_space(space)` (or wrap the env with "
            "`palaestra.compat.from_gymnasium(env)`)."
        )
    return ""
