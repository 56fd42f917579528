"""FrozenLake-v1: cross a frozen lake from S to G without falling into a hole (H).

Gymnasium 1.x's ``FrozenLakeEnv``: the same maps, ``P`` table (slippery moves go sideways
with ``(1 - success_rate) / 2`` each), rewards from ``reward_schedule`` (goal, hole,
frozen), ``info["prob"]``, ansi text and seeded draws. ``generate_random_map`` draws the same
maps as Gymnasium's for the same seed. Bad maps (no start, no goal, ragged rows, unknown
letters) raise ``ValueError`` here where Gymnasium would build a broken env.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import Any

import numpy as np

from palaestra.envs.toy_text.tabular import TabularBatch, TabularEnv, Transitions, TransitionTable
from palaestra.error import ResetNeeded
from palaestra.rendering.toy_text import render_frozen_lake
from palaestra.utils.colorize import colorize
from palaestra.utils.seeding import np_random

LEFT, DOWN, RIGHT, UP = 0, 1, 2, 3
_ACTION_NAMES = ["Left", "Down", "Right", "Up"]
_LETTERS = "SFHG"

MAPS: dict[str, list[str]] = {
    "4x4": ["SFFF", "FHFH", "FFFH", "HFFG"],
    "8x8": [
        "SFFFFFFF",
        "FFFFFFFF",
        "FFFHFFFF",
        "FFFFFHFF",
        "FFFHFFFF",
        "FHHFFFHF",
        "FHFFHFHF",
        "FFFHFFFG",
    ],
}


def _reachable(board: np.ndarray) -> bool:
    """Whether the bottom-right corner can be reached from the top-left one avoiding holes."""
    size = board.shape[0]
    seen = {(0, 0)}
    frontier = deque([(0, 0)])
    while frontier:
        r, c = frontier.popleft()
        for nr, nc in ((r + 1, c), (r, c + 1), (r - 1, c), (r, c - 1)):
            if 0 <= nr < size and 0 <= nc < size and (nr, nc) not in seen:
                if nr == nc == size - 1:
                    return True
                if not board[nr, nc]:  # True marks a hole
                    seen.add((nr, nc))
                    frontier.append((nr, nc))
    return False


def generate_random_map(size: int = 8, p: float = 0.8, seed: int | None = None) -> list[str]:
    """A random ``size`` x ``size`` map with a path from S (top left) to G (bottom right).

    Each other tile is frozen with probability ``p``, else a hole; maps without a path are
    drawn again. The same ``seed`` gives the same map as Gymnasium's ``generate_random_map``.

    >>> generate_random_map(4, seed=3)
    ['SFHF', 'FFFF', 'FFFF', 'FFFG']
    """
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)):
        raise TypeError(f"size must be an int, got {size!r} ({type(size).__name__})")
    if size < 2:
        # Gymnasium loops forever on size 1: S and G would share the only tile.
        raise ValueError(f"size must be at least 2 (a start and a goal tile), got {size}")
    if isinstance(p, bool) or not isinstance(p, (int, float, np.integer, np.floating)):
        raise TypeError(f"p must be a number in (0, 1], got {p!r} ({type(p).__name__})")
    if not 0 < p <= 1:
        why = "every tile would be a hole: no map has a path" if p == 0 else ""
        raise ValueError(
            f"p must be a probability in (0, 1], got {p!r}{' (' + why + ')' if why else ''}"
        )
    rng, _ = np_random(seed)
    size = int(size)
    while True:
        # choice over two items with these weights: the draws of Gymnasium's choice(["F", "H"])
        holes = rng.choice(2, (size, size), p=[p, 1 - p]).astype(bool)
        holes[0, 0] = holes[-1, -1] = False
        if _reachable(holes):
            break
    rows = [["H" if h else "F" for h in row] for row in holes.tolist()]
    rows[0][0], rows[-1][-1] = "S", "G"
    return ["".join(row) for row in rows]


def parse_map(desc: Any) -> np.ndarray:
    """A map (rows of letters S, F, H, G) as Gymnasium's ``desc``: a ``[nrow, ncol]`` bytes
    array. Raises ``ValueError`` naming what is wrong with a bad one."""
    if isinstance(desc, (str, bytes)) or not isinstance(desc, (Sequence, np.ndarray)):
        raise ValueError(
            f"desc must be a list of rows (strings of S, F, H, G), got {desc!r} "
            f"({type(desc).__name__})"
        )
    rows = []
    for i, row in enumerate(desc):
        if isinstance(row, bytes):
            row = row.decode("ascii", errors="replace")
        elif isinstance(row, np.ndarray):
            row = "".join(c.decode() if isinstance(c, bytes) else str(c) for c in row.tolist())
        elif not isinstance(row, str):
            row = "".join(c.decode() if isinstance(c, bytes) else str(c) for c in row)
        rows.append(row)
        for j, letter in enumerate(row):
            if letter not in _LETTERS:
                raise ValueError(
                    f"Unknown letter {letter!r} at row {i}, column {j} of the map {list(desc)!r}: "
                    "tiles are S (start), F (frozen), H (hole), G (goal)"
                )
    if not rows or not rows[0]:
        raise ValueError(f"The map {desc!r} is empty: it needs at least a start and a goal")
    lengths = [len(row) for row in rows]
    if len(set(lengths)) != 1:
        raise ValueError(f"The map's rows have different lengths {lengths}: {rows!r}")
    text = "".join(rows)
    if "S" not in text:
        raise ValueError(f"The map {rows!r} has no start tile 'S'")
    if "G" not in text:
        raise ValueError(f"The map {rows!r} has no goal tile 'G'")
    return np.asarray(rows, dtype="c")


def build_transitions(
    desc: np.ndarray, is_slippery: bool, success_rate: float, reward_schedule: Sequence[Any]
) -> Transitions:
    """Gymnasium's ``P`` for a map: G and H absorb; a slippery move goes to either side of
    the intended direction with probability ``(1 - success_rate) / 2`` each."""
    nrow, ncol = desc.shape
    fail_rate = (1.0 - success_rate) / 2.0
    goal_r, hole_r, frozen_r = reward_schedule

    def move(row: int, col: int, a: int) -> tuple[int, Any, bool]:
        if a == LEFT:
            col = max(col - 1, 0)
        elif a == DOWN:
            row = min(row + 1, nrow - 1)
        elif a == RIGHT:
            col = min(col + 1, ncol - 1)
        else:
            row = max(row - 1, 0)
        letter = desc[row, col]
        reward = goal_r if letter == b"G" else hole_r if letter == b"H" else frozen_r
        return row * ncol + col, reward, letter in (b"G", b"H")

    P: Transitions = {}
    for row in range(nrow):
        for col in range(ncol):
            s = row * ncol + col
            P[s] = {}
            for a in range(4):
                if desc[row, col] in (b"G", b"H"):
                    P[s][a] = [(1.0, s, 0, True)]
                elif is_slippery:
                    P[s][a] = [
                        (success_rate if b == a else fail_rate, *move(row, col, b))
                        for b in ((a - 1) % 4, a, (a + 1) % 4)
                    ]
                else:
                    P[s][a] = [(1.0, *move(row, col, a))]
    return P


def _check_options(
    is_slippery: Any, success_rate: Any, reward_schedule: Any
) -> tuple[Any, tuple[Any, ...]]:
    if not isinstance(success_rate, (int, float, np.integer, np.floating)) or isinstance(
        success_rate, bool
    ):
        raise TypeError(f"success_rate must be a number in [0, 1], got {success_rate!r}")
    if not 0.0 <= success_rate <= 1.0:
        raise ValueError(f"success_rate must be a probability in [0, 1], got {success_rate!r}")
    schedule = tuple(reward_schedule)
    if len(schedule) != 3 or not all(
        isinstance(r, (int, float, np.integer, np.floating)) for r in schedule
    ):
        raise ValueError(
            f"reward_schedule must be 3 numbers (goal, hole, frozen), got {reward_schedule!r}"
        )
    return success_rate, schedule  # kept as given: P holds it as Gymnasium's does


def _resolve_map(desc: Any, map_name: str | None) -> np.ndarray:
    if desc is None and map_name is None:
        return parse_map(generate_random_map())
    if desc is None:
        if map_name not in MAPS:
            raise ValueError(f"Unknown map_name {map_name!r}: expected one of {list(MAPS)}")
        return parse_map(MAPS[map_name])
    return parse_map(desc)


def _initial(desc: np.ndarray) -> np.ndarray:
    initial = (desc == b"S").astype(np.float64).ravel()
    return initial / initial.sum()


class FrozenLakeEnv(TabularEnv):
    """Single FrozenLake (Gymnasium's arguments). Actions: 0 left, 1 down, 2 right, 3 up."""

    metadata: dict[str, Any] = {"render_modes": ["human", "ansi", "rgb_array"], "render_fps": 4}

    def __init__(
        self,
        render_mode: str | None = None,
        desc: list[str] | None = None,
        map_name: str | None = "4x4",
        is_slippery: bool = True,
        success_rate: float = 1.0 / 3.0,
        reward_schedule: tuple[int, int, int] = (1, 0, 0),
    ) -> None:
        success_rate, schedule = _check_options(is_slippery, success_rate, reward_schedule)
        self.desc = _resolve_map(desc, map_name)
        self.nrow, self.ncol = self.desc.shape
        self.reward_range = (min(schedule), max(schedule))
        P = build_transitions(self.desc, bool(is_slippery), success_rate, schedule)
        self._init_table(P, _initial(self.desc))
        self._init_render(render_mode)

    def _text(self) -> str:
        assert self.s is not None
        grid = [[c.decode() for c in line] for line in self.desc.tolist()]
        row, col = divmod(self.s, self.ncol)
        grid[row][col] = colorize(grid[row][col], "red", highlight=True)
        head = f"  ({_ACTION_NAMES[self.lastaction]})\n" if self.lastaction is not None else "\n"
        return head + "\n".join("".join(line) for line in grid) + "\n"

    def _frame(self) -> np.ndarray:
        if self.s is None:
            raise ResetNeeded("Call reset before render.")
        return render_frozen_lake(self.desc, self.s, self.lastaction)


class FrozenLakeBatch(TabularBatch):
    """N FrozenLakes (same arguments as the env, minus rendering) stepped as arrays.

    All rows share one map: with ``desc=None, map_name=None`` that is one random map, where N
    separate envs would each draw their own.
    """

    def __init__(
        self,
        num_envs: int,
        desc: list[str] | None = None,
        map_name: str | None = "4x4",
        is_slippery: bool = True,
        success_rate: float = 1.0 / 3.0,
        reward_schedule: tuple[int, int, int] = (1, 0, 0),
    ) -> None:
        success_rate, schedule = _check_options(is_slippery, success_rate, reward_schedule)
        self.desc = _resolve_map(desc, map_name)
        P = build_transitions(self.desc, bool(is_slippery), success_rate, schedule)
        super().__init__(num_envs, TransitionTable(P, _initial(self.desc)))

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture, as the single env in that state draws it;
        ``action``: the row's last action (None since its reset)."""
        last = None if action is None else int(action)
        return render_frozen_lake(self.desc, int(self._state[row]), last)
