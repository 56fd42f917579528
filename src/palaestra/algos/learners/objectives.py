"""The update of each algorithm as an ``Objective`` for the learners: the nets it runs, the
loss (from ``losses``, over ``xp``) and its VJP chained back through the head and the nets."""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.algos.learners.learner import Backprop, Run
from palaestra.algos.learners.losses import (
    a2c_loss,
    a2c_loss_vjp,
    dqn_loss,
    dqn_loss_vjp,
    ppo_loss,
    ppo_loss_vjp,
)

__all__ = ["A2CObjective", "DQNObjective", "PPOObjective"]


class DQNObjective:
    """Huber TD loss of the online net ``q`` against the target net ``q_target``."""

    def __init__(self, gamma: float) -> None:
        self.gamma = gamma

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        next_q = run("q_target", batch["next_observations"])
        q = run("q", batch["observations"])
        return dqn_loss(
            xp, q, batch["actions"], batch["rewards"], batch["terminated"], next_q, self.gamma
        )

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        backprop("q", dqn_loss_vjp(tape))
        return {}


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
        head_params, values = run("pi", obs), run("vf", obs)[:, 0]
        log_prob, entropy, head_tape = self.head.evaluate(
            xp, head_params, extras.get("log_std"), batch["actions"]
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
        backprop("pi", g_params)
        return {} if g_log_std is None else {"log_std": g_log_std}


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
        head_params, values = run("pi", obs), run("vf", obs)[:, 0]
        log_prob, entropy, head_tape = self.head.evaluate(
            xp, head_params, extras.get("log_std"), batch["actions"]
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
        backprop("pi", g_params)
        return {} if g_log_std is None else {"log_std": g_log_std}
