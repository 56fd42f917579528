"""Helpers shared by the wrappers: zero observations and affine rescaling of ``Box`` spaces.

Mirrors ``gymnasium.wrappers.utils`` (``RunningMeanStd``, ``create_zero_array``,
``rescale_box``) so code importing those names keeps working.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import singledispatch
from typing import Any

import numpy as np

from palaestra.error import CustomSpaceError
from palaestra.spaces import (
    Box,
    Dict,
    Discrete,
    Graph,
    GraphInstance,
    MultiBinary,
    MultiDiscrete,
    OneOf,
    Sequence,
    Space,
    Text,
    Tuple,
)
from palaestra.spaces.batching import batch_space
from palaestra.wrappers.running_mean_std import RunningMeanStd, update_mean_var_count_from_moments

__all__ = [
    "RunningMeanStd",
    "create_zero_array",
    "rescale_box",
    "update_mean_var_count_from_moments",
]


@singledispatch
def create_zero_array(space: Space[Any]) -> Any:
    """The element of ``space`` closest to zero (used to pad delayed or stacked observations).

    Unlike an empty array, the result is always inside the space, e.g. a ``Box`` whose ``low``
    is positive gets ``low`` rather than 0.
    """
    if isinstance(space, Space):
        raise CustomSpaceError(
            f"Space of type {type(space)} has no `create_zero_array` function; register one with "
            f"`create_zero_array.register({type(space).__name__})`."
        )
    raise TypeError(f"Expected a palaestra Space, got {type(space)}: {space!r}")


@create_zero_array.register(Box)
def _zero_box(space: Box) -> np.ndarray:
    zero = np.zeros(space.shape, dtype=space.dtype)
    zero = np.where(space.low > 0, space.low, zero)
    return np.where(space.high < 0, space.high, zero)


@create_zero_array.register(Discrete)
def _zero_discrete(space: Discrete) -> Any:
    return space.start


@create_zero_array.register(MultiDiscrete)
def _zero_multidiscrete(space: MultiDiscrete) -> np.ndarray:
    return np.array(space.start, copy=True, dtype=space.dtype)


@create_zero_array.register(MultiBinary)
def _zero_multibinary(space: MultiBinary) -> np.ndarray:
    return np.zeros(space.shape, dtype=space.dtype)


@create_zero_array.register(Tuple)
def _zero_tuple(space: Tuple) -> tuple[Any, ...]:
    return tuple(create_zero_array(sub) for sub in space.spaces)


@create_zero_array.register(Dict)
def _zero_dict(space: Dict) -> dict[str, Any]:
    return {key: create_zero_array(sub) for key, sub in space.spaces.items()}


@create_zero_array.register(Sequence)
def _zero_sequence(space: Sequence) -> Any:
    # Gymnasium's: a stacked sequence's zero is its stacked space's; otherwise empty
    return create_zero_array(space.stacked_feature_space) if space.stack else ()


@create_zero_array.register(Text)
def _zero_text(space: Text) -> str:
    return space.characters[0] * space.min_length


@create_zero_array.register(Graph)
def _zero_graph(space: Graph) -> GraphInstance:
    """One node (and, with an edge space, one self-edge of node 0), each at its zero."""
    nodes = create_zero_array(batch_space(space.node_space, 1))
    if space.edge_space is None:
        return GraphInstance(nodes=nodes, edges=None, edge_links=None)
    edges = create_zero_array(batch_space(space.edge_space, 1))
    return GraphInstance(nodes=nodes, edges=edges, edge_links=np.zeros((1, 2), dtype=np.int64))


@create_zero_array.register(OneOf)
def _zero_oneof(space: OneOf) -> tuple[int, Any]:
    return 0, create_zero_array(space.spaces[0])


def _as_bound(value: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    if not isinstance(value, np.ndarray):
        if not np.issubdtype(type(value), np.integer) and not np.issubdtype(
            type(value), np.floating
        ):
            raise TypeError(
                f"Expected {name} to be an int, float or numpy array, got {type(value)}"
            )
        value = np.full(shape, value)
    if value.shape != shape:
        raise ValueError(f"Expected {name}.shape to be {shape}, got {value.shape}")
    return value


def rescale_box(
    box: Box, new_min: Any, new_max: Any
) -> tuple[Box, Callable[[Any], Any], Callable[[Any], Any]]:
    """Map ``box`` affinely onto ``[new_min, new_max]``.

    Returns ``(new_box, forward, backward)`` where ``forward`` takes a point of ``box`` to
    ``new_box`` and ``backward`` inverts it. Infinite bounds must stay the same infinity; such
    components are shifted, not scaled.

    >>> new, fwd, bwd = rescale_box(Box(0.0, 2.0, (2,)), np.float32(-1), np.float32(1))
    >>> new
    Box(-1.0, 1.0, (2,), float32)
    >>> fwd(np.array([0.0, 2.0], dtype=np.float32)), bwd(np.zeros(2, dtype=np.float32))
    (array([-1.,  1.], dtype=float32), array([1., 1.], dtype=float32))
    """
    if not isinstance(box, Box):
        raise TypeError(f"Expected box to be a Box space, got {type(box)}")
    new_min = _as_bound(new_min, box.shape, "new_min")
    new_max = _as_bound(new_max, box.shape, "new_max")
    for new, old in ((new_min, box.low), (new_max, box.high)):
        unbounded = np.isinf(new) | np.isinf(old)
        if not np.all(new[unbounded] == old[unbounded]):
            raise ValueError(
                "For unbounded components, the target bounds must match the original infinity "
                f"bounds, got new bounds [{new_min}, {new_max}] for box {box}"
            )
    if not np.all(new_min <= new_max):
        raise ValueError(f"Expected new_min <= new_max, got {new_min} and {new_max}")
    if not np.all(box.low <= box.high):
        raise ValueError(f"Expected box.low <= box.high, got {box.low} and {box.high}")

    min_finite, max_finite = np.isfinite(new_min), np.isfinite(new_max)
    both = min_finite & max_finite
    # Extended precision for the width so float32 boxes near their range limits do not
    # overflow; the same precision Gymnasium uses, so the coefficients are bit-identical.
    wide = getattr(np, "float128", np.float64)
    width = np.asarray(box.high[both], dtype=wide) - np.asarray(box.low[both], dtype=wide)
    gradient = np.ones_like(new_min, dtype=box.dtype)
    gradient[both] = (new_max[both] - new_min[both]) / width
    intercept = np.zeros_like(new_min, dtype=box.dtype)
    intercept[max_finite] = new_max[max_finite] - box.high[max_finite]
    # Where both bounds are finite the lower bound decides, as in Gymnasium.
    intercept[min_finite] = gradient[min_finite] * -box.low[min_finite] + new_min[min_finite]

    new_box = Box(low=new_min, high=new_max, shape=box.shape, dtype=box.dtype)

    def forward(x: Any) -> Any:
        return gradient * x + intercept

    def backward(y: Any) -> Any:
        return (y - intercept) / gradient

    return new_box, forward, backward
