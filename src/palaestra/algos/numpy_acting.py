"""Acting in numpy: the per-step forward pass of small MLP policies without torch dispatch.

At batch sizes of 1-16 a torch forward costs tens of microseconds of framework overhead per
layer; the same matmuls in numpy cost a few. ``numpy_mlp`` turns a chain of torch modules
into a numpy function over *views* of the CPU parameters, so optimizer steps, target updates
and ``load_state_dict`` (all in place) are seen without copying. Anything it cannot express
(convolutions, one-hot inputs, other activations, GPU tensors) returns ``None`` and the caller
keeps the torch path. (Training in numpy: ``numpy_nn``, ``numpy_dqn``, ``numpy_ppo``.)
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
    # (kind, weight.T, bias, activation after it); an activation that follows a linear layer
    # is folded into that step: this runs every env step, where each step costs ~1 µs.
    steps: list[tuple[str, np.ndarray | None, np.ndarray | None, str]] = []
    for m in flat:
        if isinstance(m, nn.Linear):
            if m.weight.device.type != "cpu" or m.weight.dtype != torch.float32:
                return None
            bias = None if m.bias is None else m.bias.detach().numpy()
            steps.append(("linear", m.weight.detach().numpy().T, bias, ""))  # views, not copies
        elif isinstance(m, (nn.ReLU, nn.Tanh)):
            act = "relu" if isinstance(m, nn.ReLU) else "tanh"
            if steps and steps[-1][0] == "linear" and not steps[-1][3]:
                steps[-1] = (*steps[-1][:3], act)
            else:
                steps.append((act, None, None, act))
        else:
            steps.append(("flatten", None, None, ""))

    def forward(x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=np.float32)
        for op, w, b, act in steps:
            if w is not None:  # a linear layer
                x = x.dot(w)  # the method: less call overhead than ``@`` at batch 1-16
                if b is not None:
                    x += b
            elif op == "flatten":
                x = x.reshape(x.shape[0], -1)
            if act == "tanh":
                np.tanh(x, out=x)
            elif act == "relu":
                np.maximum(x, 0.0, out=x)
        return x

    return forward


def log_softmax(logits: np.ndarray) -> np.ndarray:
    """Row-wise, numerically stable."""
    shifted = logits - np.maximum.reduce(logits, axis=1, keepdims=True)
    return shifted - np.log(np.add.reduce(np.exp(shifted), axis=1, keepdims=True))


def sample_categorical(
    logits: np.ndarray, rng: np.random.Generator, deterministic: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Row-wise draws (inverse CDF) or the argmax of categorical logits ``[B, n]``, and the
    log-probability of each pick: ``(indices [B], log_probs [B])``.

    Called every env step with B of 1-16, where each numpy call costs about a microsecond
    whatever its size: the ufuncs' own ``reduce``/``accumulate`` skip the Python layers of
    ``max``/``sum``/``cumsum``, and the CDF is the running sum of the unnormalised
    probabilities (the draw is scaled by their total) so nothing is normalised twice.
    """
    shifted = logits - np.maximum.reduce(logits, axis=1, keepdims=True)
    cdf = np.add.accumulate(np.exp(shifted), axis=1)
    total = cdf[:, -1]
    if deterministic:
        idx = shifted.argmax(axis=1)
    else:
        # u < 1, so u * total < total == cdf[:, -1] (float64 product of a float32 total):
        # at most n - 1 entries lie below, and the index needs no clamp.
        u = rng.random(logits.shape[0]) * total
        idx = np.add.reduce(cdf < u[:, None], axis=1)
    return idx, shifted[np.arange(len(idx)), idx] - np.log(total)
