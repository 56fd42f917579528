"""PPO's math as pure functions: GAE, the clipped surrogate loss, explained variance.

References: Schulman et al. 2016 (GAE), Schulman et al. 2017 (PPO); the exact conventions
(episode_starts bookkeeping, per-minibatch advantage normalisation, KL estimator) are SB3's.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import torch

__all__ = ["PPOLoss", "explained_variance", "gae", "ppo_loss"]


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


class PPOLoss(NamedTuple):
    """The total loss (differentiable) and its logged parts (detached scalars)."""

    loss: torch.Tensor
    policy_loss: torch.Tensor
    value_loss: torch.Tensor
    entropy_loss: torch.Tensor
    clip_fraction: torch.Tensor
    approx_kl: torch.Tensor


def ppo_loss(
    log_prob: torch.Tensor,
    old_log_prob: torch.Tensor,
    advantages: torch.Tensor,
    values: torch.Tensor,
    old_values: torch.Tensor,
    returns: torch.Tensor,
    entropy: torch.Tensor | None,
    clip_range: float,
    clip_range_vf: float | None = None,
    ent_coef: float = 0.0,
    vf_coef: float = 0.5,
    normalize_advantage: bool = True,
) -> PPOLoss:
    """Clipped surrogate + value loss - entropy bonus for one minibatch (all inputs ``[B]``)."""
    if normalize_advantage and advantages.numel() > 1:
        # SB3 normalises per minibatch, with the unbiased std and 1e-8.
        advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
    log_ratio = log_prob - old_log_prob
    ratio = torch.exp(log_ratio)
    surrogate = torch.min(
        advantages * ratio, advantages * torch.clamp(ratio, 1 - clip_range, 1 + clip_range)
    )
    policy_loss = -surrogate.mean()
    if clip_range_vf is not None:
        # Value clipping around the rollout's values (OpenAI baselines; off by default in SB3).
        values = old_values + torch.clamp(values - old_values, -clip_range_vf, clip_range_vf)
    value_loss = torch.nn.functional.mse_loss(returns, values)
    # Without an analytic entropy, SB3 approximates it with -log_prob.
    entropy_loss = -torch.mean(-log_prob) if entropy is None else -torch.mean(entropy)
    loss = policy_loss + ent_coef * entropy_loss + vf_coef * value_loss
    with torch.no_grad():
        clip_fraction = torch.mean((torch.abs(ratio - 1) > clip_range).float())
        # http://joschu.net/blog/kl-approx.html: unbiased, low-variance estimator of KL(old||new)
        approx_kl = torch.mean((ratio - 1) - log_ratio)
    return PPOLoss(
        loss,
        policy_loss.detach(),
        value_loss.detach(),
        entropy_loss.detach(),
        clip_fraction,
        approx_kl,
    )


def explained_variance(y_pred: np.ndarray, y_true: np.ndarray) -> float:
    """``1 - Var[y_true - y_pred] / Var[y_true]``; NaN when ``y_true`` is constant (as SB3).

    >>> explained_variance(np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, 3.0]))
    1.0
    """
    var_y = float(np.var(y_true))
    return float("nan") if var_y == 0 else float(1.0 - np.var(y_true - y_pred) / var_y)
