"""`Sequence`: finite sequences (of any length) of elements of one feature space."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any, Literal

import numpy as np

from palaestra.error import CustomSpaceError
from palaestra.spaces.batched_samples import concatenate, create_empty_array, iterate
from palaestra.spaces.batching import _differing_as_tuple, batch_differing_spaces, batch_space
from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space


class Sequence(Space[Any]):
    """Tuples ``(a_0, ..., a_k)`` of elements of ``space``; ``stack=True`` stacks them instead.

    >>> from palaestra.spaces import Box
    >>> [float(x[0]) for x in Sequence(Box(0, 1), seed=0).sample()]
    [0.6822636127471924, 0.18933342397212982, 0.19049619138240814]
    >>> Sequence(Box(0, 1), stack=True)
    Sequence(Box(0.0, 1.0, (1,), float32), stack=True)
    """

    feature_space: Space[Any]
    stack: bool

    def __init__(
        self,
        space: Space[Any],
        seed: int | np.random.Generator | None = None,
        stack: bool = False,
    ) -> None:
        """Build sequences of ``space`` elements; ``stack`` returns them as one batch."""
        if not isinstance(space, Space):
            raise TypeError(
                "Expects the feature space to be instance of a palaestra Space, "
                f"actual type: {type(space)}"
            )
        self.feature_space = space
        self.stack = stack
        if self.stack:
            self.stacked_feature_space = batch_space(self.feature_space, 1)
        super().__init__(None, None, seed)

    def seed(self, seed: int | tuple[int, int] | list[int] | None = None) -> tuple[Any, Any]:
        """Seed this space (sequence lengths) and the feature space; return both seeds."""
        if seed is None:
            return super().seed(None), self.feature_space.seed(None)
        if isinstance(seed, int):
            super_seed = super().seed(seed)
            feature_seed = int(self.np_random.integers(np.iinfo(np.int32).max))
            # Re-seed so that int and tuple seeding leave this space in the same state.
            super().seed(seed)
            return super_seed, self.feature_space.seed(feature_seed)
        if isinstance(seed, (tuple, list)):
            if len(seed) != 2:
                raise ValueError(
                    "Expects the seed to have two elements for the Sequence and feature space, "
                    f"actual length: {len(seed)}"
                )
            return super().seed(seed[0]), self.feature_space.seed(seed[1])
        raise TypeError(f"Expected None, int, tuple of ints, actual type: {type(seed)}")

    @property
    def is_np_flattenable(self) -> Literal[False]:
        """Variable length: cannot be flattened to a fixed-size Box."""
        return False

    def sample(
        self, mask: tuple[Any, Any] | None = None, probability: tuple[Any, Any] | None = None
    ) -> Any:
        """Draw a length (geometric(0.25) unless fixed by the mask), then that many features.

        ``mask``/``probability`` is ``(length_mask, feature_mask)``: the length is ``None``
        (random), an int, or an array of allowed lengths; ``feature_mask`` goes to the feature
        space's ``sample``.
        """
        if mask is not None and probability is not None:
            raise ValueError(
                "Only one of `mask` or `probability` can be provided, "
                f"actual values: mask={mask}, probability={probability}"
            )
        if mask is not None:
            length = self.generate_sample_length(mask[0], "mask")
            values = tuple(self.feature_space.sample(mask=mask[1]) for _ in range(length))
        elif probability is not None:
            length = self.generate_sample_length(probability[0], "probability")
            values = tuple(
                self.feature_space.sample(probability=probability[1]) for _ in range(length)
            )
        else:
            length = self.np_random.geometric(0.25)
            values = tuple(self.feature_space.sample() for _ in range(length))
        if self.stack:
            out = create_empty_array(self.feature_space, len(values))
            return concatenate(self.feature_space, values, out)
        return values

    def generate_sample_length(self, length_mask: Any, mask_type: str | None) -> int:
        """The length of a sample for a given length mask (see :meth:`sample`)."""
        exc = InvalidMask if mask_type == "mask" else InvalidProbabilityMask
        if length_mask is None:
            return int(self.np_random.geometric(0.25))
        if np.issubdtype(type(length_mask), np.integer):
            if length_mask < 0:
                raise exc(
                    f"Expects the length mask of `{mask_type}` to be greater than or equal to "
                    f"zero, actual value: {length_mask}"
                )
            return int(length_mask)
        if isinstance(length_mask, np.ndarray):
            if length_mask.ndim != 1:
                raise exc(
                    f"Expects the shape of the length mask of `{mask_type}` to be "
                    f"1-dimensional, actual shape: {length_mask.shape}"
                )
            if not (length_mask >= 0).all():
                raise exc(
                    f"Expects all values in the length_mask of `{mask_type}` to be greater than "
                    f"or equal to zero, actual values: {length_mask}"
                )
            if not np.issubdtype(length_mask.dtype, np.integer):
                raise exc(
                    f"Expects the length mask array of `{mask_type}` to have dtype of "
                    f"np.integer, actual type: {length_mask.dtype}"
                )
            return int(self.np_random.choice(length_mask))
        raise TypeError(
            f"Expects the type of length_mask of `{mask_type}` to be an integer or a np.ndarray, "
            f"actual type: {type(length_mask)}"
        )

    def contains(self, x: Any) -> bool:
        """Whether ``x`` is a tuple (or, stacked, a batch) of feature-space elements."""
        if self.stack:
            # Gymnasium raises TypeError for non-iterables; "not a member" is the useful answer.
            try:
                return all(
                    item in self.feature_space for item in iterate(self.stacked_feature_space, x)
                )
            except (TypeError, CustomSpaceError):  # iterate's "could not iterate through ..."
                return False
        return isinstance(x, tuple) and all(self.feature_space.contains(item) for item in x)

    def __repr__(self) -> str:
        return f"Sequence({self.feature_space}, stack={self.stack})"

    def to_jsonable(self, sample_n: Iterable[Any]) -> list[Any]:
        """Each sample as the feature space's JSON list."""
        if self.stack:
            return self.stacked_feature_space.to_jsonable(sample_n)
        return [self.feature_space.to_jsonable(sample) for sample in sample_n]

    def from_jsonable(self, sample_n: list[Any]) -> list[Any]:
        """JSON lists back to tuples (or stacked batches)."""
        if self.stack:
            return self.stacked_feature_space.from_jsonable(sample_n)
        return [tuple(self.feature_space.from_jsonable(sample)) for sample in sample_n]

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, Sequence)
            and self.feature_space == other.feature_space
            and self.stack == other.stack
        )


@create_empty_array.register(Sequence)
def _empty_sequence(
    space: Sequence, n: int = 1, fn: Callable[..., Any] = np.zeros
) -> tuple[Any, ...]:
    if space.stack:
        return tuple(create_empty_array(space.feature_space, n=1, fn=fn) for _ in range(n))
    return tuple(() for _ in range(n))


batch_differing_spaces.register(Sequence)(_differing_as_tuple)
