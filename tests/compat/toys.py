"""Small palaestra envs for the interop tests: Dict observations, and a Graph observation."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

import palaestra
from palaestra import spaces


class ReachDict(palaestra.Env[dict[str, Any], int]):
    """Move a point on a 5x5 grid to a goal; the observation is a Dict of two Boxes and a
    Discrete step counter (SB3's MultiInputPolicy takes it)."""

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 4}
    MOVES = np.array([[0, 1], [0, -1], [1, 0], [-1, 0]], dtype=np.float32)

    def __init__(self, render_mode: str | None = None) -> None:
        self.observation_space = spaces.Dict(
            {
                "pos": spaces.Box(0.0, 4.0, (2,), np.float32),
                "goal": spaces.Box(0.0, 4.0, (2,), np.float32),
                "steps": spaces.Discrete(21),
            }
        )
        self.action_space = spaces.Discrete(4)
        self.render_mode = render_mode
        self.closed = 0

    def _obs(self) -> dict[str, Any]:
        return {"pos": self.pos.copy(), "goal": self.goal.copy(), "steps": self.steps}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        super().reset(seed=seed)
        self.pos = self.np_random.integers(0, 5, 2).astype(np.float32)
        self.goal = self.np_random.integers(0, 5, 2).astype(np.float32)
        self.steps = 0
        return self._obs(), {}

    def step(self, action: int) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        self.pos = np.clip(self.pos + self.MOVES[int(action)], 0, 4).astype(np.float32)
        self.steps += 1
        reached = bool((self.pos == self.goal).all())
        return self._obs(), 1.0 if reached else -0.1, reached, self.steps >= 20, {}

    def render(self) -> np.ndarray:
        frame = np.zeros((5, 5, 3), np.uint8)
        frame[int(self.pos[0]), int(self.pos[1])] = 255
        return frame

    def close(self) -> None:
        self.closed += 1


class GraphWalk(palaestra.Env[Any, Any]):
    """A graph observation and a OneOf action: the two space types whose values differ in type
    or shape between the libraries, so the adapters must convert them."""

    def __init__(self) -> None:
        self.observation_space = spaces.Graph(spaces.Box(-1, 1, (2,)), spaces.Discrete(3))
        self.action_space = spaces.OneOf(
            (spaces.Discrete(2), spaces.Graph(spaces.Discrete(4), None))
        )
        self.actions: list[Any] = []

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        super().reset(seed=seed)
        self.observation_space.seed(int(self.np_random.integers(2**31)))
        return self.observation_space.sample(num_nodes=3, num_edges=2), {}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        assert action in self.action_space, action
        self.actions.append(action)
        return self.observation_space.sample(num_nodes=2, num_edges=1), 0.0, False, False, {}
