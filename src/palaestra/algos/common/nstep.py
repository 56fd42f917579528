"""n-step returns for the off-policy algorithms (``n_steps`` of DQN, SAC, TD3, DDPG), as SB3
2.x's ``NStepReplayBuffer`` computes them at sampling time from the one-step transitions a
replay ring stores (no extra memory but a flag per transition: did the episode end there).

A transition sampled at row ``t`` of env ``e`` becomes the window ``t, t + 1, ...`` of that env,
at most ``n_steps`` long and cut after the first transition whose episode ended (terminated
*or* truncated) and after the newest stored transition (the ring's row ``pos - 1``, whose
successor is not stored yet; when the ring is full, the row after it is the oldest). The sample
then holds ``R = sum_k gamma^k r_{t+k}`` over the window, the next observation and the
``terminated`` flag of the window's last transition, and the discount ``gamma^len`` its target
applies: ``R + discount * (1 - terminated) * V(s')``. A window cut by a truncation bootstraps
from the truncated episode's last observation, as a one-step truncated transition does.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["check_n_steps", "n_step_window"]


def check_n_steps(value: Any) -> int:
    """``n_steps`` as an int >= 1; a ``ValueError`` naming anything else (``True``, ``2.5``)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"n_steps must be an integer >= 1, got {value!r}")
    return int(value)


def n_step_window(
    rewards: np.ndarray,
    ends: tuple[np.ndarray, ...],
    newest: int,
    rows: np.ndarray,
    cols: np.ndarray,
    n_steps: int,
    gamma: float,
    scale: Callable[[np.ndarray], np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(returns [B], discounts [B], last rows [B])`` of the windows starting at
    ``(rows, cols)`` of a ring whose ``rewards`` are ``[buffer rows, n_envs]``, whose episodes
    end where any array of ``ends`` (same shape) is nonzero, and whose newest row is ``newest``
    (see the module doc). ``scale`` maps rewards elementwise before they are summed
    (``VecNormalize``'s ``normalize_reward``).

    Float32 as SB3's (its sums, added in window order, are the same bits for ``n_steps < 8``;
    numpy's pairwise summation rounds longer ones differently). Memory is ``O(B)``: the loop
    stops once every window is cut, after at most ``min(n_steps, buffer rows)`` steps.

    >>> r = np.array([[1.0], [2.0], [4.0]], np.float32)
    >>> ended = np.array([[0.0], [1.0], [0.0]], np.float32)  # the episode ends at row 1
    >>> n_step_window(r, (ended,), 2, np.array([0, 2]), np.array([0, 0]), 3, 0.5)
    (array([2., 4.], dtype=float32), array([0.25, 0.5 ], dtype=float32), array([1, 2]))
    """
    size = rewards.shape[0]
    g = np.float32(gamma)
    returns = np.zeros(rows.shape, dtype=np.float32)
    length = np.zeros(rows.shape, dtype=np.int64)
    last = rows.copy()
    open_ = np.ones(rows.shape, dtype=bool)
    for k in range(n_steps):
        at = (rows + k) % size
        reward = rewards[at, cols] if scale is None else scale(rewards[at, cols])
        returns = np.where(open_, returns + reward * g ** np.float32(k), returns)
        last = np.where(open_, at, last)
        length += open_
        open_ &= at != newest
        for ended in ends:
            open_ &= ended[at, cols] == 0
        if not open_.any():
            break
    return returns, g ** length.astype(np.float32), last
