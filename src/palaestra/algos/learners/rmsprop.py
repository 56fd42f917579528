"""RMSprop on one flat float32 buffer, owned by numpy, beside ``FlatAdam``; and handing its
state to and from a ``torch.optim.RMSprop``.

A2C's optimizer (SB3: ``alpha=0.99``, ``eps=rms_prop_eps``, no momentum, not centred). The
math is torch's single-tensor float32 formula in torch's order of operations
(``v = alpha * v + (1 - alpha) * g * g``; ``p -= lr * g / (sqrt(v) + eps)``), so the squared
averages and the parameters match torch's RMSprop to float32 rounding (tested). As with
``FlatAdam``, the torch optimizer is only read and written at the learner's synchronisation
points, so a model file holds ordinary ``torch.optim.RMSprop`` state.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch

from palaestra.algos.learners.adam import clip_flat_grad_norm

__all__ = ["FlatRMSprop", "rmsprop_unsupported"]


def rmsprop_unsupported(optimizer: torch.optim.Optimizer) -> str | None:
    """Why ``FlatRMSprop`` cannot stand in for ``optimizer`` (None: it can)."""
    if type(optimizer) is not torch.optim.RMSprop:
        return f"the optimizer is {type(optimizer).__name__}, not RMSprop"
    if len(optimizer.param_groups) != 1:
        return "the optimizer has several parameter groups"
    group = optimizer.param_groups[0]
    for option in ("centered", "maximize", "differentiable", "capturable"):
        if group.get(option):
            return f"RMSprop with {option}=True"
    if group.get("momentum"):
        return "RMSprop with momentum"
    return None


class FlatRMSprop:
    """``torch.optim.RMSprop`` (L2 ``weight_decay`` included, no momentum, not centred) over
    a flat float32 buffer; ``grad`` is the flat gradient the backward pass writes into."""

    def __init__(self, size: int, n_tensors: int, slices: list[slice]) -> None:
        self.slices = slices
        self.grad = np.zeros(size, dtype=np.float32)
        self.square_avg = np.zeros(size, dtype=np.float32)
        self.steps = np.zeros(n_tensors, dtype=np.float32)  # torch keeps one per tensor
        self._tmp, self._tmp2 = np.empty_like(self.grad), np.empty_like(self.grad)
        self.lr, self.alpha, self.eps, self.weight_decay = 1e-2, 0.99, 1e-8, 0.0

    def clip_grad_norm(self, max_norm: float) -> None:
        """Scale ``grad`` in place like ``clip_grad_norm_`` (coefficient clamped at 1)."""
        clip_flat_grad_norm(self.grad, max_norm)

    def step(self, params: np.ndarray) -> None:
        """Apply ``grad`` (already clipped) to ``params`` in place."""
        g, v, tmp, tmp2 = self.grad, self.square_avg, self._tmp, self._tmp2
        if self.weight_decay:
            g += self.weight_decay * params  # torch: grad.add(param, alpha=wd)
        self.steps += 1  # counted, as torch does, though the update does not use it
        v *= np.float32(self.alpha)  # square_avg.mul_(alpha).addcmul_(g, g, value=1 - alpha)
        np.multiply(g, np.float32(1.0 - self.alpha), out=tmp)
        tmp *= g
        v += tmp
        np.sqrt(v, out=tmp)  # avg = square_avg.sqrt().add_(eps)
        tmp += np.float32(self.eps)
        np.multiply(g, np.float32(-self.lr), out=tmp2)  # param.addcdiv_(g, avg, value=-lr)
        tmp2 /= tmp
        params += tmp2

    def to_torch(self, optimizer: torch.optim.Optimizer, tensors: Sequence[torch.Tensor]) -> None:
        """Write the squared averages and step counts into ``optimizer``'s state for
        ``tensors`` (the torch parameters in this buffer's order), as torch keeps them."""
        optimizer.param_groups[0]["lr"] = self.lr
        state = optimizer.state
        for i, (p, sl) in enumerate(zip(tensors, self.slices)):
            if not self.steps[i]:
                state.pop(p, None)  # never stepped: torch has no state for it either
                continue
            state[p] = {
                "step": torch.tensor(float(self.steps[i]), dtype=torch.float32),
                "square_avg": torch.from_numpy(self.square_avg[sl].copy()).view_as(p),
            }

    def from_torch(self, optimizer: torch.optim.Optimizer, tensors: Sequence[torch.Tensor]) -> None:
        """Read the hyperparameters, squared averages and step counts from ``optimizer``."""
        group = optimizer.param_groups[0]
        self.lr, self.alpha = float(group["lr"]), float(group["alpha"])
        self.eps, self.weight_decay = float(group["eps"]), float(group["weight_decay"] or 0.0)
        state = optimizer.state
        for i, (p, sl) in enumerate(zip(tensors, self.slices)):
            st = state.get(p)
            if not st:
                self.square_avg[sl] = self.steps[i] = 0.0
                continue
            self.square_avg[sl] = st["square_avg"].detach().reshape(-1).cpu().numpy()
            self.steps[i] = float(st["step"])
