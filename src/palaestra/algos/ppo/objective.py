"""PPO's update for the learners: its loss over an array namespace ``xp`` with the
vector-Jacobian product beside it (the numpy learner's gradient), and the ``Objective`` that
runs the nets, the loss and the VJP chained back through the head and the nets.

Conventions are SB3's: the clipped surrogate with per-minibatch advantage normalisation
(unbiased std, +1e-8), optional value clipping, and the entropy bonus (``-log_prob`` where a
head has no entropy). Reference: Schulman et al. 2017.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.algos.learners.learner import Backprop, Run

__all__ = ["PPOObjective", "ppo_loss", "ppo_loss_vjp"]


def ppo_loss(
    xp: Any,
    log_prob: Any,
    old_log_prob: Any,
    advantages: Any,
    values: Any,
    old_values: Any,
    returns: Any,
    entropy: Any,
    clip_range: float,
    clip_range_vf: float | None = None,
    ent_coef: float = 0.0,
    vf_coef: float = 0.5,
    normalize_advantage: bool = True,
) -> tuple[Any, dict[str, Any], Any]:
    """Clipped surrogate + value loss - entropy bonus for one minibatch (inputs ``[B]``;
    ``entropy`` ``[B]``, one number, or None for ``-log_prob``)."""
    n = log_prob.shape[0]
    adv = xp.standardize(advantages) if normalize_advantage and n > 1 else advantages
    log_ratio = log_prob - old_log_prob
    ratio = xp.exp(log_ratio)
    clipped = xp.clip(ratio, 1 - clip_range, 1 + clip_range)
    s1, s2 = adv * ratio, adv * clipped
    policy_loss = -xp.mean(xp.minimum(s1, s2))
    v_pred = values
    if clip_range_vf is not None:
        # Value clipping around the rollout's values (OpenAI baselines; off by default in SB3).
        v_pred = old_values + xp.clip(values - old_values, -clip_range_vf, clip_range_vf)
    v_err = v_pred - returns
    value_loss = xp.mean(v_err * v_err)
    entropy_loss = xp.mean(log_prob) if entropy is None else -xp.mean(entropy)
    loss = policy_loss + ent_coef * entropy_loss + vf_coef * value_loss
    metrics = {
        "loss": loss,
        "policy_loss": policy_loss,
        "value_loss": value_loss,
        "entropy_loss": entropy_loss,
        "clip_fraction": xp.count_mean(xp.abs(ratio - 1) > clip_range),
        # http://joschu.net/blog/kl-approx.html: unbiased, low-variance estimator of KL(old||new)
        "approx_kl": xp.mean((ratio - 1) - log_ratio),
    }
    tape = (adv, ratio, clipped, s1, s2, values, old_values, v_err, clip_range_vf)
    return loss, metrics, (tape, ent_coef, vf_coef, entropy is None)


def ppo_loss_vjp(tape: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """``(d/d log_prob [B], d/d values [B], d/d mean(entropy))``.

    d(min(s1, s2))/d(ratio) is adv where s1 < s2 or the ratio lies inside the clip range.
    Inside, clipped == ratio, so s1 == s2 and torch.minimum's even split of the tie gives
    1/2 + 1/2 (both sides are the ratio); outside, the clipped side is a constant (a tie there
    needs adv == 0, a zero gradient either way). ``clamp`` passes the value gradient on its
    closed interval."""
    (
        (adv, ratio, clipped, s1, s2, values, old_values, v_err, clip_range_vf),
        ent_coef,
        vf_coef,
        no_entropy,
    ) = tape
    n = ratio.shape[0]
    d_min = adv * ((clipped == ratio) | (s1 < s2))
    neg_g = np.multiply(d_min, ratio, out=d_min)
    neg_g /= n  # -d(policy_loss)/d(log_prob)
    g_log_prob = -neg_g
    g_values = (2.0 * vf_coef / n) * v_err
    if clip_range_vf is not None:
        g_values = g_values * (np.abs(values - old_values) <= clip_range_vf)
    if no_entropy:  # entropy_loss = mean(log_prob)
        return g_log_prob + np.float32(ent_coef / n), g_values, 0.0
    return g_log_prob, g_values, -ent_coef


class PPOObjective:
    """Clipped surrogate, value and entropy terms of the actor ``pi`` (through ``head``) and
    the critic ``vf`` on one minibatch."""

    def __init__(
        self,
        head: Any,
        clip_range: float,
        clip_range_vf: float | None,
        ent_coef: float,
        vf_coef: float,
        normalize_advantage: bool,
    ) -> None:
        self.head = head
        self.args = (clip_range, clip_range_vf, ent_coef, vf_coef, normalize_advantage)

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        obs = batch["observations"]
        head_params, latent = self.head.run(run, obs)
        values = run("vf", obs)[:, 0]
        log_prob, entropy, head_tape = self.head.evaluate(
            xp, head_params, extras.get("log_std"), batch["actions"], latent
        )
        loss, metrics, tape = ppo_loss(
            xp,
            log_prob,
            batch["old_log_prob"],
            batch["advantages"],
            values,
            batch["old_values"],
            batch["returns"],
            entropy,
            *self.args,
        )
        return loss, metrics, (tape, head_tape)

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        loss_tape, head_tape = tape
        g_log_prob, g_values, g_mean_entropy = ppo_loss_vjp(loss_tape)
        g_params, g_log_std = self.head.evaluate_vjp(head_tape, g_log_prob, g_mean_entropy)
        backprop("vf", g_values[:, None])
        self.head.backprop(backprop, g_params)
        return {} if g_log_std is None else {"log_std": g_log_std}
