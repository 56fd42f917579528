"""Space conversion between palaestra and Gymnasium, both ways, for every standard space type.

``to_gymnasium_space(s)`` builds the Gymnasium space with the same elements (bounds, dtype,
``start``, charset, key order, nesting); ``from_gymnasium_space`` is its inverse, so
``from_gymnasium_space(to_gymnasium_space(s)) == s``. Samples of both are the same Python and
numpy values except graphs, whose ``GraphInstance`` tuple type belongs to each library:
``to_gymnasium_value`` / ``from_gymnasium_value`` convert those (and containers holding them).
Random generators are not carried over: a converted space seeds itself afresh.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from palaestra import spaces
from palaestra.compat._optional import gymnasium_missing

try:
    from gymnasium import spaces as gym_spaces
except ImportError as exc:  # pragma: no cover - exercised in a subprocess test
    raise gymnasium_missing() from exc

__all__ = [
    "from_gymnasium_space",
    "from_gymnasium_value",
    "needs_value_conversion",
    "to_gymnasium_space",
    "to_gymnasium_value",
]

_KINDS = "Box, Discrete, MultiDiscrete, MultiBinary, Text, Tuple, Dict, Sequence, Graph, OneOf"


def _unsupported(space: Any, direction: str, expected: str) -> TypeError:
    return TypeError(
        f"{direction}: {space!r} (type {type(space).__module__}.{type(space).__qualname__}) has "
        f"no counterpart; expected a {expected} space of one of these types: {_KINDS}"
    )


def _bound(values: np.ndarray, bounded: np.ndarray, infinity: float) -> Any:
    """Integer boxes store an unbounded side as the dtype's limit plus a flag; hand the other
    library an infinity there so that its ``bounded_below/above`` flags come out the same."""
    if bounded.all() or values.dtype.kind == "f":
        return values
    if not bounded.any():
        return infinity  # scalar: an int64 limit does not survive a float64 array
    return np.where(bounded, values.astype(np.float64), infinity)


# -- palaestra -> Gymnasium ------------------------------------------------------------------
@functools.singledispatch
def to_gymnasium_space(space: Any) -> Any:
    """The Gymnasium space with the same elements as palaestra ``space``.

    >>> from palaestra import spaces
    >>> to_gymnasium_space(spaces.Discrete(3, start=-1))
    Discrete(3, start=-1)
    >>> type(to_gymnasium_space(spaces.Box(0, 1, (2,)))).__module__
    'gymnasium.spaces.box'
    """
    raise _unsupported(space, "to_gymnasium_space", "palaestra")


@to_gymnasium_space.register
def _(space: spaces.Box) -> gym_spaces.Box:
    low = _bound(space.low, space.bounded_below, -np.inf)
    high = _bound(space.high, space.bounded_above, np.inf)
    return gym_spaces.Box(low, high, space.shape, space.dtype)


@to_gymnasium_space.register
def _(space: spaces.Discrete) -> gym_spaces.Discrete:
    return gym_spaces.Discrete(int(space.n), start=int(space.start), dtype=space.dtype)


@to_gymnasium_space.register
def _(space: spaces.MultiDiscrete) -> gym_spaces.MultiDiscrete:
    return gym_spaces.MultiDiscrete(space.nvec.copy(), dtype=space.dtype, start=space.start.copy())


@to_gymnasium_space.register
def _(space: spaces.MultiBinary) -> gym_spaces.MultiBinary:
    return gym_spaces.MultiBinary(space.n)


@to_gymnasium_space.register
def _(space: spaces.Text) -> gym_spaces.Text:
    # A string charset keeps the character order, which decides what a seeded sample draws.
    return gym_spaces.Text(
        space.max_length, min_length=space.min_length, charset="".join(space.character_list)
    )


@to_gymnasium_space.register
def _(space: spaces.Tuple) -> gym_spaces.Tuple:
    return gym_spaces.Tuple([to_gymnasium_space(s) for s in space.spaces])


@to_gymnasium_space.register
def _(space: spaces.Dict) -> gym_spaces.Dict:
    # A list of pairs keeps palaestra's key order (a mapping would be re-sorted).
    return gym_spaces.Dict([(k, to_gymnasium_space(s)) for k, s in space.spaces.items()])


@to_gymnasium_space.register
def _(space: spaces.Sequence) -> gym_spaces.Sequence:
    return gym_spaces.Sequence(to_gymnasium_space(space.feature_space), stack=space.stack)


@to_gymnasium_space.register
def _(space: spaces.Graph) -> gym_spaces.Graph:
    edge = None if space.edge_space is None else to_gymnasium_space(space.edge_space)
    return gym_spaces.Graph(to_gymnasium_space(space.node_space), edge)


@to_gymnasium_space.register
def _(space: spaces.OneOf) -> gym_spaces.OneOf:
    return gym_spaces.OneOf([to_gymnasium_space(s) for s in space.spaces])


# -- Gymnasium -> palaestra ------------------------------------------------------------------
@functools.singledispatch
def from_gymnasium_space(space: Any) -> spaces.Space[Any]:
    """The palaestra space with the same elements as Gymnasium ``space``.

    >>> import gymnasium
    >>> from_gymnasium_space(gymnasium.spaces.MultiDiscrete([2, 3]))
    MultiDiscrete([2 3])
    """
    raise _unsupported(space, "from_gymnasium_space", "Gymnasium")


@from_gymnasium_space.register
def _(space: gym_spaces.Box) -> spaces.Box:
    low = _bound(space.low, space.bounded_below, -np.inf)
    high = _bound(space.high, space.bounded_above, np.inf)
    return spaces.Box(low, high, space.shape, space.dtype)


@from_gymnasium_space.register
def _(space: gym_spaces.Discrete) -> spaces.Discrete:
    return spaces.Discrete(int(space.n), start=int(space.start), dtype=space.dtype)


@from_gymnasium_space.register
def _(space: gym_spaces.MultiDiscrete) -> spaces.MultiDiscrete:
    return spaces.MultiDiscrete(space.nvec.copy(), dtype=space.dtype, start=space.start.copy())


@from_gymnasium_space.register
def _(space: gym_spaces.MultiBinary) -> spaces.MultiBinary:
    return spaces.MultiBinary(space.n)


@from_gymnasium_space.register
def _(space: gym_spaces.Text) -> spaces.Text:
    return spaces.Text(
        space.max_length, min_length=space.min_length, charset="".join(space.character_list)
    )


@from_gymnasium_space.register
def _(space: gym_spaces.Tuple) -> spaces.Tuple:
    return spaces.Tuple([from_gymnasium_space(s) for s in space.spaces])


@from_gymnasium_space.register
def _(space: gym_spaces.Dict) -> spaces.Dict:
    return spaces.Dict([(k, from_gymnasium_space(s)) for k, s in space.spaces.items()])


@from_gymnasium_space.register
def _(space: gym_spaces.Sequence) -> spaces.Sequence:
    return spaces.Sequence(from_gymnasium_space(space.feature_space), stack=space.stack)


@from_gymnasium_space.register
def _(space: gym_spaces.Graph) -> spaces.Graph:
    edge = None if space.edge_space is None else from_gymnasium_space(space.edge_space)
    return spaces.Graph(from_gymnasium_space(space.node_space), edge)


@from_gymnasium_space.register
def _(space: gym_spaces.OneOf) -> spaces.OneOf:
    return spaces.OneOf([from_gymnasium_space(s) for s in space.spaces])


# -- values ----------------------------------------------------------------------------------
def needs_value_conversion(space: spaces.Space[Any]) -> bool:
    """Whether samples of palaestra ``space`` differ in type from Gymnasium's (a Graph inside).

    Adapters check this once so that the common spaces pass values through untouched.
    """
    if isinstance(space, spaces.Graph):
        return True
    if isinstance(space, (spaces.Tuple, spaces.OneOf)):
        return any(needs_value_conversion(s) for s in space.spaces)
    if isinstance(space, spaces.Dict):
        return any(needs_value_conversion(s) for s in space.spaces.values())
    if isinstance(space, spaces.Sequence):
        return needs_value_conversion(space.feature_space)
    return False


def _convert(space: spaces.Space[Any], value: Any, graph: type) -> Any:
    """Rebuild ``value`` (an element of palaestra ``space``) with graphs as ``graph`` tuples."""
    if isinstance(space, spaces.Graph):
        return graph(value.nodes, value.edges, value.edge_links)
    if isinstance(space, spaces.Tuple):
        return tuple(_convert(s, v, graph) for s, v in zip(space.spaces, value))
    if isinstance(space, spaces.Dict):
        return {k: _convert(s, value[k], graph) for k, s in space.spaces.items()}
    if isinstance(space, spaces.OneOf):
        index, inner = value
        return (index, _convert(space.spaces[int(index)], inner, graph))
    if isinstance(space, spaces.Sequence) and not space.stack:
        return tuple(_convert(space.feature_space, v, graph) for v in value)
    return value  # stacked sequences of graphs do not exist: Graph cannot be batched


def to_gymnasium_value(space: spaces.Space[Any], value: Any) -> Any:
    """An element of palaestra ``space`` as an element of ``to_gymnasium_space(space)``."""
    if not needs_value_conversion(space):
        return value
    return _convert(space, value, gym_spaces.GraphInstance)


def from_gymnasium_value(space: spaces.Space[Any], value: Any) -> Any:
    """An element of ``to_gymnasium_space(space)`` as an element of palaestra ``space``."""
    if not needs_value_conversion(space):
        return value
    return _convert(space, value, spaces.GraphInstance)
