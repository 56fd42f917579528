"""The flat (1-D ``Box``) form of a space: its size, its dtype and the space itself."""

from __future__ import annotations

import math
from functools import singledispatch
from typing import Any

import numpy as np

from palaestra.spaces.box import Box
from palaestra.spaces.dict import Dict
from palaestra.spaces.discrete import Discrete
from palaestra.spaces.graph import Graph
from palaestra.spaces.multi_binary import MultiBinary
from palaestra.spaces.multi_discrete import MultiDiscrete
from palaestra.spaces.oneof import OneOf
from palaestra.spaces.sequence import Sequence
from palaestra.spaces.space import Space, foreign_space_hint
from palaestra.spaces.text import Text
from palaestra.spaces.tuple import Tuple

_NOT_FLATTENABLE = (
    "{} cannot be flattened to a numpy array, probably because it contains a `Graph` or "
    "`Sequence` subspace"
)


@singledispatch
def flat_dtype(space: Space[Any]) -> np.dtype:
    """The dtype of ``flatten(space, x)`` for a numpy-flattenable space."""
    if space.dtype is None:
        raise ValueError(
            f"{space} does not have a dtype, therefore, it cannot be flattened to a numpy array, "
            "probably because it contains a `Graph` or `Sequence` subspace."
        )
    return space.dtype


@flat_dtype.register(Text)
def _flat_dtype_text(space: Text) -> np.dtype:
    return np.dtype(np.int32)  # character indices


@flat_dtype.register(Tuple)
def _flat_dtype_tuple(space: Tuple) -> np.dtype:
    return np.result_type(*(flat_dtype(s) for s in space.spaces))


@flat_dtype.register(Dict)
def _flat_dtype_dict(space: Dict) -> np.dtype:
    return np.result_type(*(flat_dtype(s) for s in space.spaces.values()))


@flat_dtype.register(OneOf)
def _flat_dtype_oneof(space: OneOf) -> np.dtype:
    # The flat vector starts with the subspace index, so the dtype must be able to hold it.
    dtype = np.result_type(*(flat_dtype(s) for s in space.spaces))
    max_index = len(space.spaces) - 1
    if (dtype.kind == "b" and max_index > 1) or (
        dtype.kind in "iu" and max_index > np.iinfo(dtype).max
    ):
        dtype = np.result_type(dtype, np.min_scalar_type(max_index))
    return dtype


@singledispatch
def flatdim(space: Space[Any]) -> int:
    """The length of ``flatten(space, x)``; raises for spaces without a fixed flat size.

    >>> flatdim(Dict(a=Discrete(3), b=Box(0, 1, shape=(2, 2))))
    7
    """
    if space.is_np_flattenable is False:
        raise ValueError(_NOT_FLATTENABLE.format(space))
    raise NotImplementedError(f"Unknown space: `{space}`" + foreign_space_hint(space))


@flatdim.register(Box)
@flatdim.register(MultiBinary)
def _flatdim_array(space: Box | MultiBinary) -> int:
    return math.prod(space.shape)


@flatdim.register(Discrete)
def _flatdim_discrete(space: Discrete) -> int:
    return int(space.n)  # one-hot


@flatdim.register(MultiDiscrete)
def _flatdim_multi_discrete(space: MultiDiscrete) -> int:
    return int(np.sum(space.nvec))  # concatenated one-hots


@flatdim.register(Tuple)
def _flatdim_tuple(space: Tuple) -> int:
    if not space.is_np_flattenable:
        raise ValueError(_NOT_FLATTENABLE.format(space))
    return sum(flatdim(s) for s in space.spaces)


@flatdim.register(Dict)
def _flatdim_dict(space: Dict) -> int:
    if not space.is_np_flattenable:
        raise ValueError(_NOT_FLATTENABLE.format(space))
    return sum(flatdim(s) for s in space.spaces.values())


@flatdim.register(Graph)
def _flatdim_graph(space: Graph) -> int:
    raise ValueError("Cannot get flattened size as the Graph Space has a dynamic size.")


@flatdim.register(Text)
def _flatdim_text(space: Text) -> int:
    return space.max_length  # padded


@flatdim.register(OneOf)
def _flatdim_oneof(space: OneOf) -> int:
    return 1 + max(flatdim(s) for s in space.spaces)  # index, then the padded sample


@singledispatch
def flatten_space(space: Space[Any]) -> Space[Any]:
    """The space of ``flatten(space, x)``: a 1-D ``Box`` when possible, else a flat container.

    >>> flatten_space(Tuple([Discrete(3), Box(-1, 1, (2,))]))
    Box([ 0.  0.  0. -1. -1.], 1.0, (5,), float64)
    """
    raise NotImplementedError(f"Unknown space: `{space}`" + foreign_space_hint(space))


@flatten_space.register(Box)
def _flatten_space_box(space: Box) -> Box:
    return Box(space.low.flatten(), space.high.flatten(), dtype=space.dtype)


@flatten_space.register(Discrete)
@flatten_space.register(MultiBinary)
@flatten_space.register(MultiDiscrete)
def _flatten_space_binary(space: Discrete | MultiBinary | MultiDiscrete) -> Box:
    return Box(low=0, high=1, shape=(flatdim(space),), dtype=space.dtype)


def _concatenate_boxes(boxes: list[Box]) -> Box:
    return Box(
        low=np.concatenate([box.low for box in boxes]),
        high=np.concatenate([box.high for box in boxes]),
        dtype=np.result_type(*(box.dtype for box in boxes)),
    )


@flatten_space.register(Tuple)
def _flatten_space_tuple(space: Tuple) -> Box | Tuple:
    if space.is_np_flattenable:
        return _concatenate_boxes([flatten_space(s) for s in space.spaces])  # type: ignore[misc]
    return Tuple([flatten_space(s) for s in space.spaces])


@flatten_space.register(Dict)
def _flatten_space_dict(space: Dict) -> Box | Dict:
    if space.is_np_flattenable:
        return _concatenate_boxes([flatten_space(s) for s in space.spaces.values()])  # type: ignore[misc]
    return Dict(
        {key: flatten_space(s) for key, s in space.spaces.items()}, sort_keys=space.sort_keys
    )


@flatten_space.register(Graph)
def _flatten_space_graph(space: Graph) -> Graph:
    edge_space = None if space.edge_space is None else flatten_space(space.edge_space)
    return Graph(node_space=flatten_space(space.node_space), edge_space=edge_space)


@flatten_space.register(Text)
def _flatten_space_text(space: Text) -> Box:
    # Index len(charset) pads strings shorter than max_length.
    return Box(low=0, high=len(space.character_set), shape=(space.max_length,), dtype=np.int32)


@flatten_space.register(Sequence)
def _flatten_space_sequence(space: Sequence) -> Sequence:
    return Sequence(flatten_space(space.feature_space), stack=space.stack)


@flatten_space.register(OneOf)
def _flatten_space_oneof(space: OneOf) -> Box:
    size = flatdim(space)
    flat_spaces: list[Any] = [flatten_space(s) for s in space.spaces]
    overall_low = np.min([np.min(s.low) for s in flat_spaces])
    overall_high = np.max([np.max(s.high) for s in flat_spaces])
    low = np.concatenate([[0], np.full(size - 1, overall_low)])
    high = np.concatenate([[len(space.spaces) - 1], np.full(size - 1, overall_high)])
    return Box(low=low, high=high, shape=(size,), dtype=flat_dtype(space))
