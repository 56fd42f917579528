"""Batches of samples: buffers (``create_empty_array``), stacking and iterating.

``create_empty_array`` makes a buffer for ``n`` elements of a space, ``concatenate`` stacks
elements into it and ``iterate`` walks a batch (an element of the batched space) back out.

Semantics are those of ``gymnasium.vector.utils``; import them from
``palaestra.spaces.batching``, which also holds the batched spaces themselves. ``Graph`` and
``Sequence`` register their own handlers (they are built on these functions).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from functools import singledispatch
from typing import Any

import numpy as np

from palaestra.error import CustomSpaceError
from palaestra.spaces.box import Box
from palaestra.spaces.dict import Dict
from palaestra.spaces.discrete import Discrete
from palaestra.spaces.multi_binary import MultiBinary
from palaestra.spaces.multi_discrete import MultiDiscrete
from palaestra.spaces.oneof import OneOf
from palaestra.spaces.space import Space, foreign_space_hint
from palaestra.spaces.text import Text
from palaestra.spaces.tuple import Tuple

__all__ = ["concatenate", "create_empty_array", "iterate"]


@singledispatch
def iterate(space: Space[Any], items: Any) -> Iterator[Any]:
    """Iterate over the elements of a batch from the batched ``space``.

    >>> space = MultiDiscrete([3, 3])  # batch_space(Discrete(3), n=2)
    >>> [int(x) for x in iterate(space, np.array([2, 0]))]
    [2, 0]
    """
    if isinstance(space, Space):
        raise CustomSpaceError(
            f"Space of type `{type(space)}` doesn't have an registered `iterate` function. "
            f"Register `{type(space)}` for `iterate` to support it."
        )
    raise TypeError(
        "The space provided to `iterate` is not a palaestra Space instance, "
        f"type: {type(space)}, {space}" + foreign_space_hint(space)
    )


@iterate.register(Discrete)
def _iterate_discrete(space: Discrete, items: Any) -> Iterator[Any]:
    raise TypeError("Unable to iterate over a space of type `Discrete`.")


@iterate.register(Box)
@iterate.register(MultiDiscrete)
@iterate.register(MultiBinary)
def _iterate_array(space: Space[Any], items: np.ndarray) -> Iterator[Any]:
    try:
        return iter(items)
    except TypeError as e:
        raise TypeError(f"Unable to iterate over the following elements: {items}") from e


@iterate.register(Tuple)
def _iterate_tuple(space: Tuple, items: tuple[Any, ...]) -> Iterator[Any]:
    if all(type(subspace) in iterate.registry for subspace in space):
        return zip(*[iterate(sub, items[i]) for i, sub in enumerate(space)], strict=True)
    # A batch of variable-size spaces is already a tuple of elements.
    try:
        return iter(items)
    except Exception as e:
        unregistered = [type(sub) for sub in space if type(sub) not in iterate.registry]
        raise CustomSpaceError(
            f"Could not iterate through {space} as no custom iterate function is registered "
            f"for {unregistered} and `iter(items)` raised the following error: {e}."
        ) from e


@iterate.register(Dict)
def _iterate_dict(space: Dict, items: Mapping[str, Any]) -> Iterator[dict[str, Any]]:
    keys = list(space.spaces)
    columns = [iterate(space.spaces[key], items[key]) for key in keys]
    for values in zip(*columns, strict=True):
        yield dict(zip(keys, values))


@singledispatch
def concatenate(space: Space[Any], items: Iterable[Any], out: Any) -> Any:
    """Stack ``items`` (elements of ``space``) into ``out``, usually from ``create_empty_array``.

    >>> space = Box(0, 1, shape=(2,))
    >>> out = create_empty_array(space, n=2)
    >>> concatenate(space, [np.zeros(2, np.float32), np.ones(2, np.float32)], out)
    array([[0., 0.],
           [1., 1.]], dtype=float32)
    """
    raise TypeError(
        "The space provided to `concatenate` is not a palaestra Space instance, "
        f"type: {type(space)}, {space}" + foreign_space_hint(space)
    )


@concatenate.register(Box)
@concatenate.register(Discrete)
@concatenate.register(MultiDiscrete)
@concatenate.register(MultiBinary)
def concatenate_array(space: Space[Any], items: Iterable[Any], out: np.ndarray) -> np.ndarray:
    """``concatenate`` for the spaces whose batch is one array (Box, Discrete, MultiDiscrete,
    MultiBinary), callable without the dispatch (engines that step every row per call)."""
    items = list(items)
    if (
        len(items) == 1
        and out.ndim > 1
        and type(items[0]) is np.ndarray
        and items[0].shape == out.shape[1:]
    ):  # one env's observation every step (DQN, SAC): np.stack's casting and errors, ~5x cheaper
        if items[0].dtype == out.dtype:
            out[0] = items[0]  # a plain copy: no cast to check (np.copyto's keywords cost ~1 µs)
        else:
            np.copyto(out[0], items[0], casting="same_kind")
        return out
    return np.stack(items, axis=0, out=out)


@concatenate.register(Tuple)
def _concatenate_tuple(space: Tuple, items: Iterable[Any], out: tuple[Any, ...]) -> tuple[Any, ...]:
    items = list(items)
    return tuple(
        concatenate(subspace, [item[i] for item in items], out[i])
        for i, subspace in enumerate(space.spaces)
    )


@concatenate.register(Dict)
def _concatenate_dict(space: Dict, items: Iterable[Any], out: Mapping[str, Any]) -> dict[str, Any]:
    items = list(items)
    return {
        key: concatenate(subspace, [item[key] for item in items], out[key])
        for key, subspace in space.items()
    }


@concatenate.register(Space)
def _concatenate_as_tuple(space: Space[Any], items: Iterable[Any], out: Any) -> tuple[Any, ...]:
    return tuple(items)


@singledispatch
def create_empty_array(space: Space[Any], n: int = 1, fn: Callable[..., Any] = np.zeros) -> Any:
    """A buffer for ``n`` elements of ``space`` (nested like the space), made with ``fn``.

    >>> create_empty_array(Dict(a=Discrete(2), b=Box(0, 1, (2,))), n=2)
    {'a': array([0, 0]), 'b': array([[0., 0.],
           [0., 0.]], dtype=float32)}
    """
    raise TypeError(
        "The space provided to `create_empty_array` is not a palaestra Space instance, "
        f"type: {type(space)}, {space}" + foreign_space_hint(space)
    )


@create_empty_array.register(Box)
@create_empty_array.register(Discrete)
@create_empty_array.register(MultiDiscrete)
@create_empty_array.register(MultiBinary)
def _empty_array(space: Space[Any], n: int = 1, fn: Callable[..., Any] = np.zeros) -> np.ndarray:
    return fn((n, *space.shape), dtype=space.dtype)  # type: ignore[misc]


@create_empty_array.register(Tuple)
def _empty_tuple(space: Tuple, n: int = 1, fn: Callable[..., Any] = np.zeros) -> tuple[Any, ...]:
    return tuple(create_empty_array(subspace, n=n, fn=fn) for subspace in space.spaces)


@create_empty_array.register(Dict)
def _empty_dict(space: Dict, n: int = 1, fn: Callable[..., Any] = np.zeros) -> dict[str, Any]:
    return {key: create_empty_array(subspace, n=n, fn=fn) for key, subspace in space.items()}


@create_empty_array.register(Text)
def _empty_text(space: Text, n: int = 1, fn: Callable[..., Any] = np.zeros) -> tuple[str, ...]:
    return tuple(space.characters[0] * space.min_length for _ in range(n))


@create_empty_array.register(OneOf)
def _empty_oneof(space: OneOf, n: int = 1, fn: Callable[..., Any] = np.zeros) -> tuple[Any, ...]:
    return tuple(() for _ in range(n))


@create_empty_array.register(Space)
def _empty_custom(space: Space[Any], n: int = 1, fn: Callable[..., Any] = np.zeros) -> None:
    return None
