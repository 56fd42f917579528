"""Observation buffers in shared memory, laid out like ``create_empty_array``'s buffers.

Workers write their row in place; the parent reads the whole batch, so no observation is
pickled. Array spaces (Box, Discrete, MultiDiscrete, MultiBinary) are read as numpy views
``[n, *shape]`` (no copy). ``Text`` is held as character indices ``[n, max_length]`` (int32,
padded with ``len(character_set)``) and ``OneOf`` as the chosen subspace per row (int64) plus
one buffer per subspace, as in Gymnasium; reading them decodes strings and ``(index, value)``
pairs. Tuple/Dict nest any of these. Graph and Sequence (dynamic shapes) raise
``DynamicShapeSpaceError`` (a ``TypeError``, as in Gymnasium), other spaces
``CustomSpaceError`` (use ``shared_memory=False``).

:func:`shared_views` gives the raw views (what workers write into with :func:`write_row`),
:func:`decode_views` turns them into the batch (the views themselves where nothing needs
decoding), and :func:`read_from_shared_memory` is the two together (Gymnasium's function).
"""

from __future__ import annotations

import multiprocessing as mp
from functools import singledispatch
from typing import Any

import numpy as np

from palaestra.error import CustomSpaceError, DynamicShapeSpaceError
from palaestra.spaces import (
    Box,
    Dict,
    Discrete,
    Graph,
    MultiBinary,
    MultiDiscrete,
    OneOf,
    Sequence,
    Space,
    Text,
    Tuple,
)
from palaestra.spaces.utils import flatten

__all__ = [
    "create_shared_memory",
    "decode_views",
    "needs_decoding",
    "read_from_shared_memory",
    "shared_views",
    "write_row",
    "write_to_shared_memory",
]


def _not_a_space(function: str, space: Any) -> TypeError:
    """Gymnasium's error type for a value that is no Space at all (a custom Space subclass
    gets ``CustomSpaceError`` instead)."""
    return TypeError(
        f"The space given to `{function}` is not a palaestra Space, got {space!r} "
        f"({type(space).__name__})"
    )


@singledispatch
def create_shared_memory(space: Space[Any], n: int = 1, ctx: Any = mp) -> Any:
    """Shared memory for ``n`` elements of ``space`` (nested like the space)."""
    if not isinstance(space, Space):
        raise _not_a_space("create_shared_memory", space)
    raise CustomSpaceError(
        f"Space of type `{type(space)}` doesn't have a registered `create_shared_memory` "
        "function. Register it, or use shared_memory=False."
    )


@create_shared_memory.register(Box)
@create_shared_memory.register(Discrete)
@create_shared_memory.register(MultiDiscrete)
@create_shared_memory.register(MultiBinary)
def _shared_array(space: Space[Any], n: int = 1, ctx: Any = mp) -> Any:
    assert space.dtype is not None and space.shape is not None
    nbytes = n * int(np.prod(space.shape, dtype=np.int64)) * space.dtype.itemsize
    return ctx.Array("b", max(nbytes, 1), lock=False)


@create_shared_memory.register(Text)
def _shared_text(space: Text, n: int = 1, ctx: Any = mp) -> Any:
    return ctx.Array("b", max(n * space.max_length * 4, 1), lock=False)  # int32 indices


@create_shared_memory.register(OneOf)
def _shared_oneof(space: OneOf, n: int = 1, ctx: Any = mp) -> tuple[Any, ...]:
    chosen = ctx.Array("b", n * 8, lock=False)  # int64 subspace index per row
    return (chosen, *(create_shared_memory(sub, n=n, ctx=ctx) for sub in space.spaces))


@create_shared_memory.register(Graph)
@create_shared_memory.register(Sequence)
def _shared_dynamic(space: Space[Any], n: int = 1, ctx: Any = mp) -> Any:
    raise DynamicShapeSpaceError(
        f"As {space} has a dynamic shape so its not possible to make a static shared memory. "
        "For `AsyncVectorEnv`, disable `shared_memory`."
    )


@create_shared_memory.register(Tuple)
def _shared_tuple(space: Tuple, n: int = 1, ctx: Any = mp) -> tuple[Any, ...]:
    return tuple(create_shared_memory(sub, n=n, ctx=ctx) for sub in space.spaces)


@create_shared_memory.register(Dict)
def _shared_dict(space: Dict, n: int = 1, ctx: Any = mp) -> dict[str, Any]:
    return {key: create_shared_memory(sub, n=n, ctx=ctx) for key, sub in space.items()}


@singledispatch
def shared_views(space: Space[Any], shared_memory: Any, n: int = 1) -> Any:
    """Raw numpy views onto ``shared_memory`` (no copy), nested like the space."""
    if not isinstance(space, Space):
        raise _not_a_space("read_from_shared_memory", space)
    raise CustomSpaceError(
        f"Space of type `{type(space)}` doesn't have a registered `read_from_shared_memory`."
    )


@shared_views.register(Box)
@shared_views.register(Discrete)
@shared_views.register(MultiDiscrete)
@shared_views.register(MultiBinary)
def _array_views(space: Space[Any], shared_memory: Any, n: int = 1) -> np.ndarray:
    assert space.shape is not None
    count = n * int(np.prod(space.shape, dtype=np.int64))
    flat = np.frombuffer(shared_memory, dtype=space.dtype, count=count)
    return flat.reshape((n, *space.shape))


@shared_views.register(Text)
def _text_views(space: Text, shared_memory: Any, n: int = 1) -> np.ndarray:
    count = n * space.max_length
    return np.frombuffer(shared_memory, dtype=np.int32, count=count).reshape(n, space.max_length)


@shared_views.register(OneOf)
def _oneof_views(space: OneOf, shared_memory: Any, n: int = 1) -> tuple[Any, ...]:
    chosen = np.frombuffer(shared_memory[0], dtype=np.int64, count=n)
    subs = tuple(shared_views(sub, mem, n=n) for sub, mem in zip(space.spaces, shared_memory[1:]))
    return chosen, subs


@shared_views.register(Tuple)
def _tuple_views(space: Tuple, shared_memory: Any, n: int = 1) -> tuple[Any, ...]:
    return tuple(shared_views(sub, mem, n=n) for sub, mem in zip(space.spaces, shared_memory))


@shared_views.register(Dict)
def _dict_views(space: Dict, shared_memory: Any, n: int = 1) -> dict[str, Any]:
    return {key: shared_views(sub, shared_memory[key], n=n) for key, sub in space.items()}


def needs_decoding(space: Space[Any]) -> bool:
    """Whether the batch of ``space`` is not its views themselves (Text/OneOf inside)."""
    if isinstance(space, (Text, OneOf)):
        return True
    if isinstance(space, Tuple):
        return any(needs_decoding(sub) for sub in space.spaces)
    if isinstance(space, Dict):
        return any(needs_decoding(sub) for sub in space.spaces.values())
    return False


def decode_views(space: Space[Any], views: Any) -> Any:
    """The batch the views hold: the views themselves for array spaces, a tuple of strings for
    ``Text``, a tuple of ``(subspace index, value)`` for ``OneOf`` (Gymnasium's batches)."""
    if isinstance(space, Text):
        chars, size = space.character_list, len(space.character_set)
        return tuple("".join(chars[i] for i in row if i < size) for row in views.tolist())
    if isinstance(space, OneOf):
        chosen, subs = views
        decoded = [decode_views(sub, v) for sub, v in zip(space.spaces, subs)]
        # Iterating the int64 view, not .tolist(): the index comes back as np.int64, as
        # Gymnasium's does, so a sample read back is data-equivalent to the one written.
        return tuple((k, decoded[k][row]) for row, k in enumerate(chosen))
    if isinstance(space, Tuple) and needs_decoding(space):
        return tuple(decode_views(sub, v) for sub, v in zip(space.spaces, views))
    if isinstance(space, Dict) and needs_decoding(space):
        return {key: decode_views(sub, views[key]) for key, sub in space.items()}
    return views


def read_from_shared_memory(space: Space[Any], shared_memory: Any, n: int = 1) -> Any:
    """The batch in ``shared_memory``: numpy views ``[n, *shape]`` (no copy) for array spaces,
    decoded strings / ``(index, value)`` pairs for Text / OneOf."""
    return decode_views(space, shared_views(space, shared_memory, n=n))


def write_to_shared_memory(space: Space[Any], index: int, value: Any, shared_memory: Any) -> None:
    """Write one element at row ``index`` (Gymnasium's signature; builds views each call)."""
    if not isinstance(space, Space):
        raise _not_a_space("write_to_shared_memory", space)
    write_row(space, shared_views(space, shared_memory, n=index + 1), index, value)


@singledispatch
def write_row(space: Space[Any], views: Any, index: int, value: Any) -> None:
    """Write one element into row ``index`` of views made by :func:`shared_views`."""
    if not isinstance(space, Space):
        raise _not_a_space("write_to_shared_memory", space)
    raise CustomSpaceError(f"Space of type `{type(space)}` cannot be written to shared memory.")


@write_row.register(Box)
@write_row.register(Discrete)
@write_row.register(MultiDiscrete)
@write_row.register(MultiBinary)
def _write_array(space: Space[Any], views: np.ndarray, index: int, value: Any) -> None:
    views[index] = value


@write_row.register(Text)
def _write_text(space: Text, views: np.ndarray, index: int, value: Any) -> None:
    views[index] = flatten(space, value)


@write_row.register(OneOf)
def _write_oneof(space: OneOf, views: tuple[Any, ...], index: int, value: Any) -> None:
    chosen, subs = views
    which, item = value
    chosen[index] = which
    # only the chosen subspace's row changes: the others may not even hold a valid sample
    write_row(space.spaces[which], subs[which], index, item)


@write_row.register(Tuple)
def _write_tuple(space: Tuple, views: tuple[Any, ...], index: int, value: Any) -> None:
    for sub, view, item in zip(space.spaces, views, value):
        write_row(sub, view, index, item)


@write_row.register(Dict)
def _write_dict(space: Dict, views: dict[str, Any], index: int, value: Any) -> None:
    for key, sub in space.items():
        write_row(sub, views[key], index, value[key])
