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
from collections.abc import Callable
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


# -- palaestra <-> Gymnasium -----------------------------------------------------------------
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


@functools.singledispatch
def from_gymnasium_space(space: Any) -> spaces.Space[Any]:
    """The palaestra space with the same elements as Gymnasium ``space``.

    >>> import gymnasium
    >>> from_gymnasium_space(gymnasium.spaces.MultiDiscrete([2, 3]))
    MultiDiscrete([2 3])
    """
    raise _unsupported(space, "from_gymnasium_space", "Gymnasium")


# The two libraries' space classes share their names and constructor arguments, so one recipe
# per kind rebuilds a space in either direction: ``lib`` is the target library's ``spaces``
# module, ``convert`` the conversion (the same direction) for subspaces.
def _box(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    low = _bound(space.low, space.bounded_below, -np.inf)
    high = _bound(space.high, space.bounded_above, np.inf)
    return lib.Box(low, high, space.shape, space.dtype)


def _discrete(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    return lib.Discrete(int(space.n), start=int(space.start), dtype=space.dtype)


def _multi_discrete(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    return lib.MultiDiscrete(space.nvec.copy(), dtype=space.dtype, start=space.start.copy())


def _multi_binary(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    return lib.MultiBinary(space.n)


def _text(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    # A string charset keeps the character order, which decides what a seeded sample draws.
    return lib.Text(
        space.max_length, min_length=space.min_length, charset="".join(space.character_list)
    )


def _tuple(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    return lib.Tuple([convert(s) for s in space.spaces])


def _dict(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    # A list of pairs keeps the key order (a mapping would be re-sorted).
    return lib.Dict([(k, convert(s)) for k, s in space.spaces.items()])


def _sequence(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    return lib.Sequence(convert(space.feature_space), stack=space.stack)


def _graph(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    edge = None if space.edge_space is None else convert(space.edge_space)
    return lib.Graph(convert(space.node_space), edge)


def _one_of(space: Any, lib: Any, convert: Callable[[Any], Any]) -> Any:
    return lib.OneOf([convert(s) for s in space.spaces])


_REBUILD = {
    "Box": _box,
    "Discrete": _discrete,
    "MultiDiscrete": _multi_discrete,
    "MultiBinary": _multi_binary,
    "Text": _text,
    "Tuple": _tuple,
    "Dict": _dict,
    "Sequence": _sequence,
    "Graph": _graph,
    "OneOf": _one_of,
}
for _name, _rebuild in _REBUILD.items():
    to_gymnasium_space.register(
        getattr(spaces, _name),
        functools.partial(_rebuild, lib=gym_spaces, convert=to_gymnasium_space),
    )
    from_gymnasium_space.register(
        getattr(gym_spaces, _name),
        functools.partial(_rebuild, lib=spaces, convert=from_gymnasium_space),
    )
del _name, _rebuild


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
