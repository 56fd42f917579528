"""Taxi-v4: pick a passenger up at one of four stands and drop them at their destination.

Gymnasium 1.x's ``TaxiEnv`` (Dietterich 2000): 500 states ``((row * 5 + col) * 5 + passenger)
* 4 + destination``, -1 per step, -10 for an illegal pickup/dropoff, +20 for delivering;
``is_rainy`` makes a move slip sideways (``rainy_probability`` forward), ``fickle_passenger``
lets a just-picked-up passenger change destination once (``fickle_probability`` per episode).
Same ``P``, ``info["action_mask"]``, ansi text and seeded draws.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.envs.toy_text.tabular import TabularBatch, TabularEnv, Transitions, TransitionTable
from palaestra.error import ResetNeeded
from palaestra.rendering.toy_text import render_taxi
from palaestra.utils.colorize import colorize

MAP = [
    "+---------+",
    "|R: | : :G|",
    "| : | : : |",
    "| : : : : |",
    "| | : | : |",
    "|Y| : |B: |",
    "+---------+",
]
LOCS = [(0, 0), (0, 4), (4, 0), (4, 3)]  # R, G, Y, B
_DESC = np.asarray(MAP, dtype="c")
_ACTION_NAMES = ["South", "North", "East", "West", "Pickup", "Dropoff"]
# (forward, left, right) for south, north, east, west under rain (Gymnasium's convention).
_RAINY_MOVES = {
    0: ((1, 0), (0, 1), (0, -1)),
    1: ((-1, 0), (0, -1), (0, 1)),
    2: ((0, 1), (-1, 0), (1, 0)),
    3: ((0, -1), (1, 0), (-1, 0)),
}


def encode(taxi_row: Any, taxi_col: Any, pass_loc: Any, dest_idx: Any) -> Any:
    """The state number of a taxi position, passenger location (4: in the taxi), destination.

    Gymnasium's argument names (``env.unwrapped.encode(taxi_row=..., ...)``); ints or arrays.
    """
    return ((taxi_row * 5 + taxi_col) * 5 + pass_loc) * 4 + dest_idx


def decode(i: Any) -> tuple[Any, Any, Any, Any]:
    """``(taxi_row, taxi_col, pass_loc, dest_idx)`` of a state number ``i`` (ints or arrays;
    Gymnasium's argument name)."""
    rest, destination = divmod(i, 4)
    rest, passenger = divmod(rest, 5)
    row, col = divmod(rest, 5)
    return row, col, passenger, destination


def _open_east(row: int, col: int) -> bool:
    return bool(_DESC[1 + row, 2 * col + 2] == b":")


def _open_west(row: int, col: int) -> bool:
    return bool(_DESC[1 + row, 2 * col] == b":")


def _pickup(row: int, col: int, passenger: int) -> tuple[int, int]:
    """``(passenger, reward)``: -10 unless the passenger waits at the taxi's stand."""
    if passenger < 4 and (row, col) == LOCS[passenger]:
        return 4, -1
    return passenger, -10


def _dropoff(row: int, col: int, passenger: int, dest: int) -> tuple[int, int, bool]:
    """``(passenger, reward, terminated)``: +20 at the destination, free at another stand."""
    if passenger == 4 and (row, col) == LOCS[dest]:
        return dest, 20, True
    if passenger == 4 and (row, col) in LOCS:
        return LOCS.index((row, col)), -1, False
    return passenger, -10, False


def _slide(row: int, col: int, move: tuple[int, int]) -> tuple[int, int]:
    """A rainy sideways move: clamped to the grid, cancelled by a wall (Gymnasium's check)."""
    dr, dc = move
    r, c = max(0, min(row + dr, 4)), max(0, min(col + dc, 4))
    if dc == 1 and _DESC[1 + r, 2 * c] != b":":
        return row, col
    if dc == -1 and _DESC[1 + r, 2 * c + 2] != b":":
        return row, col
    return r, c


def _transitions(
    row: int, col: int, passenger: int, dest: int, action: int, rainy: float | None
) -> list[tuple[float, int, Any, bool]]:
    """``P[s][action]``; ``rainy`` is the forward probability, None when dry."""
    r, c, p, reward, terminated = row, col, passenger, -1, False
    can_move = (
        (action == 0 and row < 4)
        or (action == 1 and row > 0)
        or (action == 2 and _open_east(row, col))
        or (action == 3 and _open_west(row, col))
    )
    if can_move:
        dr, dc = _RAINY_MOVES[action][0]
        r, c = max(0, min(row + dr, 4)), max(0, min(col + dc, 4))
    elif action == 4:
        p, reward = _pickup(row, col, passenger)
    elif action == 5:
        p, reward, terminated = _dropoff(row, col, passenger, dest)
    if rainy is None or action > 3:
        return [(1.0, encode(r, c, p, dest), reward, terminated)]
    left = right = (row, col)
    if can_move:
        left = _slide(row, col, _RAINY_MOVES[action][1])
        right = _slide(row, col, _RAINY_MOVES[action][2])
    side = (1.0 - rainy) / 2.0
    return [
        (rainy, encode(r, c, p, dest), -1, terminated),
        (side, encode(*left, p, dest), -1, terminated),
        (side, encode(*right, p, dest), -1, terminated),
    ]


def build_transitions(is_rainy: bool, rainy_probability: float) -> Transitions:
    """Gymnasium's ``P`` for the dry or the rainy taxi."""
    rainy = rainy_probability if is_rainy else None
    P: Transitions = {}
    for s in range(500):
        row, col, passenger, dest = decode(s)
        P[s] = {a: _transitions(row, col, passenger, dest, a, rainy) for a in range(6)}
    return P


def initial_distribution() -> np.ndarray:
    """Uniform over the 300 states with the passenger at a stand other than the destination."""
    initial = np.zeros(500)
    for s in range(500):
        _, _, passenger, dest = decode(s)
        if passenger < 4 and passenger != dest:
            initial[s] += 1
    return initial / initial.sum()


def action_mask(state: int) -> np.ndarray:
    """The actions that change the state (Gymnasium's ``action_mask``), int8 ``[6]``."""
    row, col, passenger, dest = decode(state)
    mask = np.zeros(6, dtype=np.int8)
    mask[0] = row < 4
    mask[1] = row > 0
    mask[2] = col < 4 and _open_east(row, col)
    mask[3] = col > 0 and _open_west(row, col)
    mask[4] = passenger < 4 and (row, col) == LOCS[passenger]
    mask[5] = passenger == 4 and ((row, col) == LOCS[dest] or (row, col) in LOCS)
    return mask


_MASKS = np.stack([action_mask(s) for s in range(500)])  # [500, 6] int8
_MASKS.flags.writeable = False


def _check(rainy_probability: Any, fickle_probability: Any) -> None:
    for name, value in (
        ("rainy_probability", rainy_probability),
        ("fickle_probability", fickle_probability),
    ):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise TypeError(f"{name} must be a number in [0, 1], got {value!r}")
        if not 0.0 <= value <= 1.0:
            raise ValueError(f"{name} must be a probability in [0, 1], got {value!r}")


class TaxiEnv(TabularEnv):
    """Single Taxi. Actions: 0 south, 1 north, 2 east, 3 west, 4 pickup, 5 dropoff."""

    metadata: dict[str, Any] = {"render_modes": ["human", "ansi", "rgb_array"], "render_fps": 4}
    reset_prob = 1.0

    def __init__(
        self,
        render_mode: str | None = None,
        is_rainy: bool = False,
        fickle_passenger: bool = False,
        rainy_probability: float = 0.8,
        fickle_probability: float = 0.3,
    ) -> None:
        _check(rainy_probability, fickle_probability)
        self.desc = _DESC.copy()
        self.locs = list(LOCS)
        self.rainy_probability = rainy_probability
        self.fickle_probability = fickle_probability
        self.fickle_passenger = bool(fickle_passenger)
        self.fickle_step = False
        self.taxi_orientation = 0
        P = build_transitions(bool(is_rainy), rainy_probability)
        self._init_table(P, initial_distribution())
        self._init_render(render_mode)

    encode = staticmethod(encode)
    decode = staticmethod(decode)

    def action_mask(self, state: int) -> np.ndarray:
        """The actions that change ``state``: int8 ``[6]``."""
        return _MASKS[state].copy()

    def _info(self, prob: Any, s: int) -> dict[str, Any]:
        return {"prob": prob, "action_mask": _MASKS[s].copy()}

    def _after_reset(self) -> None:
        self.fickle_step = (
            self.fickle_passenger and self.np_random.random() < self.fickle_probability
        )
        self.taxi_orientation = 0

    def _after_move(self, old: int, new: int) -> int:
        if not (self.fickle_passenger and self.fickle_step):
            return new
        old_row, old_col, old_passenger, old_dest = decode(old)
        row, col, passenger, _ = decode(new)
        if old_passenger != 4 or (row == old_row and col == old_col):
            return new
        # Once per episode, the passenger who has been aboard a step picks another destination:
        # Gymnasium's choice among the three others (integers(3) draws the same).
        self.fickle_step = False
        j = int(self.np_random.integers(3))
        return encode(row, col, passenger, j + (j >= old_dest))

    def _text(self) -> str:
        assert self.s is not None
        out = [[c.decode() for c in line] for line in self.desc.tolist()]
        row, col, passenger, dest = decode(self.s)
        if passenger < 4:
            out[1 + row][2 * col + 1] = colorize(
                out[1 + row][2 * col + 1], "yellow", highlight=True
            )
            pi, pj = LOCS[passenger]
            out[1 + pi][2 * pj + 1] = colorize(out[1 + pi][2 * pj + 1], "blue", bold=True)
        else:  # passenger in the taxi: a blank cell shows as "_"
            cell = out[1 + row][2 * col + 1]
            out[1 + row][2 * col + 1] = colorize(
                "_" if cell == " " else cell, "green", highlight=True
            )
        di, dj = LOCS[dest]
        out[1 + di][2 * dj + 1] = colorize(out[1 + di][2 * dj + 1], "magenta")
        text = "\n".join("".join(line) for line in out) + "\n"
        if self.lastaction is not None:
            return text + f"  ({_ACTION_NAMES[self.lastaction]})\n"
        return text + "\n"

    def _frame(self) -> np.ndarray:
        if self.s is None:
            raise ResetNeeded("Call reset before render.")
        if self.lastaction is not None and self.lastaction < 4:
            self.taxi_orientation = self.lastaction  # the taxi faces its last move
        return render_taxi(self.s, self.taxi_orientation)


class TaxiBatch(TabularBatch):
    """N Taxis stepped as arrays (the fickle destination change included)."""

    RUN_STATE = (*TabularBatch.RUN_STATE, "_fickle_step")
    reset_prob = 1.0

    def __init__(
        self,
        num_envs: int,
        is_rainy: bool = False,
        fickle_passenger: bool = False,
        rainy_probability: float = 0.8,
        fickle_probability: float = 0.3,
    ) -> None:
        _check(rainy_probability, fickle_probability)
        P = build_transitions(bool(is_rainy), rainy_probability)
        super().__init__(num_envs, TransitionTable(P, initial_distribution()))
        self.fickle_passenger = bool(fickle_passenger)
        self.fickle_probability = fickle_probability
        self._fickle_step = np.zeros(self.num_envs, dtype=bool)  # [N]
        # [N] the way each taxi faces in pictures: 0 at reset, then its last move drawn, as
        # the single env's taxi_orientation (only frames read it).
        self._orientation = np.zeros(self.num_envs, dtype=np.int64)

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture, as the single env in that state draws it;
        ``action``: the row's last action (None since its reset)."""
        if action is not None and int(action) < 4:
            self._orientation[row] = int(action)  # the taxi faces its last move
        return render_taxi(int(self._state[row]), int(self._orientation[row]))

    def _info_arrays(self, prob: np.ndarray) -> dict[str, np.ndarray]:
        return {"prob": prob, "action_mask": _MASKS[self._state]}  # [N, 6] int8, a new array

    def _after_reset(self, rows: np.ndarray) -> None:
        self._orientation[rows] = 0
        if self.fickle_passenger:
            self._fickle_step[rows] = self._streams.doubles(rows) < self.fickle_probability

    def _after_move(self, rows: np.ndarray, old: np.ndarray, new: np.ndarray) -> np.ndarray:
        if not self.fickle_passenger:
            return new
        old_row, old_col, old_passenger, old_dest = decode(old)
        row, col, passenger, _ = decode(new)
        fickle = (
            self._fickle_step[rows] & (old_passenger == 4) & ((row != old_row) | (col != old_col))
        )
        hit = np.flatnonzero(fickle)  # [F] positions within rows
        if len(hit):
            self._fickle_step[rows[hit]] = False
            j = self._streams.bounded(rows[hit], 3)
            new = new.copy()
            new[hit] = encode(row[hit], col[hit], passenger[hit], j + (j >= old_dest[hit]))
        return new
