"""`Dict`: a product of named spaces; elements are dicts with the same keys."""

from __future__ import annotations

import collections.abc
import typing
from collections import OrderedDict
from collections.abc import Iterable, Iterator, KeysView
from typing import Any

import numpy as np

from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space


class Dict(Space[dict[str, Any]], typing.Mapping[str, Space[Any]]):
    """A dictionary of spaces, sampled independently.

    Keys of a plain mapping are sorted (Gymnasium keeps this for flattening order);
    an ``OrderedDict``, a sequence of pairs or ``sort_keys=False`` keeps the given order.

    >>> from palaestra.spaces import Box, Discrete
    >>> space = Dict({"position": Box(-1, 1, shape=(2,)), "color": Discrete(3)}, seed=42)
    >>> space
    Dict('color': Discrete(3), 'position': Box(-1.0, 1.0, (2,), float32))
    >>> space.sample()
    {'color': np.int64(0), 'position': array([-0.3991573 ,  0.21649833], dtype=float32)}
    """

    spaces: dict[str, Space[Any]]
    sort_keys: bool

    def __init__(
        self,
        spaces: typing.Mapping[str, Space[Any]]
        | typing.Sequence[tuple[str, Space[Any]]]
        | None = None,
        seed: dict[str, Any] | int | np.random.Generator | None = None,
        *,
        sort_keys: bool = True,
        **spaces_kwargs: Space[Any],
    ) -> None:
        """Build from a mapping, a sequence of ``(key, space)`` pairs and/or keyword spaces."""
        self.sort_keys = sort_keys
        if isinstance(spaces, OrderedDict):
            spaces_dict = dict(spaces.items())
        elif isinstance(spaces, collections.abc.Mapping):
            spaces_dict = dict(spaces.items())
            if sort_keys:
                try:
                    spaces_dict = dict(sorted(spaces_dict.items()))
                except TypeError:
                    pass  # keys that cannot be compared keep their insertion order
        elif isinstance(spaces, collections.abc.Sequence) and not isinstance(spaces, (str, bytes)):
            # dict() would also unpack two-character strings ("ab" -> key "a", space "b").
            if not all(isinstance(pair, (tuple, list)) and len(pair) == 2 for pair in spaces):
                raise TypeError(
                    "Unexpected Dict space input, expecting a sequence of (key, space) pairs, "
                    f"actual value: {spaces!r}"
                )
            spaces_dict = dict(spaces)
        elif spaces is None:
            spaces_dict = {}
        else:
            raise TypeError(
                "Unexpected Dict space input, expecting dict, OrderedDict or Sequence, "
                f"actual type: {type(spaces)}"
            )
        for key, space in spaces_kwargs.items():
            if key in spaces_dict:
                raise ValueError(
                    f"Dict space keyword '{key}' already exists in the spaces dictionary."
                )
            spaces_dict[key] = space
        for key, space in spaces_dict.items():
            if not isinstance(space, Space):
                raise TypeError(
                    f"Dict space element is not an instance of Space: key='{key}', space={space!r}"
                )
        self.spaces = spaces_dict
        super().__init__(None, None, seed)  # type: ignore[arg-type]

    @property
    def is_np_flattenable(self) -> bool:
        """Whether every subspace is flattenable."""
        return all(space.is_np_flattenable for space in self.spaces.values())

    def seed(self, seed: int | dict[str, Any] | None = None) -> dict[str, Any]:
        """Seed the subspaces: ``None`` randomly, an int via derived seeds, a dict per key.

        >>> from palaestra.spaces import Discrete
        >>> Dict(a=Discrete(2), b=Discrete(3)).seed(42)
        {'a': 191664963, 'b': 1662057957}
        """
        if seed is None:
            return {key: space.seed(None) for key, space in self.spaces.items()}
        if isinstance(seed, int):
            super().seed(seed)
            subseeds = self.np_random.integers(np.iinfo(np.int32).max, size=len(self.spaces))
            return {
                key: space.seed(int(subseed))
                for (key, space), subseed in zip(self.spaces.items(), subseeds)
            }
        if isinstance(seed, dict):
            if seed.keys() != self.spaces.keys():
                raise ValueError(
                    f"The seed keys: {seed.keys()} are not identical to space keys: "
                    f"{self.spaces.keys()}"
                )
            return {key: self.spaces[key].seed(seed[key]) for key in seed}
        raise TypeError(f"Expected seed type: dict, int or None, actual type: {type(seed)}")

    def sample(
        self, mask: dict[str, Any] | None = None, probability: dict[str, Any] | None = None
    ) -> dict[str, Any]:
        """Sample each subspace, passing it the matching entry of ``mask`` or ``probability``."""
        if mask is not None and probability is not None:
            raise ValueError(
                "Only one of `mask` or `probability` can be provided, "
                f"actual values: mask={mask}, probability={probability}"
            )
        if mask is not None:
            self._check_masks(mask, "sample mask", InvalidMask)
            return {k: space.sample(mask=mask[k]) for k, space in self.spaces.items()}
        if probability is not None:
            self._check_masks(probability, "sample probability mask", InvalidProbabilityMask)
            return {k: space.sample(probability=probability[k]) for k, space in self.spaces.items()}
        return {k: space.sample() for k, space in self.spaces.items()}

    def _check_masks(self, masks: Any, name: str, exc: type[Exception]) -> None:
        if not isinstance(masks, dict):
            raise exc(f"Expected {name} to be a dict, actual type: {type(masks)}")
        if masks.keys() != self.spaces.keys():
            raise exc(
                f"Expected {name} keys to be same as space keys, mask keys: {masks.keys()}, "
                f"space keys: {self.spaces.keys()}"
            )

    def contains(self, x: Any) -> bool:
        """Whether ``x`` is a dict with exactly the space's keys and valid values."""
        if isinstance(x, dict) and x.keys() == self.spaces.keys():
            return all(self.spaces[key].contains(x[key]) for key in self.spaces)
        return False

    def __getitem__(self, key: str) -> Space[Any]:
        return self.spaces[key]

    def __setitem__(self, key: str, value: Space[Any]) -> None:
        if not isinstance(value, Space):
            raise TypeError(
                f"Trying to set {key} to Dict space with value that is not a palaestra space, "
                f"actual type: {type(value)}"
            )
        self.spaces[key] = value

    def keys(self) -> KeysView[str]:
        """The subspace names, in order."""
        return KeysView(self.spaces)

    def __iter__(self) -> Iterator[str]:
        yield from self.spaces

    def __len__(self) -> int:
        return len(self.spaces)

    def __repr__(self) -> str:
        return "Dict(" + ", ".join(f"{k!r}: {s}" for k, s in self.spaces.items()) + ")"

    def __eq__(self, other: object) -> bool:
        # Plain dict equality ignores order, matching Gymnasium's comparison.
        return isinstance(other, Dict) and self.spaces == other.spaces

    def to_jsonable(self, sample_n: Iterable[dict[str, Any]]) -> dict[str, list[Any]]:
        """One JSON list per key (column-wise), as Gymnasium stores it."""
        samples = list(sample_n)
        return {
            key: space.to_jsonable([sample[key] for sample in samples])
            for key, space in self.spaces.items()
        }

    def from_jsonable(self, sample_n: dict[str, list[Any]]) -> list[dict[str, Any]]:
        """Columns from ``to_jsonable`` back to a list of dicts."""
        columns = {key: space.from_jsonable(sample_n[key]) for key, space in self.spaces.items()}
        n_elements = len(next(iter(columns.values()))) if columns else 0
        return [{key: column[i] for key, column in columns.items()} for i in range(n_elements)]
