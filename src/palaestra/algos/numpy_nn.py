"""Numpy forward/backward for chains of Linear + ReLU/Tanh layers, global-norm clipping, and
Adam on views of a ``torch.optim.Adam``'s state: the pieces of the numpy trainers.

Everything works on *views* of torch tensors (parameters, ``exp_avg``, ``exp_avg_sq``,
``step``), so the torch model and optimizer stay the single source of truth for ``save``,
``load`` and the torch code paths. The math follows ``torch.optim.Adam`` (non-fused) and
``clip_grad_norm_``.
"""

from __future__ import annotations

import ctypes
import glob
import os
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache
from typing import Any

import numpy as np
import torch
from torch import nn

__all__ = [
    "Layer",
    "adam_ok",
    "adam_step",
    "backward",
    "clip_grads",
    "forward",
    "linear_chain",
    "views",
]

Layer = tuple[np.ndarray, np.ndarray, str]  # weight [out, in], bias [out], activation after


def linear_chain(modules: list[nn.Module]) -> list[tuple[nn.Linear, str]] | None:
    """``[(linear, activation)]`` for modules made only of Linear(bias)/ReLU/Tanh/Flatten on
    the CPU in float32, else None."""
    out: list[tuple[nn.Linear, str]] = []
    for m in modules:
        for sub in m.modules():
            if isinstance(sub, nn.Linear):
                if (
                    sub.bias is None
                    or sub.weight.device.type != "cpu"
                    or sub.weight.dtype != torch.float32
                ):
                    return None
                out.append((sub, "none"))
            elif isinstance(sub, (nn.ReLU, nn.Tanh)):
                if not out or out[-1][1] != "none":
                    return None
                out[-1] = (out[-1][0], "relu" if isinstance(sub, nn.ReLU) else "tanh")
            elif not isinstance(sub, nn.Sequential | nn.Flatten) and type(sub).__name__ not in (
                "FlattenExtractor",
                "QNetwork",
            ):
                return None
    return out


def views(chain: list[tuple[nn.Linear, str]]) -> list[Layer]:
    return [(lin.weight.detach().numpy(), lin.bias.detach().numpy(), act) for lin, act in chain]


def forward(layers: list[Layer], x: np.ndarray) -> list[np.ndarray]:
    """Activations after each layer, the input first."""
    acts = [x]
    for w, b, act in layers:
        h = acts[-1] @ w.T
        h += b
        if act == "relu":
            np.maximum(h, 0.0, out=h)
        elif act == "tanh":
            np.tanh(h, out=h)
        acts.append(h)
    return acts


def backward(
    layers: list[Layer], acts: list[np.ndarray], grad_out: np.ndarray
) -> tuple[list[np.ndarray], np.ndarray]:
    """Gradients ``[dW0, db0, dW1, ...]`` and the gradient at the input, given d(loss)/d(out).
    ``grad_out`` is taken *after* the last layer's activation (the head has none)."""
    grads: list[np.ndarray] = []
    g = grad_out
    for i in range(len(layers) - 1, -1, -1):
        w, _, act = layers[i]
        if act == "relu":
            g = g * (acts[i + 1] > 0)
        elif act == "tanh":
            g = g * (1.0 - acts[i + 1] * acts[i + 1])
        grads[:0] = [g.T @ acts[i], g.sum(axis=0)]
        g = g @ w
    return grads, g


def clip_grads(grads: list[np.ndarray], max_norm: float) -> None:
    """In place, like ``clip_grad_norm_`` (coefficient clamped at 1)."""
    total = np.sqrt(sum(float(np.dot(g.ravel(), g.ravel())) for g in grads))
    coef = max_norm / (total + 1e-6)
    if coef < 1.0:
        for g in grads:
            g *= coef


def adam_ok(optimizer: torch.optim.Optimizer) -> bool:
    """Plain Adam: one group, no weight decay/amsgrad/maximize."""
    if type(optimizer) is not torch.optim.Adam or len(optimizer.param_groups) != 1:
        return False
    g = optimizer.param_groups[0]
    return not (
        g.get("weight_decay")
        or g.get("amsgrad")
        or g.get("maximize")
        or g.get("differentiable")
        or g.get("capturable")
        or g.get("decoupled_weight_decay")
    )


def adam_step(
    optimizer: torch.optim.Optimizer, params: list[torch.Tensor], grads: list[np.ndarray]
) -> None:
    """One ``torch.optim.Adam`` step done in numpy on views of ``params`` and their state."""
    group = optimizer.param_groups[0]
    lr, (beta1, beta2), eps = float(group["lr"]), group["betas"], float(group["eps"])
    for p, grad in zip(params, grads, strict=True):
        st = optimizer.state[p]
        if not st:  # the zero state torch creates on a first step
            st["step"] = torch.tensor(0.0)
            st["exp_avg"] = torch.zeros_like(p, memory_format=torch.preserve_format)
            st["exp_avg_sq"] = torch.zeros_like(p, memory_format=torch.preserve_format)
        st["step"] += 1
        t = float(st["step"])
        m, v = st["exp_avg"].numpy(), st["exp_avg_sq"].numpy()
        m *= beta1
        m += (1.0 - beta1) * grad
        v *= beta2
        v += (1.0 - beta2) * grad * grad
        denom = np.sqrt(v) / np.sqrt(1.0 - beta2**t) + eps
        param = p.detach().numpy()
        param -= (lr / (1.0 - beta1**t)) * m / denom


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
