"""``RMSpropTFLike``: RMSprop as TensorFlow (and so SB2 and the A2C paper's code) computes it,
which SB3 offers for A2C (``policy_kwargs=dict(optimizer_class=RMSpropTFLike,
optimizer_kwargs=dict(eps=1e-5))``, the RL Zoo's Atari setting).

It differs from ``torch.optim.RMSprop`` in two places: the squared-gradient average starts at
ones, not zeros (so the first steps are small instead of ``lr``-sized), and ``eps`` is added
inside the square root (``g / sqrt(v + eps)``, torch: ``g / (sqrt(v) + eps)``). The update is
SB3's, operation for operation, so the parameters match SB3's to float32 rounding (tested).

palaestra's numpy learner runs ``torch.optim.RMSprop`` and Adam only; a model with this
optimizer trains on the torch learner, and ``verbose=1`` says so.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import torch

__all__ = ["RMSpropTFLike"]


class RMSpropTFLike(torch.optim.Optimizer):
    """TF-style RMSprop: ``v = alpha * v + (1 - alpha) * g**2`` from ``v = 1``, then
    ``p -= lr * g / sqrt(v + eps)`` (``centered``: ``sqrt(v - mean(g)**2 + eps)``; with
    ``momentum``: ``b = momentum * b + g / sqrt(...)``, ``p -= lr * b``). ``weight_decay``
    adds ``weight_decay * p`` to the gradient (L2), as in torch's RMSprop.

    :param params: parameters, or dicts of parameter groups
    :param lr: learning rate (1e-2)
    :param alpha: smoothing constant of the squared-gradient average (0.99)
    :param eps: added to the average inside the square root (1e-8)
    :param weight_decay: L2 penalty (0)
    :param momentum: momentum factor (0)
    :param centered: divide by the estimated variance of the gradient instead (False)
    """

    def __init__(
        self,
        params: Iterable[torch.nn.Parameter] | Iterable[dict[str, Any]],
        lr: float = 1e-2,
        alpha: float = 0.99,
        eps: float = 1e-8,
        weight_decay: float = 0,
        momentum: float = 0,
        centered: bool = False,
    ) -> None:
        # SB3's checks and messages (ValueError, the value named)
        for label, value in (
            ("learning rate", lr),
            ("epsilon value", eps),
            ("momentum value", momentum),
            ("weight_decay value", weight_decay),
            ("alpha value", alpha),
        ):
            if not 0.0 <= value:
                raise ValueError(f"Invalid {label}: {value}")
        defaults = {
            "lr": lr,
            "momentum": momentum,
            "alpha": alpha,
            "eps": eps,
            "centered": centered,
            "weight_decay": weight_decay,
        }
        super().__init__(params, defaults)

    def __setstate__(self, state: dict[str, Any]) -> None:
        super().__setstate__(state)
        for group in self.param_groups:  # groups saved before these options existed
            group.setdefault("momentum", 0)
            group.setdefault("centered", False)

    @torch.no_grad()
    def step(self, closure: Callable[[], float] | None = None) -> float | None:  # type: ignore[override]
        """One update of every parameter that has a gradient; returns ``closure()``'s loss
        (re-evaluated with gradients on) when given."""
        loss = None
        if closure is not None:
            with torch.enable_grad():
                loss = closure()
        for group in self.param_groups:
            for param in group["params"]:
                if param.grad is not None:
                    self._update(param, group)
        return loss

    def _update(self, param: torch.Tensor, group: dict[str, Any]) -> None:
        grad = param.grad
        assert grad is not None
        if grad.is_sparse:
            raise RuntimeError("RMSpropTF does not support sparse gradients")
        state = self.state[param]
        if not state:
            state["step"] = 0
            state["square_avg"] = torch.ones_like(param, memory_format=torch.preserve_format)
            if group["momentum"] > 0:
                state["momentum_buffer"] = torch.zeros_like(
                    param, memory_format=torch.preserve_format
                )
            if group["centered"]:
                state["grad_avg"] = torch.zeros_like(param, memory_format=torch.preserve_format)
        state["step"] += 1
        alpha, eps, lr = group["alpha"], group["eps"], group["lr"]
        if group["weight_decay"] != 0:
            grad = grad.add(param, alpha=group["weight_decay"])
        square_avg = state["square_avg"]
        square_avg.mul_(alpha).addcmul_(grad, grad, value=1 - alpha)
        if group["centered"]:
            grad_avg = state["grad_avg"]
            grad_avg.mul_(alpha).add_(grad, alpha=1 - alpha)
            denominator = square_avg.addcmul(grad_avg, grad_avg, value=-1).add_(eps).sqrt_()
        else:
            denominator = square_avg.add(eps).sqrt_()  # eps inside the root: TF's order
        if group["momentum"] > 0:
            buffer = state["momentum_buffer"]
            buffer.mul_(group["momentum"]).addcdiv_(grad, denominator)
            param.add_(buffer, alpha=-lr)
        else:
            param.addcdiv_(grad, denominator, value=-lr)
