"""The losses of DQN, PPO and A2C written once over an array namespace ``xp``, each with its
vector-Jacobian product beside it, and GAE and explained variance (not differentiated).

Each loss returns ``(loss, metrics, tape)``: ``loss`` is what autograd differentiates on the
torch learner, ``metrics`` the logged values (numbers the caller turns into floats), ``tape``
what the VJP needs on the numpy learner. Conventions are SB3's: Huber (smooth L1, delta 1) TD
loss against a target net, truncated episodes bootstrapped by the buffer; PPO's clipped
surrogate with per-minibatch advantage normalisation (unbiased std, +1e-8), optional value
clipping, and the entropy bonus (``-log_prob`` where a head has no entropy); A2C's plain
policy gradient over the whole rollout with the same value and entropy terms.

References: Mnih et al. 2015 (DQN), 2016 (A2C/A3C), Schulman et al. 2016 (GAE) and 2017 (PPO).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "a2c_loss",
    "a2c_loss_vjp",
    "deterministic_actor_loss",
    "deterministic_actor_loss_vjp",
    "dqn_loss",
    "dqn_loss_vjp",
    "ent_coef_loss",
    "ent_coef_loss_vjp",
    "explained_variance",
    "gae",
    "min_of",
    "min_of_vjp",
    "polyak",
    "ppo_loss",
    "ppo_loss_vjp",
    "q_regression_loss",
    "q_regression_loss_vjp",
    "soft_actor_loss",
    "soft_actor_loss_vjp",
]


def dqn_loss(
    xp: Any,
    q_values: Any,
    actions: Any,
    rewards: Any,
    terminated: Any,
    next_q_target: Any,
    gamma: float,
) -> tuple[Any, dict[str, Any], Any]:
    """Huber loss between ``Q(s, a)`` and ``r + gamma * (1 - terminated) * max_a' Q'(s', a')``.

    ``q_values``/``next_q_target``: ``[B, n_actions]`` (online net on ``s``, target net on
    ``s'``, not differentiated); ``actions``: ``[B]`` 0-based; the rest ``[B]``.

    >>> from palaestra.algos.learners.xp import numpy_ops as xp
    >>> q, nq = np.array([[1.0, 2.0]]), np.array([[0.0, 3.0]])
    >>> dqn_loss(xp, q, np.array([1]), np.array([1.0]), np.array([0.0]), nq, 0.5)[0]
    0.125
    """
    target = rewards + (1.0 - terminated) * gamma * xp.max_rows(next_q_target)
    diff = xp.take_rows(q_values, actions) - target
    absd = xp.abs(diff)
    loss = xp.mean(xp.where(absd < 1.0, 0.5 * diff * diff, absd - 0.5))
    return loss, {"loss": loss}, (q_values.shape, actions, diff)


def dqn_loss_vjp(tape: Any) -> np.ndarray:
    """d(loss)/d(q_values): ``clip(diff, -1, 1) / B`` at each row's action, 0 elsewhere (at
    ``|diff| == 1`` both Huber branches have slope 1)."""
    shape, actions, diff = tape
    g = np.zeros(shape, dtype=np.float32)
    g[np.arange(shape[0]), actions] = np.clip(diff, -1.0, 1.0) / shape[0]
    return g


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


def q_regression_loss(
    xp: Any, current_qs: list[Any], target_q: Any, scale: float
) -> tuple[Any, dict[str, Any], Any]:
    """``scale * sum_i mean((Q_i - target)^2)`` over the critics (``[B]`` each; the target
    not differentiated). SAC halves it (``scale=0.5``), TD3 and DDPG do not (``scale=1``).

    >>> from palaestra.algos.learners.xp import numpy_ops as xp
    >>> qs, target = [np.array([1.0, 2.0]), np.array([0.0, 2.0])], np.array([1.0, 1.0])
    >>> q_regression_loss(xp, qs, target, 0.5)[0]  # 0.5 * (mean(0, 1) + mean(1, 1))
    0.75
    """
    errors = [q - target_q for q in current_qs]
    loss = scale * sum(xp.mean(e * e) for e in errors)
    return loss, {"critic_loss": loss}, (errors, scale)


def q_regression_loss_vjp(tape: Any) -> list[np.ndarray]:
    """d(loss)/d(Q_i) ``= 2 * scale * (Q_i - target) / B`` for each critic."""
    errors, scale = tape
    return [(2.0 * scale / e.shape[0]) * e for e in errors]


def min_of(xp: Any, qs: list[Any]) -> Any:
    m = qs[0]
    for q in qs[1:]:
        m = xp.minimum(m, q)
    return m


def min_of_vjp(qs: list[np.ndarray], g: np.ndarray) -> list[np.ndarray]:
    """The gradient of ``minimum(minimum(q0, q1), q2)...`` (ties split evenly, as torch)."""
    mins = [qs[0]]
    for q in qs[1:]:
        mins.append(np.minimum(mins[-1], q))
    grads: list[np.ndarray] = [np.zeros_like(q) for q in qs]
    for k in range(len(qs) - 1, 0, -1):
        left, right = mins[k - 1], qs[k]
        half = 0.5 * g * (left == right)
        grads[k] = g * (right < left) + half
        g = g * (left < right) + half
    grads[0] = g
    return grads


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


def deterministic_actor_loss(xp: Any, q_pi: Any) -> tuple[Any, dict[str, Any], Any]:
    """TD3's and DDPG's actor loss ``-mean(Q_0(s, mu(s)))``."""
    loss = -xp.mean(q_pi)
    return loss, {"actor_loss": loss}, q_pi.shape[0]


def deterministic_actor_loss_vjp(tape: Any) -> np.ndarray:
    return np.full(tape, -1.0 / tape, dtype=np.float32)


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


def polyak(params: list[Any], target_params: list[Any], tau: float) -> None:
    """``target = tau * online + (1 - tau) * target`` in place (numpy arrays or torch tensors
    under ``no_grad``); ``tau == 1`` copies exactly."""
    for p, tp in zip(params, target_params, strict=True):
        if tau == 1.0:
            tp[...] = p
        elif hasattr(tp, "add_"):  # torch: one fused a + tau * b, SB3's bits
            tp.mul_(1.0 - tau).add_(p, alpha=tau)
        else:
            tp *= 1.0 - tau
            tp += tau * p


def gae(
    rewards: np.ndarray,
    values: np.ndarray,
    episode_starts: np.ndarray,
    last_values: np.ndarray,
    last_dones: np.ndarray,
    gamma: float,
    gae_lambda: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Generalized advantage estimates and returns (``advantages + values``).

    ``rewards``, ``values``, ``episode_starts``: ``[T, N]``; ``episode_starts[t]`` is 1 when
    the observation at step ``t`` began an episode (so step ``t-1`` ended one). ``last_values``
    and ``last_dones`` describe the observation after the last step.

    >>> adv, ret = gae(np.array([[1.0], [1.0]]), np.array([[0.5], [0.5]]), np.zeros((2, 1)),
    ...                np.array([0.5]), np.array([1.0]), gamma=0.9, gae_lambda=0.8)
    >>> [round(float(x), 4) for x in adv.ravel()], [round(float(x), 4) for x in ret.ravel()]
    ([1.31, 0.5], [1.81, 1.0])
    """
    n_steps = rewards.shape[0]
    # The per-step terms, computed for all steps at once; only the recursion stays a loop
    # (same operations in the same order as the step-by-step form, so the same bits).
    next_non_terminal = np.empty_like(values, dtype=np.float32)
    next_non_terminal[-1] = 1.0 - np.asarray(last_dones, dtype=np.float32)
    next_non_terminal[:-1] = 1.0 - episode_starts[1:]
    next_values = np.empty_like(values)
    next_values[-1] = last_values
    next_values[:-1] = values[1:]
    delta = rewards + gamma * next_values * next_non_terminal - values
    decay = gamma * gae_lambda * next_non_terminal
    advantages = np.zeros_like(rewards, dtype=np.float32)
    last_gae = np.zeros_like(last_values, dtype=np.float32)
    for t in reversed(range(n_steps)):
        last_gae = delta[t] + decay[t] * last_gae
        advantages[t] = last_gae
    return advantages, (advantages + values).astype(np.float32)


def explained_variance(y_pred: np.ndarray, y_true: np.ndarray) -> float:
    """``1 - Var[y_true - y_pred] / Var[y_true]``; NaN when ``y_true`` is constant (as SB3).

    In float64 with dot products: logged once per update (every 5 steps for A2C), where
    ``np.var``'s Python layers cost more than the arithmetic.

    >>> explained_variance(np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, 3.0]))
    1.0
    """
    true = np.asarray(y_true, dtype=np.float64).ravel()
    resid = true - np.asarray(y_pred, dtype=np.float64).ravel()
    n = true.size
    centred = true - np.add.reduce(true) / n
    var_y = float(np.dot(centred, centred)) / n
    if var_y == 0:
        return float("nan")
    resid -= np.add.reduce(resid) / n
    return 1.0 - float(np.dot(resid, resid)) / n / var_y
