"""Observation buffers in shared memory, laid out like ``create_empty_array``'s buffers.

Workers write their row in place; the parent reads the whole batch as numpy views, so no
observation is pickled. Array spaces (Box, Discrete, MultiDiscrete, MultiBinary) and Tuple/Dict
of them are supported; Graph and Sequence (dynamic shapes) raise ``DynamicShapeSpaceError`` (a
``TypeError``, as in Gymnasium), other spaces ``CustomSpaceError`` (use ``shared_memory=False``).
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
    Sequence,
    Space,
    Tuple,
)

__all__ = ["create_shared_memory", "read_from_shared_memory", "write_to_shared_memory"]


@singledispatch
def create_shared_memory(space: Space[Any], n: int = 1, ctx: Any = mp) -> Any:
    """Shared memory for ``n`` elements of ``space`` (nested like the space)."""
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
def read_from_shared_memory(space: Space[Any], shared_memory: Any, n: int = 1) -> Any:
    """Numpy views ``[n, *shape]`` onto ``shared_memory`` (no copy)."""
    raise CustomSpaceError(
        f"Space of type `{type(space)}` doesn't have a registered `read_from_shared_memory`."
    )


@read_from_shared_memory.register(Box)
@read_from_shared_memory.register(Discrete)
@read_from_shared_memory.register(MultiDiscrete)
@read_from_shared_memory.register(MultiBinary)
def _read_array(space: Space[Any], shared_memory: Any, n: int = 1) -> np.ndarray:
    assert space.shape is not None
    count = n * int(np.prod(space.shape, dtype=np.int64))
    flat = np.frombuffer(shared_memory, dtype=space.dtype, count=count)
    return flat.reshape((n, *space.shape))


@read_from_shared_memory.register(Tuple)
def _read_tuple(space: Tuple, shared_memory: Any, n: int = 1) -> tuple[Any, ...]:
    return tuple(
        read_from_shared_memory(sub, mem, n=n) for sub, mem in zip(space.spaces, shared_memory)
    )


@read_from_shared_memory.register(Dict)
def _read_dict(space: Dict, shared_memory: Any, n: int = 1) -> dict[str, Any]:
    return {
        key: read_from_shared_memory(sub, shared_memory[key], n=n) for key, sub in space.items()
    }


def write_to_shared_memory(space: Space[Any], index: int, value: Any, shared_memory: Any) -> None:
    """Write one element at row ``index`` (Gymnasium's signature; builds views each call)."""
    n = index + 1
    write_row(space, read_from_shared_memory(space, shared_memory, n=n), index, value)


@singledispatch
def write_row(space: Space[Any], views: Any, index: int, value: Any) -> None:
    """Write one element into row ``index`` of views made by :func:`read_from_shared_memory`."""
    raise CustomSpaceError(f"Space of type `{type(space)}` cannot be written to shared memory.")


@write_row.register(Box)
@write_row.register(Discrete)
@write_row.register(MultiDiscrete)
@write_row.register(MultiBinary)
def _write_array(space: Space[Any], views: np.ndarray, index: int, value: Any) -> None:
    views[index] = value


@write_row.register(Tuple)
def _write_tuple(space: Tuple, views: tuple[Any, ...], index: int, value: Any) -> None:
    for sub, view, item in zip(space.spaces, views, value):
        write_row(sub, view, index, item)


@write_row.register(Dict)
def _write_dict(space: Dict, views: dict[str, Any], index: int, value: Any) -> None:
    for key, sub in space.items():
        write_row(sub, views[key], index, value[key])
