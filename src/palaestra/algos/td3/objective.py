"""TD3's update for the learners: its loss over an array namespace ``xp`` with the
vector-Jacobian product beside it (the numpy learner's gradient), and the ``Objective`` that
runs the nets, the loss and the VJP chained back through the head and the nets."""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.algos.learners.learner import Backprop, Run, critics
from palaestra.algos.learners.losses import (
    min_of,
    q_regression_loss,
    q_regression_loss_vjp,
)

__all__ = [
    "TD3ActorObjective",
    "TD3CriticObjective",
    "deterministic_actor_loss",
    "deterministic_actor_loss_vjp",
]


def deterministic_actor_loss(xp: Any, q_pi: Any) -> tuple[Any, dict[str, Any], Any]:
    """TD3's and DDPG's actor loss ``-mean(Q_0(s, mu(s)))``."""
    loss = -xp.mean(q_pi)
    return loss, {"actor_loss": loss}, q_pi.shape[0]


def deterministic_actor_loss_vjp(tape: Any) -> np.ndarray:
    return np.full(tape, -1.0 / tape, dtype=np.float32)


class TD3CriticObjective:
    """Clipped double-Q regression (Fujimoto et al. 2018): target actions are the target
    actor's plus the clipped ``target_noise``, clipped to [-1, 1]; the target takes the
    minimum of the target critics (DDPG: one critic, no noise). A batch with ``discounts``
    (n-step returns) discounts each sample by its own instead of gamma."""

    def __init__(self, n_critics: int, gamma: float) -> None:
        self.names = [f"qf{i}" for i in range(n_critics)]
        self.gamma = gamma

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        next_obs = batch["next_observations"]
        with xp.no_grad():
            next_a = xp.clip(run("actor_target", next_obs) + batch["target_noise"], -1.0, 1.0)
            targets = [f"{name}_target" for name in self.names]
            next_q = min_of(xp, critics(xp, run, targets, next_obs, next_a))
            gamma = batch.get("discounts", self.gamma)
            target = batch["rewards"] + (1.0 - batch["terminated"]) * gamma * next_q
        qs = critics(xp, run, self.names, batch["observations"], batch["actions"])
        return q_regression_loss(xp, qs, xp.stop_gradient(target), 1.0)

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        for name, g in reversed(list(zip(self.names, q_regression_loss_vjp(tape)))):
            backprop(name, g[:, None])
        return {}


class TD3ActorObjective:
    """``-mean(Q_0(s, mu(s)))`` through the first critic (not trained here) into the actor."""

    def __init__(self, action_dim: int) -> None:
        self.action_dim = action_dim

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        obs = batch["observations"]
        q = run("qf0", (obs, run("actor", obs)))[:, 0]
        return deterministic_actor_loss(xp, q)

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        g_q = deterministic_actor_loss_vjp(tape)
        g_input = backprop("qf0", g_q[:, None], input_grad=True)
        assert g_input is not None
        backprop("actor", g_input[:, -self.action_dim :])
        return {}
