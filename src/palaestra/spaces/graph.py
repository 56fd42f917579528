"""`Graph`: node features, optional edge features and the node pairs each edge links."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from collections.abc import Sequence as PySequence
from typing import Any, Literal, NamedTuple

import numpy as np
import numpy.typing as npt

from palaestra import logger
from palaestra.error import CustomSpaceError
from palaestra.spaces.batched_samples import create_empty_array, iterate
from palaestra.spaces.batching import _differing_as_tuple, batch_differing_spaces, batch_space
from palaestra.spaces.space import InvalidMask, Space


class GraphInstance(NamedTuple):
    """One graph: ``nodes`` ``[n, ...]``, ``edges`` ``[m, ...]`` and ``edge_links`` ``[m, 2]``."""

    nodes: Any
    edges: Any | None
    edge_links: npt.NDArray[Any] | None


def _is_graph_instance(x: Any) -> bool:
    return isinstance(x, GraphInstance) or (
        isinstance(x, tuple) and getattr(x, "_fields", None) == GraphInstance._fields
    )


class Graph(Space[GraphInstance]):
    """Graphs whose node (and edge) features are elements of ``node_space`` (``edge_space``).

    >>> from palaestra.spaces import Box, Discrete
    >>> Graph(node_space=Box(-100, 100, shape=(3,)), edge_space=Discrete(3))
    Graph(Box(-100.0, 100.0, (3,), float32), Discrete(3))
    """

    def __init__(
        self,
        node_space: Space[Any],
        edge_space: Space[Any] | None,
        seed: int | np.random.Generator | None = None,
    ) -> None:
        """Build the space; ``edge_space=None`` means graphs without edges."""
        for name, space in (("node_space", node_space), ("edge_space", edge_space)):
            # Gymnasium fails later with an obscure dispatch error; say what is wrong here.
            if space is not None and not isinstance(space, Space):
                raise TypeError(
                    f"Expects `{name}` to be a palaestra Space, actual type: {type(space)}"
                )
        self.node_space = node_space
        self.edge_space = edge_space
        self.batch_node_space = batch_space(node_space, n=1)
        self.batch_edge_space = None if edge_space is None else batch_space(edge_space, n=1)
        super().__init__(None, None, seed)

    @property
    def is_np_flattenable(self) -> Literal[False]:
        """Variable size: cannot be flattened to a fixed-size Box."""
        return False

    def seed(self, seed: int | PySequence[int] | None = None) -> tuple[Any, ...]:
        """Seed this space (edge links), the node space and the edge space (if any)."""
        subspaces = [self.node_space] + ([] if self.edge_space is None else [self.edge_space])
        if seed is None:
            return (super().seed(None), *(space.seed(None) for space in subspaces))
        if isinstance(seed, int):
            super_seed = super().seed(seed)
            if len(subspaces) == 1:
                subseeds = [self.np_random.integers(np.iinfo(np.int32).max)]
            else:
                subseeds = list(self.np_random.integers(np.iinfo(np.int32).max, size=(2,)))
            # Re-seed so that int and tuple seeding leave this space in the same state.
            super().seed(seed)
            return (super_seed, *(s.seed(int(sub)) for s, sub in zip(subspaces, subseeds)))
        if isinstance(seed, (list, tuple)):
            if len(seed) != len(subspaces) + 1:
                if self.edge_space is None:
                    raise ValueError(
                        "Expects a tuple of two values for Graph and node space, "
                        f"actual length: {len(seed)}"
                    )
                raise ValueError(
                    "Expects a tuple of three values for Graph, node and edge space, "
                    f"actual length: {len(seed)}"
                )
            return (super().seed(seed[0]), *(s.seed(sub) for s, sub in zip(subspaces, seed[1:])))
        raise TypeError(f"Expects `None`, int or tuple of ints, actual type: {type(seed)}")

    def sample(
        self,
        mask: tuple[Any, Any] | None = None,
        probability: tuple[Any, Any] | None = None,
        num_nodes: int = 10,
        num_edges: int | None = None,
    ) -> GraphInstance:
        """Draw ``num_nodes`` nodes, ``num_edges`` edges (random up to n(n-1) if None) and links.

        ``mask``/``probability`` is ``(node_mask, edge_mask)``, passed to the batched subspaces.
        """
        if num_nodes <= 0:
            raise InvalidMask(
                f"The number of nodes is expected to be greater than 0, actual value: {num_nodes}"
            )
        if mask is not None and probability is not None:
            raise ValueError(
                "Only one of `mask` or `probability` can be provided, "
                f"actual values: mask={mask}, probability={probability}"
            )
        mask_type = (
            "mask" if mask is not None else "probability" if probability is not None else None
        )
        node_mask, edge_mask = mask or probability or (None, None)

        if num_edges is None:
            # Self-loops and both directions are allowed; at most n*(n-1) edges are drawn.
            num_edges = (
                int(self.np_random.integers(num_nodes * (num_nodes - 1))) if num_nodes > 1 else 0
            )
            if edge_mask is not None:
                edge_mask = tuple(edge_mask for _ in range(num_edges))
        else:
            if self.edge_space is None:
                logger.warn(f"The number of edges is set ({num_edges}) but the edge space is None.")
            if num_edges < 0:
                raise InvalidMask(
                    f"Expects the number of edges to be greater than 0, actual value: {num_edges}"
                )
        node_kwargs = {} if mask_type is None else {mask_type: node_mask}
        edge_kwargs = {} if mask_type is None else {mask_type: edge_mask}

        # batch_space copies the subspace's generator; advancing the original afterwards (as
        # Gymnasium does) keeps consecutive samples different.
        nodes = batch_space(self.node_space, num_nodes).sample(**node_kwargs)
        self.node_space.np_random.random()
        edges = edge_links = None
        if num_edges >= 1 and self.edge_space is not None:
            edges = batch_space(self.edge_space, num_edges).sample(**edge_kwargs)
            self.edge_space.np_random.random()
            edge_links = self.np_random.integers(
                low=0, high=num_nodes, size=(num_edges, 2), dtype=np.int32
            )
        return GraphInstance(nodes, edges, edge_links)

    def contains(self, x: Any) -> bool:
        """Whether ``x`` is a GraphInstance with valid nodes, edges and in-range integer links."""
        # Any GraphInstance-shaped namedtuple (e.g. gymnasium's) is accepted, for interop.
        if not _is_graph_instance(x) or x.nodes is None:
            return False
        try:  # iterate refuses what is not a batch of the space's elements: not a member
            nodes = list(iterate(self.batch_node_space, x.nodes))
        except (TypeError, CustomSpaceError):
            return False
        if not all(node in self.node_space for node in nodes):
            return False
        if x.edges is None or x.edge_links is None:
            return x.edges is None and x.edge_links is None
        if self.edge_space is None or not isinstance(x.edge_links, np.ndarray):
            return False
        assert self.batch_edge_space is not None  # set whenever edge_space is
        try:
            edges = list(iterate(self.batch_edge_space, x.edges))
        except (TypeError, CustomSpaceError):
            return False
        return bool(
            all(edge in self.edge_space for edge in edges)
            and np.issubdtype(x.edge_links.dtype, np.integer)
            and x.edge_links.shape == (len(edges), 2)
            and ((x.edge_links >= 0) & (x.edge_links < len(nodes))).all()
        )

    def __repr__(self) -> str:
        return f"Graph({self.node_space}, {self.edge_space})"

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, Graph)
            and self.node_space == other.node_space
            and self.edge_space == other.edge_space
        )

    def to_jsonable(self, sample_n: Iterable[GraphInstance]) -> list[dict[str, Any]]:
        """Each graph as ``{"nodes": ..., "edges": ..., "edge_links": ...}``."""
        result = []
        for sample in sample_n:
            item = {"nodes": self.batch_node_space.to_jsonable([sample.nodes])}
            if sample.edges is not None and sample.edge_links is not None:
                assert self.batch_edge_space is not None
                item["edges"] = self.batch_edge_space.to_jsonable([sample.edges])
                item["edge_links"] = sample.edge_links.tolist()
            result.append(item)
        return result

    def from_jsonable(self, sample_n: PySequence[dict[str, Any]]) -> list[GraphInstance]:
        """JSON dicts back to GraphInstances."""
        result = []
        for sample in sample_n:
            nodes = self.batch_node_space.from_jsonable(sample["nodes"])[0]
            if "edges" in sample and self.batch_edge_space is not None:
                edges = self.batch_edge_space.from_jsonable(sample["edges"])[0]
                links = np.asarray(sample["edge_links"], dtype=np.int32)
                result.append(GraphInstance(nodes, edges, links))
            else:
                result.append(GraphInstance(nodes, None, None))
        return result


@create_empty_array.register(Graph)
def _empty_graph(
    space: Graph, n: int = 1, fn: Callable[..., Any] = np.zeros
) -> tuple[GraphInstance, ...]:
    edge_space = space.edge_space
    return tuple(
        GraphInstance(
            nodes=create_empty_array(space.node_space, n=1, fn=fn),
            edges=None if edge_space is None else create_empty_array(edge_space, n=1, fn=fn),
            edge_links=None if edge_space is None else fn((1, 2), dtype=np.int64),
        )
        for _ in range(n)
    )


batch_differing_spaces.register(Graph)(_differing_as_tuple)
