"""Adam on one flat float32 buffer, owned by numpy, with global-norm clipping; and handing its
state to and from a ``torch.optim.Adam``.

For a small net, a per-tensor optimizer spends most of its time in per-tensor overhead: here
one step is about a dozen numpy operations over all weights. The math is torch's non-fused
float32 formula, so the moments, the step count and the parameters match torch's Adam to
float32 rounding (tested). The torch optimizer is not touched while training; ``to_torch`` and
``from_torch`` copy the state at the learner's synchronisation points (saving, parameters read
through the model), so a model file holds ordinary ``torch.optim.Adam`` state.
"""

from __future__ import annotations

import ctypes
import glob
import math
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from functools import cache
from typing import Any

import numpy as np
import torch

__all__ = ["FlatAdam", "adam_unsupported", "clip_flat_grad_norm", "one_blas_thread"]


def adam_unsupported(optimizer: torch.optim.Optimizer) -> str | None:
    """Why ``FlatAdam`` cannot stand in for ``optimizer`` (None: it can)."""
    if type(optimizer) is not torch.optim.Adam:
        return f"the optimizer is {type(optimizer).__name__}, not Adam"
    if len(optimizer.param_groups) != 1:
        return "the optimizer has several parameter groups"
    group = optimizer.param_groups[0]
    for option in ("amsgrad", "maximize", "differentiable", "capturable"):
        if group.get(option):
            return f"Adam with {option}=True"
    if group.get("weight_decay") and group.get("decoupled_weight_decay"):
        return "Adam with decoupled_weight_decay=True"
    return None


def clip_flat_grad_norm(grad: np.ndarray, max_norm: float) -> None:
    """Scale a flat gradient in place like ``clip_grad_norm_`` (coefficient clamped at 1)."""
    total = math.sqrt(float(np.dot(grad, grad)))
    coef = max_norm / (total + 1e-6)
    if coef < 1.0:
        grad *= coef


class FlatAdam:
    """``torch.optim.Adam`` (L2 ``weight_decay`` included) over ``params``, a flat float32
    buffer; ``grad`` is the flat gradient the backward pass writes into."""

    def __init__(self, size: int, n_tensors: int, slices: list[slice]) -> None:
        self.slices = slices
        self.grad = np.zeros(size, dtype=np.float32)
        self.m = np.zeros(size, dtype=np.float32)
        self.v = np.zeros(size, dtype=np.float32)
        self.steps = np.zeros(n_tensors, dtype=np.float32)  # torch keeps one per tensor
        self._tmp, self._tmp2 = np.empty_like(self.grad), np.empty_like(self.grad)
        self.lr, self.betas, self.eps, self.weight_decay = 1e-3, (0.9, 0.999), 1e-8, 0.0

    def clip_grad_norm(self, max_norm: float) -> None:
        """Scale ``grad`` in place like ``clip_grad_norm_`` (coefficient clamped at 1)."""
        clip_flat_grad_norm(self.grad, max_norm)

    def step(self, params: np.ndarray) -> None:
        """Apply ``grad`` (already clipped) to ``params`` in place."""
        hyper = self.lr, *self.betas, self.eps
        if self.weight_decay:
            self.grad += self.weight_decay * params  # torch: grad.add(param, alpha=wd)
        self.steps += 1
        first = float(self.steps[0])
        if not np.count_nonzero(self.steps != first):
            _adam_update(self.grad, params, self.m, self.v, self._tmp, self._tmp2, first, *hyper)
        else:  # per-tensor step counts (state loaded from elsewhere): one update per tensor
            for sl, t in zip(self.slices, self.steps.tolist()):
                tmp, tmp2 = self._tmp[sl], self._tmp2[sl]
                _adam_update(
                    self.grad[sl], params[sl], self.m[sl], self.v[sl], tmp, tmp2, t, *hyper
                )

    def to_torch(self, optimizer: torch.optim.Optimizer, tensors: Sequence[torch.Tensor]) -> None:
        """Write the moments and step counts into ``optimizer``'s state for ``tensors`` (the
        torch parameters in this buffer's order), as torch's Adam keeps them."""
        group = optimizer.param_groups[0]
        group["lr"] = self.lr
        state = optimizer.state
        for i, (p, sl) in enumerate(zip(tensors, self.slices)):
            if not self.steps[i]:
                state.pop(p, None)  # never stepped: torch has no state for it either
                continue
            state[p] = {
                "step": torch.tensor(float(self.steps[i]), dtype=torch.float32),
                "exp_avg": torch.from_numpy(self.m[sl].copy()).view_as(p),
                "exp_avg_sq": torch.from_numpy(self.v[sl].copy()).view_as(p),
            }

    def from_torch(self, optimizer: torch.optim.Optimizer, tensors: Sequence[torch.Tensor]) -> None:
        """Read the hyperparameters, moments and step counts from ``optimizer``."""
        group = optimizer.param_groups[0]
        beta1, beta2 = group["betas"]
        self.lr, self.betas = float(group["lr"]), (float(beta1), float(beta2))
        self.eps, self.weight_decay = float(group["eps"]), float(group["weight_decay"] or 0.0)
        state = optimizer.state
        for i, (p, sl) in enumerate(zip(tensors, self.slices)):
            st = state.get(p)
            if not st:
                self.m[sl] = self.v[sl] = self.steps[i] = 0.0
                continue
            self.m[sl] = st["exp_avg"].detach().reshape(-1).cpu().numpy()
            self.v[sl] = st["exp_avg_sq"].detach().reshape(-1).cpu().numpy()
            self.steps[i] = float(st["step"])


def _adam_update(
    g: np.ndarray,
    p: np.ndarray,
    m: np.ndarray,
    v: np.ndarray,
    tmp: np.ndarray,
    tmp2: np.ndarray,
    t: float,
    lr: float,
    beta1: float,
    beta2: float,
    eps: float,
) -> None:
    """One Adam step of ``p`` (in place, with ``m``, ``v``) at step count ``t``: torch's
    non-fused float32 formula, with ``tmp``/``tmp2`` as scratch space."""
    np.subtract(g, m, out=tmp)  # m.lerp_(g, 1 - beta1)
    tmp *= 1.0 - beta1
    m += tmp
    v *= beta2  # v.mul_(beta2).addcmul_(g, g, value=1 - beta2)
    np.multiply(g, g, out=tmp)
    tmp *= 1.0 - beta2
    v += tmp
    np.sqrt(v, out=tmp)
    tmp /= math.sqrt(1.0 - beta2**t)
    tmp += eps
    np.divide(m, tmp, out=tmp2)
    tmp2 *= lr / (1.0 - beta1**t)
    p -= tmp2


@cache
def _openblas() -> Any:
    """numpy's bundled OpenBLAS (``scipy_openblas64_``), or None."""
    pattern = os.path.join(os.path.dirname(np.__file__), os.pardir, "numpy.libs", "*openblas*")
    for path in glob.glob(pattern):
        try:
            lib = ctypes.CDLL(path)
            return lib.scipy_openblas_get_num_threads64_, lib.scipy_openblas_set_num_threads64_
        except (OSError, AttributeError):
            continue
    return None


@cache
def _threadpool_limits() -> Any:
    """threadpoolctl's ``threadpool_limits``, or None (looked up once: a failed import is not
    cached by Python and costs ~50 µs per try, once per update)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        return None
    return threadpool_limits


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run numpy matmuls on one thread, then restore the previous setting.

    OpenBLAS splits even 256x64 matmuls across threads; the synchronisation costs more than
    the math, and on a busy machine it makes an update 10-30x slower (measured). Uses numpy's
    bundled OpenBLAS directly (two C calls), else threadpoolctl when installed, else nothing.
    """
    funcs = _openblas()
    if funcs is not None:
        get, set_ = funcs
        previous = get()
        set_(1)
        try:
            yield
        finally:
            set_(previous)
        return
    limits = _threadpool_limits()
    if limits is None:
        yield
        return
    with limits(1, user_api="blas"):
        yield
