"""Tabular MDPs (FrozenLake, CliffWalking, Taxi): one transition table, two faces.

Each env builds Gymnasium's ``P`` (``P[s][a]`` = list of ``(prob, next_state, reward,
terminated)``) and its initial-state distribution; :class:`TransitionTable` turns both into
the engine that the single env and the batch step through:

- a step draws one uniform ``u`` and takes the first outcome whose cumulative probability
  exceeds ``u`` -- Gymnasium's ``categorical_sample``, ``argmax(cumsum(p) > u)``, including
  its fallback to outcome 0 when rounding leaves ``u`` above the last cumulative value;
- a reset draws one uniform and takes the first state whose cumulative initial probability
  exceeds it, the same way.

The single env reads the table as Python tuples (a step is a dict-free lookup and one
``Generator.random()``); the batch reads it as flat arrays indexed by ``state * nA + action``
(one gather per quantity, no loop over rows). Both are built from the same cumulative sums.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.action_checks import check_discrete_action
from palaestra.envs.toy_text._common import ToyTextBatch, ToyTextEnv
from palaestra.spaces import Discrete
from palaestra.utils.stacked_infos import StackedInfos

Transitions = dict[int, dict[int, list[tuple[float, int, Any, bool]]]]


class TransitionTable:
    """``P`` and the initial distribution as lookup tables for both faces.

    ``outcomes[s][a]`` is a tuple of ``(threshold, (prob, next_state, reward, terminated))``
    for the single env; the ``[S * A, ...]`` arrays serve the batch. Outcome lists are padded
    to ``K + 1`` entries, the extra entry (index "no threshold exceeded") repeating outcome 0.
    """

    def __init__(self, P: Transitions, initial: np.ndarray) -> None:
        n_states, n_actions = len(P), len(P[0])
        self.n_states, self.n_actions = n_states, n_actions
        k = max(len(P[s][a]) for s in range(n_states) for a in range(n_actions))
        self.k = k
        rows = n_states * n_actions
        self.cum = np.full((rows, k), np.inf)  # [S*A, K] thresholds; padding never exceeded
        self.next_state = np.zeros((rows, k + 1), dtype=np.int64)  # [S*A, K+1]
        self.reward = np.zeros((rows, k + 1))
        self.terminated = np.zeros((rows, k + 1), dtype=bool)
        self.prob = np.zeros((rows, k + 1))
        outcomes: list[tuple[tuple[tuple[float, Any], ...], ...]] = []
        for s in range(n_states):
            per_action = []
            for a in range(n_actions):
                trans = P[s][a]
                cum = np.cumsum([t[0] for t in trans])  # as categorical_sample sums them
                i = s * n_actions + a
                self.cum[i, : len(trans)] = cum
                padded = list(trans) + [trans[0]] * (k + 1 - len(trans))
                for j, (p, nxt, r, t) in enumerate(padded):
                    self.prob[i, j], self.next_state[i, j] = p, nxt
                    self.reward[i, j], self.terminated[i, j] = r, t
                per_action.append(
                    tuple(
                        (float(c), (t[0], int(t[1]), t[2], bool(t[3]))) for c, t in zip(cum, trans)
                    )
                )
            outcomes.append(tuple(per_action))
        self.outcomes = tuple(outcomes)
        # Every outcome list is one certain outcome (no slipping): its threshold 1.0 always
        # exceeds u < 1, so the batch skips the comparison (the uniform is still drawn).
        self.certain = k == 1 and bool((self.cum[:, 0] >= 1.0).all())
        self.initial_cum = np.cumsum(np.asarray(initial, dtype=np.float64))  # [S]
        self.flat = tuple(a.reshape(-1) for a in (self.next_state, self.reward, self.terminated))
        self.flat_prob = self.prob.reshape(-1)
        self.cum_columns = tuple(np.ascontiguousarray(self.cum[:, j]) for j in range(k))

    def sample(self, s: int, a: int, u: float) -> tuple[Any, int, Any, bool]:
        """The outcome ``(prob, next_state, reward, terminated)`` that ``u`` selects."""
        outcomes = self.outcomes[s][a]
        for threshold, outcome in outcomes:
            if threshold > u:
                return outcome
        return outcomes[0][1]  # argmax of an all-False array is 0

    def initial_state(self, u: float | np.ndarray) -> Any:
        """The initial state(s) that uniform(s) ``u`` select (0 if ``u`` is past the sum)."""
        s = np.searchsorted(self.initial_cum, u, side="right")
        return np.where(s >= self.n_states, 0, s)


class TabularEnv(ToyTextEnv):
    """A single tabular env: ``P``, ``s``, ``lastaction`` and Gymnasium's step and reset.

    Subclasses build ``P`` and the initial distribution, then call :meth:`_init_table`.
    """

    s: int | None = None
    lastaction: int | None = None
    reset_prob: Any = 1  # the info["prob"] of a reset (Gymnasium: int 1, Taxi's 1.0)

    def _init_table(self, P: Transitions, initial: np.ndarray) -> None:
        self.P = P
        self.initial_state_distrib = initial
        self.table = TransitionTable(P, initial)
        self.observation_space = Discrete(self.table.n_states)
        self.action_space = Discrete(self.table.n_actions)

    def step(self, action: Any) -> tuple[int, Any, bool, bool, dict[str, Any]]:
        """Take ``action``; the outcome is drawn from ``P[s][action]``."""
        n = self.table.n_actions
        if type(action) is not int or not 0 <= action < n:
            action = check_discrete_action(action, self.action_space, n)
        if self.s is None:
            raise error.ResetNeeded("Call reset before using step method.")
        p, s, r, t = self.table.sample(self.s, action, self.np_random.random())
        s = self._after_move(self.s, s)
        self.s = s
        self.lastaction = action
        if self.render_mode == "human":
            self.render()
        return s, r, t, False, self._info(p, s)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[int, dict[str, Any]]:
        """Draw the start state from the initial distribution."""
        super().reset(seed=seed)
        self.s = int(self.table.initial_state(self.np_random.random()))
        self.lastaction = None
        self._after_reset()
        if self.render_mode == "human":
            self.render()
        return self.s, self._info(self.reset_prob, self.s)

    def _after_move(self, old: int, new: int) -> int:
        """Taxi's fickle passenger changes the state after the move; others keep it."""
        return new

    def _after_reset(self) -> None:
        """Taxi draws its fickle flag here."""

    def _info(self, prob: Any, s: int) -> dict[str, Any]:
        return {"prob": prob}


class TabularBatch(ToyTextBatch):
    """N copies of a tabular env, stepped through the table's arrays."""

    RUN_STATE = (*ToyTextBatch.RUN_STATE, "_state", "_obs", "_prob")
    reset_prob: Any = 1

    def __init__(self, num_envs: int, table: TransitionTable) -> None:
        super().__init__(num_envs)
        self.table = table
        self.single_observation_space = Discrete(table.n_states)
        self.single_action_space = Discrete(table.n_actions)
        n = self.num_envs
        self._state = np.zeros(n, dtype=np.int64)  # [N]
        self._obs = np.zeros(n, dtype=np.int64)  # [N], what callers see
        self._prob = np.zeros(n)  # [N] info["prob"] of the last step
        self._reward = np.zeros(n)  # [N]
        self._terminated = np.zeros(n, dtype=bool)  # [N]

    @property
    def state(self) -> np.ndarray:
        """The ``[N]`` int64 states (row i is env i's ``s``)."""
        return self._state

    def _reset_rows(self, rows: np.ndarray, mask: np.ndarray | None) -> Any:
        self._state[rows] = self.table.initial_state(self._streams.doubles(rows))
        self._after_reset(rows)
        self._obs[rows] = self._state[rows]
        return self._reset_infos(rows, mask)

    def _after_reset(self, rows: np.ndarray) -> None:
        """Taxi draws its fickle flags here."""

    def _reset_infos(self, rows: np.ndarray, mask: np.ndarray | None) -> Any:
        prob = np.full(self.num_envs, self.reset_prob)  # int64 for int 1, as Gymnasium stacks
        return StackedInfos(self._info_arrays(prob), self.num_envs, mask)

    def _info_arrays(self, prob: np.ndarray) -> dict[str, np.ndarray]:
        return {"prob": prob}

    def _step_rows(self, rows: np.ndarray, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        table = self.table
        every = rows is self._all  # the usual case: whole arrays, no index gathers
        at = slice(None) if every else rows
        u = self._streams.doubles(None if every else rows)  # [R], drawn even if certain
        old = self._state[at]
        sa = old * table.n_actions + actions  # [R]
        if table.certain:
            idx = sa * 2  # outcome 0 of each K + 1 = 2 entries
        else:
            # The outcome index: how many cumulative thresholds u reaches (1-D takes per
            # column are cheaper than gathering [R, K] rows).
            k = table.cum_columns[0].take(sa) <= u
            k = k.astype(np.int64)
            for column in table.cum_columns[1:]:
                k += column.take(sa) <= u
            idx = sa * (table.k + 1) + k
        next_state, reward, terminated = (a.take(idx) for a in table.flat)
        self._state[at] = self._after_move(rows, old, next_state)
        self._obs[at] = self._state[at]
        self._prob[at] = table.flat_prob.take(idx)
        self._reward[at] = reward
        self._terminated[at] = terminated
        return self._reward, self._terminated

    def _after_move(self, rows: np.ndarray, old: np.ndarray, new: np.ndarray) -> np.ndarray:
        return new

    def _step_infos(self, rows: np.ndarray) -> Any:
        return StackedInfos(self._info_arrays(self._prob.copy()), self.num_envs)

    def _merge_infos(self, step_infos: Any, reset_infos: Any, resetting: np.ndarray) -> Any:
        # A float array: a reset row's int 1 reads 1.0 beside the step rows' probabilities
        # (Gymnasium's stacking would take the dtype of whichever row comes first).
        prob = step_infos.arrays["prob"]
        prob[resetting] = self.reset_prob
        return StackedInfos(self._info_arrays(prob), self.num_envs)
