"""Batched spaces and batched samples for vector environments.

``batch_space`` turns the space of one env into the space of ``n`` stacked envs;
``concatenate`` stacks ``n`` samples into one batch (into ``create_empty_array``'s buffer) and
``iterate`` walks a batch back out. Semantics (and seeding of batched spaces) are those of
``gymnasium.vector.utils``; every function dispatches on the space type with
``functools.singledispatch``, so a custom space can register its own implementation.
"""

from __future__ import annotations

from collections.abc import Callable
from collections.abc import Sequence as PySequence
from copy import deepcopy
from functools import singledispatch
from typing import Any

import numpy as np

from palaestra.spaces.batched_samples import concatenate, create_empty_array, iterate
from palaestra.spaces.box import Box
from palaestra.spaces.dict import Dict
from palaestra.spaces.discrete import Discrete
from palaestra.spaces.multi_binary import MultiBinary
from palaestra.spaces.multi_discrete import MultiDiscrete
from palaestra.spaces.oneof import OneOf
from palaestra.spaces.space import Space, foreign_space_hint
from palaestra.spaces.text import Text
from palaestra.spaces.tuple import Tuple

__all__ = ["batch_differing_spaces", "batch_space", "concatenate", "create_empty_array", "iterate"]


@singledispatch
def batch_space(space: Space[Any], n: int = 1) -> Space[Any]:
    """The space of ``n`` stacked elements of ``space``; it continues ``space``'s random stream.

    >>> batch_space(Box(0, 1, shape=(3,)), n=5)
    Box(0.0, 1.0, (5, 3), float32)
    >>> batch_space(Discrete(3), n=2)
    MultiDiscrete([3 3])
    """
    raise TypeError(
        "The space provided to `batch_space` is not a palaestra Space instance, "
        f"type: {type(space)}, {space}" + foreign_space_hint(space)
    )


@batch_space.register(Box)
def _batch_box(space: Box, n: int = 1) -> Box:
    repeats = (n,) + (1,) * space.low.ndim
    low, high = np.tile(space.low, repeats), np.tile(space.high, repeats)
    return Box(low=low, high=high, dtype=space.dtype, seed=deepcopy(space.np_random))


@batch_space.register(Discrete)
def _batch_discrete(space: Discrete, n: int = 1) -> MultiDiscrete:
    return MultiDiscrete(
        np.full((n,), space.n, dtype=space.dtype),
        dtype=space.dtype,
        seed=deepcopy(space.np_random),
        start=np.full((n,), space.start, dtype=space.dtype),
    )


@batch_space.register(MultiDiscrete)
def _batch_multi_discrete(space: MultiDiscrete, n: int = 1) -> Box:
    repeats = (n,) + (1,) * space.nvec.ndim
    low = np.tile(space.start, repeats)
    high = low + np.tile(space.nvec, repeats) - 1
    return Box(low=low, high=high, dtype=space.dtype, seed=deepcopy(space.np_random))


@batch_space.register(MultiBinary)
def _batch_multi_binary(space: MultiBinary, n: int = 1) -> Box:
    shape = (n, *space.shape)
    return Box(low=0, high=1, shape=shape, dtype=space.dtype, seed=deepcopy(space.np_random))


@batch_space.register(Tuple)
def _batch_tuple(space: Tuple, n: int = 1) -> Tuple:
    subspaces = tuple(batch_space(subspace, n=n) for subspace in space.spaces)
    return Tuple(subspaces, seed=deepcopy(space.np_random))


@batch_space.register(Dict)
def _batch_dict(space: Dict, n: int = 1) -> Dict:
    return Dict(
        {key: batch_space(subspace, n=n) for key, subspace in space.items()},
        seed=deepcopy(space.np_random),
        sort_keys=space.sort_keys,
    )


@batch_space.register(Space)
def _batch_as_tuple(space: Space[Any], n: int = 1) -> Tuple:
    # Variable-size spaces (Text, Sequence, Graph, OneOf, custom) cannot be stacked into one
    # array, so the batch is a Tuple of copies, each re-seeded from the space's stream.
    batched = Tuple(tuple(deepcopy(space) for _ in range(n)), seed=deepcopy(space.np_random))
    new_seeds = [int(s) for s in deepcopy(space.np_random).integers(0, int(1e8), n)]
    batched.seed(new_seeds)
    return batched


@singledispatch
def batch_differing_spaces(spaces: Any) -> Space[Any]:
    """Batch spaces of one type whose parameters differ (e.g. bounds), sharing shape and dtype.

    >>> batch_differing_spaces([Discrete(3), Discrete(5), Discrete(4)])
    MultiDiscrete([3 5 4])
    """
    if len(spaces) == 0:
        raise ValueError("Expects a non-empty list of spaces")
    first_type = type(spaces[0])
    if not all(isinstance(space, first_type) for space in spaces):
        raise TypeError(
            "Expects all spaces to be of the same type, "
            f"actual types: {[type(space) for space in spaces]}"
        )
    if first_type not in batch_differing_spaces.registry:
        raise TypeError(
            "Requires the Space type to have a registered `batch_differing_space`, "
            f"current list: {batch_differing_spaces.registry}"
        )
    return batch_differing_spaces.dispatch(first_type)(spaces)


def _require_same(spaces: PySequence[Any], attr: Callable[[Any], Any], message: str) -> None:
    values = [attr(space) for space in spaces]
    if not all(value == values[0] for value in values):
        raise ValueError(f"{message}, actually {values}")


@batch_differing_spaces.register(Box)
def _differing_box(spaces: PySequence[Box]) -> Box:
    _require_same(spaces, lambda s: s.dtype, "Expected all dtypes to be equal")
    _require_same(spaces, lambda s: s.low.shape, "Expected all Box.low shape to be equal")
    _require_same(spaces, lambda s: s.high.shape, "Expected all Box.high shape to be equal")
    return Box(
        low=np.array([space.low for space in spaces]),
        high=np.array([space.high for space in spaces]),
        dtype=spaces[0].dtype,
        seed=deepcopy(spaces[0].np_random),
    )


@batch_differing_spaces.register(Discrete)
def _differing_discrete(spaces: PySequence[Discrete]) -> MultiDiscrete:
    largest = max((space.dtype for space in spaces), key=lambda dtype: dtype.itemsize)
    return MultiDiscrete(
        nvec=np.array([space.n for space in spaces]),
        dtype=largest,
        start=np.array([space.start for space in spaces]),
        seed=deepcopy(spaces[0].np_random),
    )


@batch_differing_spaces.register(MultiDiscrete)
def _differing_multi_discrete(spaces: PySequence[MultiDiscrete]) -> Box:
    _require_same(spaces, lambda s: s.dtype, "Expected all dtypes to be equal")
    _require_same(spaces, lambda s: s.nvec.shape, "Expects all MultiDiscrete.nvec shape")
    _require_same(spaces, lambda s: s.start.shape, "Expects all MultiDiscrete.start shape")
    return Box(
        low=np.array([space.start for space in spaces]),
        high=np.array([space.start + space.nvec for space in spaces]) - 1,
        dtype=spaces[0].dtype,
        seed=deepcopy(spaces[0].np_random),
    )


@batch_differing_spaces.register(MultiBinary)
def _differing_multi_binary(spaces: PySequence[MultiBinary]) -> Box:
    _require_same(spaces, lambda s: s.shape, "Expected all MultiBinary shapes to be equal")
    return Box(
        low=0,
        high=1,
        shape=(len(spaces), *spaces[0].shape),
        dtype=spaces[0].dtype,
        seed=deepcopy(spaces[0].np_random),
    )


@batch_differing_spaces.register(Tuple)
def _differing_tuple(spaces: PySequence[Tuple]) -> Tuple:
    columns = zip(*[space.spaces for space in spaces], strict=True)
    return Tuple(
        tuple(batch_differing_spaces(column) for column in columns),
        seed=deepcopy(spaces[0].np_random),
    )


@batch_differing_spaces.register(Dict)
def _differing_dict(spaces: PySequence[Dict]) -> Dict:
    if not all(spaces[0].keys() == space.keys() for space in spaces):
        raise ValueError(
            "Expected all Dict spaces to have the same keys, "
            f"actually {[list(space.keys()) for space in spaces]}"
        )
    return Dict(
        {key: batch_differing_spaces([space[key] for space in spaces]) for key in spaces[0]},
        seed=deepcopy(spaces[0].np_random),
        sort_keys=spaces[0].sort_keys,
    )


# Graph and Sequence register this too, in their own modules (they are built on batch_space).
@batch_differing_spaces.register(Text)
@batch_differing_spaces.register(OneOf)
def _differing_as_tuple(spaces: PySequence[Space[Any]]) -> Tuple:
    return Tuple([deepcopy(space) for space in spaces], seed=deepcopy(spaces[0].np_random))
