"""The update of each algorithm as an ``Objective`` for the learners: the nets it runs, the
loss (from ``losses``, over ``xp``) and its VJP chained back through the head and the nets."""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.algos.learners.heads import (
    squashed_gaussian_rsample,
    squashed_gaussian_rsample_vjp,
)
from palaestra.algos.learners.learner import Backprop, Run
from palaestra.algos.learners.losses import (
    a2c_loss,
    a2c_loss_vjp,
    deterministic_actor_loss,
    deterministic_actor_loss_vjp,
    dqn_loss,
    dqn_loss_vjp,
    ent_coef_loss,
    ent_coef_loss_vjp,
    min_of,
    ppo_loss,
    ppo_loss_vjp,
    q_regression_loss,
    q_regression_loss_vjp,
    soft_actor_loss,
    soft_actor_loss_vjp,
)

__all__ = [
    "A2CObjective",
    "DQNObjective",
    "EntCoefObjective",
    "PPOObjective",
    "SACActorObjective",
    "SACCriticObjective",
    "TD3ActorObjective",
    "TD3CriticObjective",
]


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


def _critics(xp: Any, run: Run, names: list[str], obs: Any, actions: Any) -> list[Any]:
    """``Q(obs, actions)`` ``[B]`` of each named critic."""
    return [run(name, (obs, actions))[:, 0] for name in names]


class SACCriticObjective:
    """Soft Bellman regression of every critic (SB3's SAC): the target is
    ``r + gamma (1 - done) (min_i Q'_i(s', a') - alpha log pi(a'|s'))`` with ``a'`` drawn by the
    actor with ``next_noise``, not differentiated."""

    def __init__(self, n_critics: int, gamma: float, ent_coef: float) -> None:
        self.names = [f"qf{i}" for i in range(n_critics)]
        self.gamma, self.ent_coef = gamma, ent_coef

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        next_obs = batch["next_observations"]
        with xp.no_grad():
            latent = run("latent", next_obs)
            next_a, next_log_prob, _ = squashed_gaussian_rsample(
                xp, run("mu", latent), run("log_std", latent), batch["next_noise"]
            )
            targets = [f"{name}_target" for name in self.names]
            next_q = min_of(xp, _critics(xp, run, targets, next_obs, next_a))
            next_q = next_q - self.ent_coef * next_log_prob
            target = batch["rewards"] + (1.0 - batch["terminated"]) * self.gamma * next_q
        qs = _critics(xp, run, self.names, batch["observations"], batch["actions"])
        return q_regression_loss(xp, qs, xp.stop_gradient(target), 0.5)

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]:
        for name, g in reversed(list(zip(self.names, q_regression_loss_vjp(tape)))):
            backprop(name, g[:, None])
        return {}


class SACActorObjective:
    """``mean(alpha log pi(a|s) - min_i Q_i(s, a))``, ``a`` reparameterised with ``noise``
    through the critics (not trained here) into the actor. Keeps the batch's log-probs for
    the temperature update (``last_log_prob``)."""

    def __init__(self, n_critics: int, ent_coef: float, action_dim: int) -> None:
        self.names = [f"qf{i}" for i in range(n_critics)]
        self.ent_coef, self.action_dim = ent_coef, action_dim
        self.last_log_prob: Any = None

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]:
        obs = batch["observations"]
        latent = run("latent", obs)
        actions, log_prob, head_tape = squashed_gaussian_rsample(
            xp, run("mu", latent), run("log_std", latent), batch["noise"]
        )
        self.last_log_prob = xp.stop_gradient(log_prob)
        qs = _critics(xp, run, self.names, obs, actions)
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


class TD3CriticObjective:
    """Clipped double-Q regression (Fujimoto et al. 2018): target actions are the target
    actor's plus the clipped ``target_noise``, clipped to [-1, 1]; the target takes the
    minimum of the target critics (DDPG: one critic, no noise)."""

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
            next_q = min_of(xp, _critics(xp, run, targets, next_obs, next_a))
            target = batch["rewards"] + (1.0 - batch["terminated"]) * self.gamma * next_q
        qs = _critics(xp, run, self.names, batch["observations"], batch["actions"])
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
