"""A2C's update for the learners: its loss over an array namespace ``xp`` with the
vector-Jacobian product beside it (the numpy learner's gradient), and the ``Objective`` that
runs the nets, the loss and the VJP chained back through the head and the nets.

Conventions are SB3's: a plain policy gradient over the whole rollout with PPO's value and
entropy terms. Reference: Mnih et al. 2016.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.algos.learners.learner import Backprop, Run

__all__ = ["A2CObjective", "a2c_loss", "a2c_loss_vjp"]


def a2c_loss(
    xp: Any,
    log_prob: Any,
    advantages: Any,
    values: Any,
    returns: Any,
    entropy: Any,
    ent_coef: float = 0.0,
    vf_coef: float = 0.5,
    normalize_advantage: bool = False,
) -> tuple[Any, dict[str, Any], Any]:
    """Policy gradient + value loss - entropy bonus over one rollout (inputs ``[B]``;
    ``entropy`` ``[B]`` or None for ``-log_prob``), as SB3's ``A2C.train``:
    ``-mean(adv * log_prob) + ent_coef * entropy_loss + vf_coef * mean((returns - V)^2)``.

    >>> from palaestra.algos.learners.xp import numpy_ops as xp
    >>> one = np.array([1.0, 1.0])
    >>> loss, m, _ = a2c_loss(xp, np.log([0.5, 0.25]), np.array([2.0, 1.0]), 0 * one, one, None)
    >>> round(float(loss), 4), round(m["policy_loss"], 4), m["value_loss"]
    (1.8863, 1.3863, 1.0)
    """
    n = log_prob.shape[0]
    adv = xp.standardize(advantages) if normalize_advantage and n > 1 else advantages
    policy_loss = -xp.mean(adv * log_prob)
    v_err = values - returns
    value_loss = xp.mean(v_err * v_err)
    entropy_loss = xp.mean(log_prob) if entropy is None else -xp.mean(entropy)
    loss = policy_loss + ent_coef * entropy_loss + vf_coef * value_loss
    metrics = {
        "loss": loss,
        "policy_loss": policy_loss,
        "value_loss": value_loss,
        "entropy_loss": entropy_loss,
    }
    return loss, metrics, (adv, v_err, ent_coef, vf_coef, entropy is None)


def a2c_loss_vjp(tape: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """``(d/d log_prob [B], d/d values [B], d/d mean(entropy))``; the advantages are
    constants (computed before the update), so normalising them adds no gradient path."""
    adv, v_err, ent_coef, vf_coef, no_entropy = tape
    n = adv.shape[0]
    g_log_prob = (-1.0 / n) * adv
    if no_entropy:  # entropy_loss = mean(log_prob)
        g_log_prob = g_log_prob + ent_coef / n
    g_values = (2.0 * vf_coef / n) * v_err
    return (
        g_log_prob.astype(np.float32, copy=False),
        g_values.astype(np.float32, copy=False),
        0.0 if no_entropy else -ent_coef,
    )


class A2CObjective:
    """Policy gradient, value and entropy terms of the actor ``pi`` (through ``head``) and the
    critic ``vf`` over a whole rollout."""

    def __init__(
        self, head: Any, ent_coef: float, vf_coef: float, normalize_advantage: bool
    ) -> None:
        self.head = head
        self.args = (ent_coef, vf_coef, normalize_advantage)

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        obs = batch["observations"]
        head_params, latent = self.head.run(run, obs)
        values = run("vf", obs)[:, 0]
        log_prob, entropy, head_tape = self.head.evaluate(
            xp, head_params, extras.get("log_std"), batch["actions"], latent
        )
        loss, metrics, tape = a2c_loss(
            xp, log_prob, batch["advantages"], values, batch["returns"], entropy, *self.args
        )
        return loss, metrics, (tape, head_tape)

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        loss_tape, head_tape = tape
        g_log_prob, g_values, g_mean_entropy = a2c_loss_vjp(loss_tape)
        g_params, g_log_std = self.head.evaluate_vjp(head_tape, g_log_prob, g_mean_entropy)
        backprop("vf", g_values[:, None])
        self.head.backprop(backprop, g_params)
        return {} if g_log_std is None else {"log_std": g_log_std}
