"""``create_zero_array`` for Graph, OneOf, Sequence and Text equals Gymnasium's, so
``FrameStackObservation`` pads those observations as Gymnasium does (issue 16)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from palaestra import spaces
from palaestra.core import Env
from palaestra.wrappers import FrameStackObservation
from palaestra.wrappers.utils import create_zero_array

gym_utils = pytest.importorskip("gymnasium.wrappers.utils")
gymnasium = pytest.importorskip("gymnasium")
compat = pytest.importorskip("palaestra.compat")

SPACES = {
    "graph": spaces.Graph(spaces.Box(-1, 2, (2,)), spaces.Discrete(3, start=1)),
    "graph_no_edges": spaces.Graph(spaces.Discrete(4), None),
    "oneof": spaces.OneOf([spaces.Box(1, 2, (2,)), spaces.Discrete(2)]),
    "sequence": spaces.Sequence(spaces.Discrete(3)),
    "sequence_stacked": spaces.Sequence(spaces.Box(-1, 1, (2,)), stack=True),
    "text": spaces.Text(5, min_length=2, charset="xyz"),
}


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return ("array", str(value.dtype), value.tolist())
    if hasattr(value, "nodes"):  # GraphInstance
        return ("graph", _plain(value.nodes), _plain(value.edges), _plain(value.edge_links))
    if isinstance(value, (tuple, list)):
        return tuple(_plain(v) for v in value)
    if isinstance(value, np.generic):
        return value.item()
    return value


@pytest.mark.parametrize("name", sorted(SPACES))
def test_zero_arrays_equal_gymnasiums(name: str) -> None:
    space = SPACES[name]
    ours = create_zero_array(space)
    theirs = gym_utils.create_zero_array(compat.to_gymnasium_space(space))
    assert _plain(ours) == _plain(theirs)
    assert ours in space


class _Env(Env[Any, Any]):
    def __init__(self, space: Any) -> None:
        self.observation_space, self.action_space = space, spaces.Discrete(2)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        if seed is not None:
            self.observation_space.seed(seed)
        return self.observation_space.sample(), {}

    def step(self, action: Any) -> Any:
        return self.observation_space.sample(), 0.0, False, False, {}


@pytest.mark.parametrize("name", ["oneof", "text", "graph"])
def test_frame_stack_pads_as_gymnasium(name: str) -> None:
    import copy

    ours = FrameStackObservation(_Env(copy.deepcopy(SPACES[name])), stack_size=3)
    theirs = gymnasium.wrappers.FrameStackObservation(
        compat.to_gymnasium(_Env(copy.deepcopy(SPACES[name]))), stack_size=3
    )
    got, _ = ours.reset(seed=1)
    want, _ = theirs.reset(seed=1)
    assert _plain(got) == _plain(want)
    got = ours.step(0)[0]
    want = theirs.step(0)[0]
    assert _plain(got) == _plain(want)
