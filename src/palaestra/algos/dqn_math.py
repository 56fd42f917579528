"""DQN's math as pure functions: the Huber TD loss and the (polyak) target update."""

from __future__ import annotations

from collections.abc import Iterable

import torch

__all__ = ["dqn_loss", "polyak_update"]


def dqn_loss(
    q_values: torch.Tensor,
    actions: torch.Tensor,
    rewards: torch.Tensor,
    terminated: torch.Tensor,
    next_q_target: torch.Tensor,
    gamma: float,
) -> torch.Tensor:
    """Huber loss between ``Q(s, a)`` and ``r + gamma * (1 - terminated) * max_a' Q'(s', a')``.

    ``q_values``/``next_q_target``: ``[B, n_actions]`` (online net on ``s``, target net on
    ``s'``); ``actions``: ``[B]`` int; the rest ``[B]``. Huber (smooth L1, delta 1) as in SB3 and
    Mnih et al. 2015's error clipping.

    >>> q = torch.tensor([[1.0, 2.0]]); nq = torch.tensor([[0.0, 3.0]])
    >>> float(dqn_loss(q, torch.tensor([1]), torch.tensor([1.0]), torch.tensor([0.0]), nq, 0.5))
    0.125
    """
    with torch.no_grad():
        target = rewards + (1.0 - terminated) * gamma * next_q_target.max(dim=1).values
    current = q_values.gather(1, actions.long().reshape(-1, 1)).squeeze(1)
    return torch.nn.functional.smooth_l1_loss(current, target)


def polyak_update(
    params: Iterable[torch.Tensor], target_params: Iterable[torch.Tensor], tau: float
) -> None:
    """``target = tau * online + (1 - tau) * target`` in place; ``tau == 1`` copies exactly."""
    with torch.no_grad():
        for p, tp in zip(params, target_params, strict=True):
            if tau == 1.0:
                tp.copy_(p)
            else:
                tp.mul_(1.0 - tau).add_(p, alpha=tau)
