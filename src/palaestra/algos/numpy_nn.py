"""Numpy forward/backward for chains of Linear + ReLU/Tanh layers, and Adam with global-norm
clipping on one flat buffer: the pieces of the numpy trainers.

Everything works on *views* of torch tensors (parameters, ``exp_avg``, ``exp_avg_sq``,
``step``), so the torch model and optimizer stay the single source of truth for ``save``,
``load`` and the torch code paths. The math follows ``torch.optim.Adam`` (non-fused) and
``clip_grad_norm_``.
"""

from __future__ import annotations

import ctypes
import glob
import itertools
import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache
from typing import Any

import numpy as np
import torch
from torch import nn

__all__ = [
    "FlatAdam",
    "Layer",
    "LayerViews",
    "adam_ok",
    "backward",
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
    """Numpy views ``(weight, bias, activation)`` of each layer's parameters."""
    return [(lin.weight.detach().numpy(), lin.bias.detach().numpy(), act) for lin, act in chain]


class LayerViews:
    """``views`` of several chains, taken again only when a parameter has moved.

    Taking the views costs ~1 µs per tensor, more than a small layer's math; checking the
    data pointers is cheaper. A ``deepcopy`` gives new pointers, so a copy takes its own views.
    """

    def __init__(self, *chains: list[tuple[nn.Linear, str]]) -> None:
        self.chains = chains
        self._params = [p for chain in chains for lin, _ in chain for p in (lin.weight, lin.bias)]
        self._key: list[int] = []
        self._views: list[list[Layer]] = []

    def __call__(self) -> list[list[Layer]]:
        """One list of layer views per chain."""
        key = [p.data_ptr() for p in self._params]
        if key != self._key:
            self._key, self._views = key, [views(chain) for chain in self.chains]
        return self._views


def forward(layers: list[Layer], x: np.ndarray) -> list[np.ndarray]:
    """Activations after each layer, the input first."""
    acts = [x]
    for w, b, act in layers:
        h = acts[-1].dot(w.T)  # ndarray.dot: less call overhead than ``@``
        h += b
        if act == "relu":
            np.maximum(h, 0.0, out=h)
        elif act == "tanh":
            np.tanh(h, out=h)
        acts.append(h)
    return acts


def backward(
    layers: list[Layer], acts: list[np.ndarray], grad_out: np.ndarray, out: list[np.ndarray]
) -> None:
    """Write the gradients ``[dW0, db0, dW1, ...]`` into ``out`` (float32 arrays, e.g. views
    of ``FlatAdam.grads``), given d(loss)/d(out) taken *after* the last layer's activation
    (the head has none)."""
    g = grad_out
    ones = _ones(g.shape[0])
    for i in range(len(layers) - 1, -1, -1):
        w, _, act = layers[i]
        if act == "relu":
            g = g * (acts[i + 1] > 0)
        elif act == "tanh":  # g * (1 - a^2), with one temporary
            d = acts[i + 1] * acts[i + 1]
            np.subtract(1.0, d, out=d)
            g = np.multiply(g, d, out=d)
        np.matmul(g.T, acts[i], out=out[2 * i])
        # Column sums as one BLAS call: np.sum over axis 0 costs ~4x more at 256 x 64.
        np.matmul(ones, g, out=out[2 * i + 1])
        if i:
            g = g.dot(w)


@cache
def _ones(n: int) -> np.ndarray:
    """A read-only float32 vector of ``n`` ones (shared: batch sizes repeat)."""
    ones = np.ones(n, dtype=np.float32)
    ones.flags.writeable = False
    return ones


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


class FlatAdam:
    """``torch.optim.Adam``'s update, done in numpy on one flat float32 buffer.

    The parameters and the optimizer's ``exp_avg``/``exp_avg_sq``/``step`` tensors are rebound
    as views of flat torch buffers, so one step is about a dozen numpy operations over all
    weights instead of a dozen per tensor (per-tensor overhead was most of a small net's
    update), and torch (``save``, ``load``, the torch code paths) keeps seeing the same tensors.
    Numpy views of these buffers are cached, taken again after a rebinding, and left out of
    copies (``__getstate__``), so a ``deepcopy`` of the model and its trainer stays wired
    together. The math is torch's non-fused float32 formula. The backward pass writes into
    ``grad_views()``.
    """

    def __init__(self, optimizer: torch.optim.Optimizer, params: list[torch.Tensor]):
        self.optimizer, self.params = optimizer, params
        bounds = np.cumsum([0] + [p.numel() for p in params])
        self.slices = [slice(int(a), int(b)) for a, b in itertools.pairwise(bounds)]
        self.grad = np.zeros(int(bounds[-1]), dtype=np.float32)
        self._tmp, self._tmp2 = np.empty_like(self.grad), np.empty_like(self.grad)
        self._grad_views: list[np.ndarray] | None = None
        self._np: tuple[np.ndarray, ...] | None = None  # numpy views of the torch buffers
        self._bind_params()
        self._bind_state()

    def __getstate__(self) -> dict[str, Any]:
        """Copies (``deepcopy``, pickle) drop the cached numpy views: a copy of a view does
        not share memory with the copied buffer, so they are taken again from the copy."""
        state = self.__dict__.copy()
        state["_grad_views"] = state["_np"] = None
        return state

    def _bind_params(self) -> None:
        """Make the parameters views of one flat buffer, keeping their values. This moves
        them: numpy views taken earlier (acting) must be taken again."""
        flat = torch.empty(self.grad.size)
        with torch.no_grad():
            for p, sl in zip(self.params, self.slices):
                flat[sl].copy_(p.reshape(-1))
                p.data = flat[sl].view_as(p)
        self._flat, self._np = flat, None

    def _bind_state(self) -> None:
        """Make the optimizer state views of flat buffers, keeping its values
        (``optimizer.load_state_dict`` replaces the state tensors: this runs again then)."""
        size = self.grad.size
        m, v, steps = torch.zeros(size), torch.zeros(size), torch.zeros(len(self.params))
        state = self.optimizer.state
        for i, (p, sl) in enumerate(zip(self.params, self.slices)):
            st = state[p]
            if st:
                m[sl].copy_(st["exp_avg"].reshape(-1))
                v[sl].copy_(st["exp_avg_sq"].reshape(-1))
                steps[i] = float(st["step"])
            st["step"] = steps[i]
            st["exp_avg"] = m[sl].view_as(p)
            st["exp_avg_sq"] = v[sl].view_as(p)
        self._m, self._v, self._steps, self._np = m, v, steps, None
        self._bound: list[tuple[dict[str, Any], torch.Tensor]] = [
            (state[p], state[p]["exp_avg"]) for p in self.params
        ]

    def _params_bound(self) -> bool:
        base = self._flat.data_ptr()
        return all(p.data_ptr() == base + 4 * sl.start for p, sl in zip(self.params, self.slices))

    def _state_bound(self) -> bool:
        state = self.optimizer.state
        return all(
            state.get(p) is st and st["exp_avg"] is m
            for p, (st, m) in zip(self.params, self._bound)
        )

    def grad_views(self) -> list[np.ndarray]:
        """Per-parameter views of the flat gradient buffer, in ``params`` order."""
        if self._grad_views is None:
            self._grad_views = [
                self.grad[sl].reshape(p.shape) for p, sl in zip(self.params, self.slices)
            ]
        return self._grad_views

    def step(self) -> None:
        """Apply ``self.grad`` (already clipped) to the parameters."""
        if not self._params_bound():  # something moved the parameters (e.g. ``.to()``)
            self._bind_params()
        if not self._state_bound():
            self._bind_state()
        if self._np is None:
            self._np = (self._flat.numpy(), self._m.numpy(), self._v.numpy(), self._steps.numpy())
        p, m, v, steps = self._np
        group = self.optimizer.param_groups[0]
        hyper = float(group["lr"]), *group["betas"], float(group["eps"])
        steps += 1
        first = float(steps[0])
        if not np.count_nonzero(steps != first):
            _adam_update(self.grad, p, m, v, self._tmp, self._tmp2, first, *hyper)
        else:  # per-tensor step counts (state loaded from elsewhere): one update per tensor
            for sl, t in zip(self.slices, steps.tolist()):
                g, tmp, tmp2 = self.grad[sl], self._tmp[sl], self._tmp2[sl]
                _adam_update(g, p[sl], m[sl], v[sl], tmp, tmp2, t, *hyper)

    def clip_grad_norm(self, max_norm: float) -> None:
        """Scale ``self.grad`` in place like ``clip_grad_norm_`` (coefficient clamped at 1)."""
        total = math.sqrt(float(np.dot(self.grad, self.grad)))
        coef = max_norm / (total + 1e-6)
        if coef < 1.0:
            self.grad *= coef


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
