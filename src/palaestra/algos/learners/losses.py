"""The parts of the losses several algorithms share, written once over an array namespace
``xp`` with their vector-Jacobian products beside them (the critics' Q regression and the min
over twin critics, of SAC and TD3), Polyak averaging, and GAE and explained variance (not
differentiated). Each algorithm's own loss is in its package (``palaestra.algos.dqn.objective``...).

Each loss returns ``(loss, metrics, tape)``: ``loss`` is what autograd differentiates on the
torch learner, ``metrics`` the logged values (numbers the caller turns into floats), ``tape``
what the VJP needs on the numpy learner.

References: Schulman et al. 2016 (GAE).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "explained_variance",
    "gae",
    "min_of",
    "min_of_vjp",
    "polyak",
    "q_regression_loss",
    "q_regression_loss_vjp",
]


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
