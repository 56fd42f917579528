"""SAC's update for the learners: its loss over an array namespace ``xp`` with the
vector-Jacobian product beside it (the numpy learner's gradient), and the ``Objective`` that
runs the nets, the loss and the VJP chained back through the head and the nets."""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.algos.learners.heads import (
    sde_rsample,
    sde_rsample_vjp,
    sde_std,
    sde_std_vjp,
    squashed_gaussian_rsample,
    squashed_gaussian_rsample_vjp,
)
from palaestra.algos.learners.learner import Backprop, Run, critics
from palaestra.algos.learners.losses import (
    min_of,
    min_of_vjp,
    q_regression_loss,
    q_regression_loss_vjp,
)

__all__ = [
    "EntCoefObjective",
    "SACActorObjective",
    "SACCriticObjective",
    "SDEDraw",
    "ent_coef_loss",
    "ent_coef_loss_vjp",
    "soft_actor_loss",
    "soft_actor_loss_vjp",
]


def soft_actor_loss(
    xp: Any, ent_coef: float, log_prob: Any, qs_pi: list[Any]
) -> tuple[Any, dict[str, Any], Any]:
    """SAC's actor loss ``mean(alpha * log pi(a|s) - min_i Q_i(s, a))`` with ``a`` drawn by the
    actor (reparameterised), ``alpha`` a number (not differentiated here)."""
    loss = xp.mean(ent_coef * log_prob - min_of(xp, qs_pi))
    return loss, {"actor_loss": loss}, (ent_coef, log_prob.shape[0], qs_pi)


def soft_actor_loss_vjp(tape: Any) -> tuple[np.ndarray, list[np.ndarray]]:
    """``(d/d log_prob [B], [d/d Q_i [B]])``."""
    ent_coef, n, qs = tape
    g_log_prob = np.full(n, ent_coef / n, dtype=np.float32)
    return g_log_prob, min_of_vjp(qs, np.full(n, -1.0 / n, dtype=np.float32))


def ent_coef_loss(
    xp: Any, log_ent_coef: Any, log_prob: Any, target_entropy: float
) -> tuple[Any, dict[str, Any], Any]:
    """SAC's temperature loss ``-mean(log_alpha * (log pi + target_entropy))``, the log-prob
    not differentiated (softlearning issue 60, kept by SB3)."""
    shifted = xp.stop_gradient(log_prob) + target_entropy
    loss = -xp.mean(log_ent_coef * shifted)
    return loss, {"ent_coef_loss": loss}, shifted


def ent_coef_loss_vjp(tape: Any) -> np.ndarray:
    """d(loss)/d(log_alpha) ``= -mean(log pi + target_entropy)`` (shape ``(1,)``)."""
    return np.array([-float(np.mean(tape))], dtype=np.float32)


class SDEDraw:
    """The actor's gSDE draw for SAC's losses (SB3's ``Actor.action_log_prob`` with
    ``use_sde``): ``latent`` and ``mu`` nets, the mean clipped to ``clip_mean``, the weights'
    log-std an extra parameter (``log_std``), one noise matrix per gradient step
    (``batch["sde_noise"]``, standard normal ``[latent, action_dim]``) for the actor's
    actions and the target's next actions alike; the features are learned."""

    def __init__(self, use_expln: bool, full_std: bool, clip_mean: float, action_dim: int):
        self.use_expln, self.full_std = use_expln, full_std
        self.clip_mean, self.action_dim = clip_mean, action_dim

    def rsample(
        self, xp: Any, run: Run, extras: dict[str, Any], obs: Any, batch: dict[str, Any]
    ) -> tuple[Any, Any, Any]:
        """``(actions, log_prob, tape)`` for ``obs``."""
        latent = run("latent", obs)
        raw = run("mu", latent)
        c = self.clip_mean
        mean = xp.clip(raw, -c, c) if c > 0 else raw
        std, std_tape = sde_std(
            xp, extras["log_std"], self.use_expln, self.full_std, self.action_dim
        )
        actions, log_prob, tape = sde_rsample(xp, mean, std, latent, batch["sde_noise"])
        return actions, log_prob, (tape, std_tape, raw)

    def vjp(
        self, tape: Any, backprop: Backprop, g_action: np.ndarray, g_log_prob: np.ndarray
    ) -> dict[str, np.ndarray]:
        """Gradients back into ``mu`` and ``latent``; the log-std's by name."""
        head_tape, std_tape, raw = tape
        g_mean, g_std, g_latent = sde_rsample_vjp(head_tape, g_action, g_log_prob)
        if self.clip_mean > 0:
            g_mean = g_mean * (np.abs(raw) <= self.clip_mean)
        g_mu_latent = backprop("mu", g_mean, input_grad=True)
        assert g_mu_latent is not None
        backprop("latent", g_latent + g_mu_latent)
        return {"log_std": sde_std_vjp(std_tape, g_std)}


class SACCriticObjective:
    """Soft Bellman regression of every critic (SB3's SAC): the target is
    ``r + gamma (1 - done) (min_i Q'_i(s', a') - alpha log pi(a'|s'))`` with ``a'`` drawn by the
    actor with ``next_noise``, not differentiated; a batch with ``discounts`` (n-step returns)
    discounts each sample by its own instead of gamma."""

    def __init__(
        self, n_critics: int, gamma: float, ent_coef: float, sde: SDEDraw | None = None
    ) -> None:
        self.names = [f"qf{i}" for i in range(n_critics)]
        self.gamma, self.ent_coef, self.sde = gamma, ent_coef, sde

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        next_obs = batch["next_observations"]
        with xp.no_grad():
            if self.sde is not None:
                next_a, next_log_prob, _ = self.sde.rsample(xp, run, extras, next_obs, batch)
            else:
                latent = run("latent", next_obs)
                next_a, next_log_prob, _ = squashed_gaussian_rsample(
                    xp, run("mu", latent), run("log_std", latent), batch["next_noise"]
                )
            targets = [f"{name}_target" for name in self.names]
            next_q = min_of(xp, critics(xp, run, targets, next_obs, next_a))
            next_q = next_q - self.ent_coef * next_log_prob
            gamma = batch.get("discounts", self.gamma)
            target = batch["rewards"] + (1.0 - batch["terminated"]) * gamma * next_q
        qs = critics(xp, run, self.names, batch["observations"], batch["actions"])
        return q_regression_loss(xp, qs, xp.stop_gradient(target), 0.5)

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        for name, g in reversed(list(zip(self.names, q_regression_loss_vjp(tape)))):
            backprop(name, g[:, None])
        return {}


class SACActorObjective:
    """``mean(alpha log pi(a|s) - min_i Q_i(s, a))``, ``a`` reparameterised with ``noise``
    through the critics (not trained here) into the actor. Keeps the batch's log-probs for
    the temperature update (``last_log_prob``)."""

    def __init__(
        self, n_critics: int, ent_coef: float, action_dim: int, sde: SDEDraw | None = None
    ) -> None:
        self.names = [f"qf{i}" for i in range(n_critics)]
        self.ent_coef, self.action_dim, self.sde = ent_coef, action_dim, sde
        self.last_log_prob: Any = None

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        obs = batch["observations"]
        if self.sde is not None:
            actions, log_prob, head_tape = self.sde.rsample(xp, run, extras, obs, batch)
        else:
            latent = run("latent", obs)
            actions, log_prob, head_tape = squashed_gaussian_rsample(
                xp, run("mu", latent), run("log_std", latent), batch["noise"]
            )
        self.last_log_prob = xp.stop_gradient(log_prob)
        qs = critics(xp, run, self.names, obs, actions)
        loss, metrics, tape = soft_actor_loss(xp, self.ent_coef, log_prob, qs)
        return loss, metrics, (tape, head_tape)

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        loss_tape, head_tape = tape
        g_log_prob, g_qs = soft_actor_loss_vjp(loss_tape)
        g_action = np.zeros_like(g_log_prob[:, None], shape=(len(g_log_prob), self.action_dim))
        for name, g in reversed(list(zip(self.names, g_qs))):
            g_input = backprop(name, g[:, None], input_grad=True)
            assert g_input is not None
            g_action += g_input[:, -self.action_dim :]
        if self.sde is not None:
            return self.sde.vjp(head_tape, backprop, g_action, g_log_prob)
        g_mean, g_log_std = squashed_gaussian_rsample_vjp(head_tape, g_action, g_log_prob)
        g_latent = backprop("log_std", g_log_std, input_grad=True)
        g_mu_latent = backprop("mu", g_mean, input_grad=True)
        assert g_latent is not None and g_mu_latent is not None
        backprop("latent", g_latent + g_mu_latent)
        return {}


class EntCoefObjective:
    """SAC's temperature: ``-mean(log_alpha (log pi + target_entropy))`` on the log-probs of
    the actor update (``SACActorObjective.last_log_prob``, on the learner's own arrays)."""

    def __init__(self, target_entropy: float, log_prob: Any) -> None:
        self.target_entropy, self.log_prob = target_entropy, log_prob

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        return ent_coef_loss(xp, extras["log_ent_coef"], self.log_prob, self.target_entropy)

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        return {"log_ent_coef": ent_coef_loss_vjp(tape)}
