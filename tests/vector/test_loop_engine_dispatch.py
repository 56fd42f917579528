"""The loop engine's direct calls for array spaces leave subclasses to their own registrations."""

from __future__ import annotations

from typing import Any

import numpy as np

import palaestra as gym
from palaestra.spaces import Box
from palaestra.spaces.batched_samples import concatenate, iterate
from palaestra.vector.engine import LoopEngine


class TaggedBox(Box):
    """A Box subclass with its own batching functions (counted)."""


CALLS = {"concatenate": 0, "iterate": 0}


@concatenate.register(TaggedBox)
def _concatenate_tagged(space: Any, items: Any, out: np.ndarray) -> np.ndarray:
    CALLS["concatenate"] += 1
    return np.stack(list(items), axis=0, out=out)


@iterate.register(TaggedBox)
def _iterate_tagged(space: Any, items: Any) -> Any:
    CALLS["iterate"] += 1
    return iter(items)


class TaggedEnv(gym.Env):
    """Observations and actions in a ``TaggedBox``."""

    def __init__(self) -> None:
        self.observation_space = TaggedBox(-1.0, 1.0, (2,), np.float32)
        self.action_space = Box(-1.0, 1.0, (1,), np.float32)

    def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[Any, dict]:
        return np.zeros(2, np.float32), {}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        return np.full(2, float(action[0]), np.float32), 0.0, False, False, {}


def test_array_spaces_step_like_the_dispatch_and_subclasses_keep_theirs() -> None:
    engine = LoopEngine([TaggedEnv, TaggedEnv], "same", "test")
    engine.reset(None, [0, 1], None)
    assert CALLS["concatenate"] == 1  # the subclass's own function, not the Box one
    engine.step_send(np.array([[0.25], [-0.5]], np.float32), None)
    engine.step_recv()
    assert CALLS["concatenate"] == 2
    assert engine.obs.tolist() == [[0.25, 0.25], [-0.5, -0.5]]
    # Box actions (exact type) are walked row by row, as iterate would
    engine.step_send([np.array([0.75], np.float32), np.array([1.0], np.float32)], None)
    engine.step_recv()
    assert engine.obs.tolist() == [[0.75, 0.75], [1.0, 1.0]]
