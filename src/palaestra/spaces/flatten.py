"""``flatten`` a sample to its flat form (see ``flat_space``) and ``unflatten`` it back."""

from __future__ import annotations

from functools import singledispatch
from typing import Any

import numpy as np

from palaestra.spaces.batching import concatenate, create_empty_array, iterate
from palaestra.spaces.box import Box
from palaestra.spaces.dict import Dict
from palaestra.spaces.discrete import Discrete
from palaestra.spaces.flat_space import flat_dtype, flatdim, flatten_space
from palaestra.spaces.graph import Graph, GraphInstance
from palaestra.spaces.multi_binary import MultiBinary
from palaestra.spaces.multi_discrete import MultiDiscrete
from palaestra.spaces.oneof import OneOf
from palaestra.spaces.sequence import Sequence
from palaestra.spaces.space import Space, foreign_space_hint
from palaestra.spaces.text import Text
from palaestra.spaces.tuple import Tuple


class UnflattenTypeError(TypeError, AssertionError):
    """``unflatten`` got the wrong container type (array vs tuple/dict) for the space.

    Gymnasium checks this with ``assert``; this error is both a ``TypeError`` and an
    ``AssertionError`` so either ``except`` keeps working.
    """


@singledispatch
def flatten(space: Space[Any], x: Any) -> Any:
    """Flatten ``x`` (an element of ``space``) to an element of ``flatten_space(space)``.

    Discrete values become one-hot vectors; containers of flattenable spaces become one array.

    >>> flatten(Tuple([Discrete(3), Box(-1, 1, (2,))]), (1, np.array([0.5, -0.5], np.float32)))
    array([ 0. ,  1. ,  0. ,  0.5, -0.5])
    """
    raise NotImplementedError(f"Unknown space: `{space}`" + foreign_space_hint(space))


@flatten.register(Box)
@flatten.register(MultiBinary)
def _flatten_array(space: Box | MultiBinary, x: Any) -> np.ndarray:
    return np.asarray(x, dtype=space.dtype).flatten()


@flatten.register(Discrete)
def _flatten_discrete(space: Discrete, x: Any) -> np.ndarray:
    onehot = np.zeros(space.n, dtype=space.dtype)
    onehot[x - space.start] = 1
    return onehot


@flatten.register(MultiDiscrete)
def _flatten_multi_discrete(space: MultiDiscrete, x: Any) -> np.ndarray:
    offsets = np.zeros(space.nvec.size + 1, dtype=np.int32)
    offsets[1:] = np.cumsum(space.nvec.flatten())
    onehot = np.zeros(offsets[-1], dtype=space.dtype)
    onehot[offsets[:-1] + (x - space.start).flatten()] = 1
    return onehot


@flatten.register(Tuple)
def _flatten_tuple(space: Tuple, x: tuple[Any, ...]) -> np.ndarray | tuple[Any, ...]:
    parts = [flatten(s, part) for part, s in zip(x, space.spaces, strict=True)]
    if space.is_np_flattenable:
        return np.concatenate([np.array(part) for part in parts])
    return tuple(parts)


@flatten.register(Dict)
def _flatten_dict(space: Dict, x: dict[str, Any]) -> np.ndarray | dict[str, Any]:
    if space.is_np_flattenable:
        return np.concatenate([np.array(flatten(s, x[key])) for key, s in space.spaces.items()])
    return {key: flatten(s, x[key]) for key, s in space.spaces.items()}


def _map_batch(space: Space[Any], batch_space: Space[Any], items: Any, fn: Any) -> Any:
    """Apply ``fn`` to each element of a batch and stack the results as elements of ``space``."""
    results = [fn(item) for item in iterate(batch_space, items)]
    return concatenate(space, results, create_empty_array(space, n=len(results)))


@flatten.register(Graph)
def _flatten_graph(space: Graph, x: GraphInstance) -> GraphInstance:
    """Flatten each node (and edge) feature; the links are unchanged."""
    nodes = _map_batch(
        flatten_space(space.node_space),
        space.batch_node_space,
        x.nodes,
        lambda node: flatten(space.node_space, node),
    )
    edges = None
    if x.edges is not None:
        assert space.edge_space is not None and space.batch_edge_space is not None
        edge_space = space.edge_space
        edges = _map_batch(
            flatten_space(edge_space),
            space.batch_edge_space,
            x.edges,
            lambda edge: flatten(edge_space, edge),
        )
    return GraphInstance(nodes, edges, x.edge_links)


@flatten.register(Text)
def _flatten_text(space: Text, x: str) -> np.ndarray:
    # Index len(charset) marks padding after the end of the string.
    arr = np.full(space.max_length, len(space.character_set), dtype=np.int32)
    for i, char in enumerate(x):
        arr[i] = space.character_index(char)
    return arr


@flatten.register(Sequence)
def _flatten_sequence(space: Sequence, x: Any) -> Any:
    if space.stack:
        return _map_batch(
            flatten_space(space.feature_space),
            space.stacked_feature_space,
            x,
            lambda item: flatten(space.feature_space, item),
        )
    return tuple(flatten(space.feature_space, item) for item in x)


@flatten.register(OneOf)
def _flatten_oneof(space: OneOf, x: tuple[int, Any]) -> np.ndarray:
    index, sample = x
    flat_sample: np.ndarray = flatten(space.spaces[index], sample)
    width = flatdim(space) - 1  # without the index
    if flat_sample.size < width:
        # Gymnasium pads with the first value of the sample (keeps the padding in bounds).
        padding = np.full(width - flat_sample.size, flat_sample[0], dtype=flat_sample.dtype)
        flat_sample = np.concatenate([flat_sample, padding])
    dtype = flat_dtype(space)
    return np.concatenate([np.array([index], dtype=dtype), flat_sample.astype(dtype, copy=False)])


@singledispatch
def unflatten(space: Space[Any], x: Any) -> Any:
    """Invert ``flatten``: turn an element of ``flatten_space(space)`` back into one of ``space``.

    >>> unflatten(Discrete(3, start=-1), np.array([0, 0, 1]))
    np.int64(1)
    """
    raise NotImplementedError(f"Unknown space: `{space}`" + foreign_space_hint(space))


@unflatten.register(Box)
@unflatten.register(MultiBinary)
def _unflatten_array(space: Box | MultiBinary, x: Any) -> np.ndarray:
    return np.asarray(x, dtype=space.dtype).reshape(space.shape)


@unflatten.register(Discrete)
def _unflatten_discrete(space: Discrete, x: np.ndarray) -> np.integer:
    nonzero = np.nonzero(x)[0]
    if len(nonzero) == 0:
        raise ValueError(
            f"{x} is not a valid one-hot encoded vector and can not be unflattened to space "
            f"{space}. Not all valid samples in a flattened space can be unflattened."
        )
    return space.start + nonzero[0].astype(space.dtype)


@unflatten.register(MultiDiscrete)
def _unflatten_multi_discrete(space: MultiDiscrete, x: np.ndarray) -> np.ndarray:
    offsets = np.zeros(space.nvec.size + 1, dtype=space.dtype)
    offsets[1:] = np.cumsum(space.nvec.flatten())
    (indices,) = np.nonzero(x)
    if len(indices) == 0:
        raise ValueError(
            f"{x} is not a concatenation of one-hot encoded vectors and can not be unflattened "
            f"to space {space}. Not all valid samples in a flattened space can be unflattened."
        )
    values = np.asarray(indices - offsets[:-1], dtype=space.dtype).reshape(space.shape)
    return values + space.start


def _split(x: np.ndarray, spaces: list[Space[Any]]) -> list[np.ndarray]:
    dims = np.asarray([flatdim(s) for s in spaces], dtype=np.int_)
    return np.split(x, np.cumsum(dims[:-1]))


@unflatten.register(Tuple)
def _unflatten_tuple(space: Tuple, x: Any) -> tuple[Any, ...]:
    if space.is_np_flattenable:
        if not isinstance(x, np.ndarray):
            raise UnflattenTypeError(
                f"{space} is numpy-flattenable. Thus, you should only unflatten numpy arrays "
                f"for this space. Got a {type(x)}"
            )
        x = _split(x, list(space.spaces))
    elif not isinstance(x, tuple):
        raise UnflattenTypeError(
            f"{space} is not numpy-flattenable. Thus, you should only unflatten tuples for this "
            f"space. Got a {type(x)}"
        )
    return tuple(unflatten(s, part) for part, s in zip(x, space.spaces, strict=True))


@unflatten.register(Dict)
def _unflatten_dict(space: Dict, x: Any) -> dict[str, Any]:
    if space.is_np_flattenable:
        if not isinstance(x, np.ndarray):
            raise UnflattenTypeError(
                "x must be a numpy array when unflattening a numpy-flattenable space, "
                f"got a {type(x)}"
            )
        parts = _split(x, list(space.spaces.values()))
        return {key: unflatten(s, p) for p, (key, s) in zip(parts, space.spaces.items())}
    if not isinstance(x, dict):
        raise UnflattenTypeError(
            f"{space} is not numpy-flattenable. Thus, you should only unflatten dictionary for "
            f"this space. Got a {type(x)}"
        )
    return {key: unflatten(s, x[key]) for key, s in space.spaces.items()}


@unflatten.register(Graph)
def _unflatten_graph(space: Graph, x: GraphInstance) -> GraphInstance:
    nodes = _map_batch(
        space.node_space,
        flatten_space(space.node_space),
        x.nodes,
        lambda node: unflatten(space.node_space, node),
    )
    edges = None
    if x.edges is not None:
        assert space.edge_space is not None
        edge_space = space.edge_space
        edges = _map_batch(
            edge_space,
            flatten_space(edge_space),
            x.edges,
            lambda edge: unflatten(edge_space, edge),
        )
    return GraphInstance(nodes, edges, x.edge_links)


@unflatten.register(Text)
def _unflatten_text(space: Text, x: np.ndarray) -> str:
    n_chars = len(space.character_set)
    return "".join(space.character_list[i] for i in x if i < n_chars)


@unflatten.register(Sequence)
def _unflatten_sequence(space: Sequence, x: Any) -> Any:
    if space.stack:
        return _map_batch(
            space.feature_space,
            flatten_space(space.feature_space),
            x,
            lambda item: unflatten(space.feature_space, item),
        )
    return tuple(unflatten(space.feature_space, item) for item in x)


@unflatten.register(OneOf)
def _unflatten_oneof(space: OneOf, x: np.ndarray) -> tuple[np.int64, Any]:
    index = np.int64(x[0])
    subspace = space.spaces[index]
    trimmed = x[1 : 1 + flatdim(subspace)].astype(flat_dtype(subspace))
    return index, unflatten(subspace, trimmed)
