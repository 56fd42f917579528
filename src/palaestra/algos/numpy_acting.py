"""Acting in numpy: the per-step forward pass of small MLP policies without torch dispatch.

At batch sizes of 1-16 a torch forward costs tens of microseconds of framework overhead per
layer; the same matmuls in numpy cost a few. ``numpy_mlp`` turns a chain of torch modules
into a numpy function over *views* of the CPU parameters, so optimizer steps, target updates
and ``load_state_dict`` (all in place) are seen without copying. Anything it cannot express
(convolutions, one-hot inputs, other activations, GPU tensors) returns ``None`` and the caller
keeps the torch path. Training always uses torch.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from torch import nn

from palaestra.algos.networks import FlattenExtractor

__all__ = ["log_softmax", "numpy_mlp", "sample_categorical"]

NumpyFn = Callable[[np.ndarray], np.ndarray]


def _flatten_modules(modules: list[nn.Module]) -> list[nn.Module] | None:
    out: list[nn.Module] = []
    for m in modules:
        if isinstance(m, nn.Sequential):
            inner = _flatten_modules(list(m))
            if inner is None:
                return None
            out += inner
        elif isinstance(m, (nn.Linear, nn.ReLU, nn.Tanh, nn.Flatten, FlattenExtractor)):
            out.append(m)
        else:
            return None
    return out


def numpy_mlp(modules: list[nn.Module]) -> NumpyFn | None:
    """``x [B, in] float32 -> [B, out]`` through Linear/ReLU/Tanh/Flatten modules, or None."""
    flat = _flatten_modules(modules)
    if flat is None:
        return None
    steps: list[tuple[str, np.ndarray | None, np.ndarray | None]] = []
    for m in flat:
        if isinstance(m, nn.Linear):
            if m.weight.device.type != "cpu" or m.weight.dtype != torch.float32:
                return None
            bias = None if m.bias is None else m.bias.detach().numpy()
            steps.append(("linear", m.weight.detach().numpy().T, bias))  # views, not copies
        elif isinstance(m, nn.ReLU):
            steps.append(("relu", None, None))
        elif isinstance(m, nn.Tanh):
            steps.append(("tanh", None, None))
        else:
            steps.append(("flatten", None, None))

    def forward(x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=np.float32)
        for op, w, b in steps:
            if op == "linear":
                x = x @ w
                if b is not None:
                    x += b
            elif op == "relu":
                np.maximum(x, 0.0, out=x)
            elif op == "tanh":
                np.tanh(x, out=x)
            else:
                x = x.reshape(x.shape[0], -1)
        return x

    return forward


def log_softmax(logits: np.ndarray) -> np.ndarray:
    """Row-wise, numerically stable."""
    shifted = logits - logits.max(axis=1, keepdims=True)
    return shifted - np.log(np.exp(shifted).sum(axis=1, keepdims=True))


def sample_categorical(
    logp: np.ndarray, rng: np.random.Generator, deterministic: bool
) -> np.ndarray:
    """Row-wise draws (inverse CDF) or the argmax of log-probabilities ``[B, n]``."""
    if deterministic:
        return logp.argmax(axis=1)
    cdf = np.cumsum(np.exp(logp), axis=1)
    u = rng.random((logp.shape[0], 1)) * cdf[:, -1:]
    return np.minimum((cdf < u).sum(axis=1), logp.shape[1] - 1)
