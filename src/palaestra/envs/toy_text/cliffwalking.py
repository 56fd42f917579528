"""CliffWalking-v1: walk a 4 x 12 grid from the bottom-left corner to the bottom-right one.

Gymnasium 1.x's ``CliffWalkingEnv`` (Sutton & Barto, Example 6.6): -1 per step, -100 and back
to the start for stepping onto the cliff (row 3, columns 1-10), termination at the goal;
``is_slippery`` sends a move to either side with probability 1/3 each. Same ``P``, ansi text
and seeded draws.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.envs.toy_text.tabular import TabularBatch, TabularEnv, Transitions, TransitionTable
from palaestra.error import ResetNeeded
from palaestra.rendering.toy_text import render_cliff_walking

UP, RIGHT, DOWN, LEFT = 0, 1, 2, 3
_MOVES = {UP: (-1, 0), RIGHT: (0, 1), DOWN: (1, 0), LEFT: (0, -1)}
SHAPE = (4, 12)
START = 3 * 12  # (3, 0)
GOAL = (3, 11)


def is_cliff(row: int, col: int) -> bool:
    """Row 3, columns 1 to 10."""
    return row == 3 and 1 <= col <= 10


def build_transitions(is_slippery: bool) -> Transitions:
    """Gymnasium's ``P``: each listed move with probability ``1 / len(moves)``."""
    nrow, ncol = SHAPE
    P: Transitions = {}
    for s in range(nrow * ncol):
        row, col = divmod(s, ncol)
        P[s] = {}
        for a in range(4):
            moves = [(a - 1) % 4, a, (a + 1) % 4] if is_slippery else [a]
            outcomes: list[tuple[float, int, Any, bool]] = []
            for m in moves:
                dr, dc = _MOVES[m]
                r, c = min(max(row + dr, 0), nrow - 1), min(max(col + dc, 0), ncol - 1)
                if is_cliff(r, c):
                    outcomes.append((1 / len(moves), START, -100, False))
                else:
                    outcomes.append((1 / len(moves), r * ncol + c, -1, (r, c) == GOAL))
            P[s][a] = outcomes
    return P


def _initial() -> np.ndarray:
    initial = np.zeros(SHAPE[0] * SHAPE[1])
    initial[START] = 1.0
    return initial


class CliffWalkingEnv(TabularEnv):
    """Single CliffWalking. Actions: 0 up, 1 right, 2 down, 3 left."""

    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array", "ansi"], "render_fps": 4}

    def __init__(self, render_mode: str | None = None, is_slippery: bool = False) -> None:
        self.shape = SHAPE
        self.start_state_index = START
        self.nS, self.nA = SHAPE[0] * SHAPE[1], 4
        self.is_slippery = bool(is_slippery)
        self._init_table(build_transitions(self.is_slippery), _initial())
        self._init_render(render_mode)

    def _text(self) -> str:
        parts = []
        for s in range(self.nS):
            row, col = divmod(s, SHAPE[1])
            if s == self.s:
                cell = " x "
            elif (row, col) == GOAL:
                cell = " T "
            elif is_cliff(row, col):
                cell = " C "
            else:
                cell = " o "
            if col == 0:
                cell = cell.lstrip()
            if col == SHAPE[1] - 1:
                cell = cell.rstrip() + "\n"
            parts.append(cell)
        return "".join(parts) + "\n"

    def _frame(self) -> np.ndarray:
        if self.s is None:
            raise ResetNeeded("Call reset before render.")
        return render_cliff_walking(self.s)


class CliffWalkingBatch(TabularBatch):
    """N CliffWalkings stepped as arrays."""

    def __init__(self, num_envs: int, is_slippery: bool = False) -> None:
        super().__init__(
            num_envs, TransitionTable(build_transitions(bool(is_slippery)), _initial())
        )

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture, as the single env in that state draws it;
        ``action``: the row's last action (None since its reset)."""
        return render_cliff_walking(int(self._state[row]))
