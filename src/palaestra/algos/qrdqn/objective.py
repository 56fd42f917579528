"""QR-DQN's update for the learners: the quantile Huber loss over an array namespace ``xp`` with
its vector-Jacobian product beside it (the numpy learner's gradient), and the ``Objective``
that runs the quantile nets, the loss and the VJP.

Conventions are sb3-contrib's ``QRDQN``: the target is the target net's quantiles of the
action whose mean quantile is largest, ``r + gamma * (1 - terminated) * theta'(s', a*)``
(truncated episodes bootstrapped by the buffer); the loss is the quantile Huber loss with
kappa 1, summed over the current quantiles and averaged over the batch and the target
quantiles. Reference: Dabney et al. 2018, "Distributional Reinforcement Learning with
Quantile Regression", eq. 10.

Index arrays and the quantile midpoints come in the batch (``rows``, ``cum_prob``), so that
the same code indexes numpy arrays and torch tensors on the model's device.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.algos.dqn.objective import DQNObjective
from palaestra.algos.learners.learner import Backprop, Run

__all__ = [
    "QRDQNObjective",
    "qrdqn_loss",
    "qrdqn_loss_vjp",
    "quantile_huber_loss",
    "quantile_huber_loss_vjp",
    "quantile_midpoints",
]


def quantile_midpoints(n_quantiles: int) -> np.ndarray:
    """``tau_i = (i + 0.5) / N``: the quantile levels the network's outputs estimate
    ``[N]`` float32.

    >>> quantile_midpoints(4)
    array([0.125, 0.375, 0.625, 0.875], dtype=float32)
    """
    return (np.arange(n_quantiles, dtype=np.float32) + 0.5) / n_quantiles


def quantile_huber_loss(
    xp: Any, current: Any, target: Any, cum_prob: Any
) -> tuple[Any, tuple[Any, ...]]:
    """``mean_{b,j} sum_i |tau_i - 1{delta < 0}| * huber(delta)``, ``delta = target[b, j] -
    current[b, i]`` (kappa 1): sb3-contrib's ``quantile_huber_loss`` with
    ``sum_over_quantiles=True``. ``current`` ``[B, N]``, ``target`` ``[B, N']`` (not
    differentiated), ``cum_prob`` the levels ``tau`` ``[N]``. Returns ``(loss, tape)``.

    >>> from palaestra.algos.learners.xp import numpy_ops as xp
    >>> current, target = np.array([[0.0, 1.0]]), np.array([[0.5, 3.0]])
    >>> quantile_huber_loss(xp, current, target, quantile_midpoints(2))[0]  # by hand below
    0.90625

    (tau 1/4, 3/4; deltas 0.5, 3 | -0.5, 2; weighted Huber 1/32 + 5/8 | 1/32 + 9/8, summed
    over the current quantiles and averaged over the two targets.)
    """
    delta = target[:, None, :] - current[:, :, None]  # [B, N, N']
    absd = xp.abs(delta)
    huber = xp.where(absd > 1.0, absd - 0.5, 0.5 * delta * delta)
    tau = cum_prob[None, :, None]
    weight = xp.where(delta < 0.0, 1.0 - tau, tau)  # |tau - 1{delta < 0}|; no gradient
    loss = xp.mean(xp.sum_rows(weight * huber))
    return loss, (delta, weight)


def quantile_huber_loss_vjp(tape: Any) -> np.ndarray:
    """d(loss)/d(current) ``[B, N]``: ``-sum_j weight * clip(delta, -1, 1) / (B * N')`` (at
    ``|delta| == 1`` both Huber branches have slope 1)."""
    delta, weight = tape
    scale = np.float32(1.0 / (delta.shape[0] * delta.shape[2]))
    return -np.add.reduce(weight * np.clip(delta, -1.0, 1.0), axis=2) * scale


def qrdqn_loss(
    xp: Any,
    quantiles: Any,
    actions: Any,
    rewards: Any,
    terminated: Any,
    next_quantiles_target: Any,
    rows: Any,
    cum_prob: Any,
    gamma: Any,
) -> tuple[Any, dict[str, Any], Any]:
    """The quantile Huber loss of ``theta(s, a)`` against ``r + gamma * (1 - terminated) *
    theta'(s', argmax_a' mean theta'(s', a'))``.

    ``quantiles``/``next_quantiles_target``: the online net on ``s`` and the target net on
    ``s'`` (not differentiated), ``[B, N * n_actions]`` or ``[B, N, n_actions]``; ``actions``
    ``[B]`` 0-based; ``rewards``/``terminated`` ``[B]``; ``rows`` ``arange(B)``; ``cum_prob``
    ``[N]``; ``gamma`` a number or each sample's discount ``[B]`` (n-step returns)."""
    n = cum_prob.shape[0]
    next_q = next_quantiles_target.reshape(rows.shape[0], n, -1)  # [B, N, n_actions]
    greedy = next_q.mean(axis=1).argmax(axis=1)
    if getattr(gamma, "ndim", 0) == 1:  # per-sample discounts [B]
        gamma = gamma[:, None]
    target = rewards[:, None] + (1.0 - terminated[:, None]) * gamma * next_q[rows, :, greedy]
    current = quantiles.reshape(rows.shape[0], n, -1)[rows, :, actions]  # [B, N]
    loss, tape = quantile_huber_loss(xp, current, target, cum_prob)
    return loss, {"loss": loss}, (quantiles.shape, rows, actions, tape)


def qrdqn_loss_vjp(tape: Any) -> np.ndarray:
    """d(loss)/d(quantiles), in the shape the net gave them: the quantile Huber gradient at
    each row's action, 0 elsewhere."""
    shape, rows, actions, huber_tape = tape
    delta = huber_tape[0]  # [B, N, N']
    g = np.zeros(shape, dtype=np.float32).reshape(delta.shape[0], delta.shape[1], -1)
    g[rows, :, actions] = quantile_huber_loss_vjp(huber_tape)
    return g.reshape(shape)


class QRDQNObjective(DQNObjective):
    """Quantile Huber loss of the online net ``q`` against the target net ``q_target``: DQN's
    nets and batch, with ``rows`` and ``cum_prob`` added to the batch."""

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        quantiles = run("q", batch["observations"])
        next_quantiles = run("q_target", batch["next_observations"])
        actions, rewards, terminated = batch["actions"], batch["rewards"], batch["terminated"]
        rows, cum_prob = batch["rows"], batch["cum_prob"]
        gamma = batch.get("discounts", self.gamma)
        args = (actions, rewards, terminated, next_quantiles, rows, cum_prob, gamma)
        return qrdqn_loss(xp, quantiles, *args)

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        backprop("q", qrdqn_loss_vjp(tape))
        return {}
