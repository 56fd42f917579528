"""Multi-layer perceptrons as data: one reader of torch module trees, one forward over an array
namespace, and the forward's vector-Jacobian product beside it.

``describe`` turns modules made of ``Linear`` layers, supported activations and flattening into
an ``MLP``: the torch parameters of each layer and the activation after it. The numpy learner
runs ``mlp_forward`` on numpy views of those parameters and differentiates it with
``mlp_forward_vjp``; ``mlp_forward`` on torch tensors is what autograd checks the VJP against.
Anything else (convolutions, a custom extractor, GPU or float64 weights) is not an MLP, and
``describe`` says why.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache, lru_cache
from typing import Any

import numpy as np
import torch
from torch import nn

from palaestra.algos.common.networks import CombinedExtractor, FlattenExtractor

__all__ = [
    "ACTIVATIONS",
    "MLP",
    "NotAnMLP",
    "describe",
    "mlp_forward",
    "mlp_forward_vjp",
]


class NotAnMLP(ValueError):
    """A module tree the numpy learner cannot express; the message says which part."""


# torch module class -> (name, the attribute holding its parameter, default parameter)
ACTIVATIONS: dict[type[nn.Module], tuple[str, str | None]] = {
    nn.ReLU: ("relu", None),
    nn.Tanh: ("tanh", None),
    nn.ELU: ("elu", "alpha"),
    nn.LeakyReLU: ("leaky_relu", "negative_slope"),
    nn.Sigmoid: ("sigmoid", None),
}
Activation = tuple[str, float]  # ("none", 0.0) after a layer without one


@dataclass(frozen=True)
class MLP:
    """Linear layers in order, each with the activation that follows it."""

    linears: tuple[nn.Linear, ...]
    activations: tuple[Activation, ...]

    def parameters(self) -> list[torch.Tensor]:
        """``[W0, b0, W1, b1, ...]``."""
        return [p for lin in self.linears for p in (lin.weight, lin.bias)]


def _leaves(module: nn.Module) -> list[nn.Module]:
    """Modules in forward order: ``Sequential`` containers and the flattening extractor
    (whose forward is its children in order) opened. Another container is returned whole,
    and ``describe`` refuses it: its forward may be anything."""
    if isinstance(module, nn.Sequential | FlattenExtractor):
        return [leaf for child in module.children() for leaf in _leaves(child)]
    if type(module) is CombinedExtractor and all(
        type(sub) is nn.Flatten for sub in module.extractors.values()
    ):  # Dict entries flattened side by side: one flattening of the concatenated input
        return [nn.Flatten()]
    return [module]


def describe(modules: list[nn.Module]) -> MLP:
    """The ``MLP`` that ``modules`` compute in sequence; ``NotAnMLP`` naming what does not fit.

    Only the flattening of vector inputs, ``Linear`` layers with a bias, on the CPU in float32,
    and the ``ACTIVATIONS`` are accepted, each activation after a linear layer.
    """
    linears: list[nn.Linear] = []
    acts: list[Activation] = []
    for leaf in (leaf for m in modules for leaf in _leaves(m)):
        if isinstance(leaf, nn.Linear):
            if leaf.bias is None:
                raise NotAnMLP("a Linear layer without bias")
            if leaf.weight.device.type != "cpu" or leaf.weight.dtype != torch.float32:
                raise NotAnMLP(f"weights on {leaf.weight.device} in {leaf.weight.dtype}")
            linears.append(leaf)
            acts.append(("none", 0.0))
        elif type(leaf) in ACTIVATIONS:
            name, attr = ACTIVATIONS[type(leaf)]
            if not linears or acts[-1][0] != "none":
                raise NotAnMLP(f"{type(leaf).__name__} not directly after a Linear layer")
            acts[-1] = (name, float(getattr(leaf, attr)) if attr else 0.0)
        elif not isinstance(leaf, nn.Flatten):
            raise NotAnMLP(f"{type(leaf).__name__} is not a Linear layer or a known activation")
    if not linears:
        raise NotAnMLP("no Linear layer")
    return MLP(tuple(linears), tuple(acts))


Layer = tuple[Any, Any, Activation]  # weight [out, in], bias [out], activation after


def _np_activate(h: np.ndarray, act: Activation) -> np.ndarray:
    """In place where the activation allows it: the buffer is this layer's own output."""
    name, param = act
    if name == "relu":
        # Against zeros of h's own shape: numpy's contiguous SIMD loop, 2-4x faster than the
        # broadcast scalar 0.0 at these sizes; the same value for every float32 (all 2^32
        # checked, NaN payloads and -0.0 included).
        return np.maximum(h, _zeros(h.shape), out=h)
    if name == "tanh":
        return np.tanh(h, out=h)
    if name == "elu":
        return np.where(h > 0, h, np.float32(param) * np.expm1(h))
    if name == "leaky_relu":
        return np.where(h > 0, h, np.float32(param) * h)
    if name == "sigmoid":
        return 1.0 / (1.0 + np.exp(-h))
    return h


def _torch_activate(h: torch.Tensor, act: Activation) -> torch.Tensor:
    name, param = act
    if name == "relu":
        return torch.relu(h)
    if name == "tanh":
        return torch.tanh(h)
    if name == "elu":
        return nn.functional.elu(h, alpha=param)
    if name == "leaky_relu":
        return nn.functional.leaky_relu(h, negative_slope=param)
    if name == "sigmoid":
        return torch.sigmoid(h)
    return h


def mlp_forward(layers: list[Layer], x: Any) -> list[Any]:
    """The activations after each layer, the input first (numpy arrays or torch tensors)."""
    acts = [x]
    if isinstance(x, np.ndarray):
        for w, b, act in layers:
            h = _product(acts[-1], w.T)
            h += b
            acts.append(_np_activate(h, act))
        return acts
    for w, b, act in layers:
        acts.append(_torch_activate(nn.functional.linear(acts[-1], w, b), act))
    return acts


def _activation_vjp(g: np.ndarray, out: np.ndarray, act: Activation) -> np.ndarray:
    """``g * d(act)/d(pre-activation)``, from the activation's output alone."""
    name, param = act
    if name == "relu":
        return g * (out > 0)
    if name == "tanh":  # g * (1 - a^2), with one temporary
        d = out * out
        np.subtract(1.0, d, out=d)
        return np.multiply(g, d, out=d)
    if name == "elu":  # a > 0: 1; else d/dh alpha (e^h - 1) = a + alpha
        return g * np.where(out > 0, np.float32(1.0), out + np.float32(param))
    if name == "leaky_relu":
        return g * np.where(out > 0, np.float32(1.0), np.float32(param))
    if name == "sigmoid":
        return g * out * (1.0 - out)
    return g


def mlp_forward_vjp(
    layers: list[Layer],
    acts: list[np.ndarray],
    grad_out: np.ndarray,
    param_grads: list[np.ndarray] | None,
    input_grad: bool = False,
) -> np.ndarray | None:
    """Backward pass of ``mlp_forward``: ``grad_out`` is d(loss)/d(output) (after the last
    activation). Writes ``[dW0, db0, dW1, ...]`` into ``param_grads`` (float32 arrays, e.g.
    views of a flat gradient buffer; None: parameters are not trained by this loss) and
    returns d(loss)/d(input) when ``input_grad`` (a critic's gradient with respect to the
    action), else None."""
    g = grad_out
    ones = _ones(g.shape[0])
    for i in range(len(layers) - 1, -1, -1):
        w, _, act = layers[i]
        g = _activation_vjp(g, acts[i + 1], act)
        if param_grads is not None:
            _product(g.T, acts[i], out=param_grads[2 * i])
            # Column sums as one BLAS call: np.sum over axis 0 costs ~4x more at 256 x 64.
            np.matmul(ones, g, out=param_grads[2 * i + 1])
        if i or input_grad:
            g = _product(g, w)
    return g if input_grad else None


# Matrix products of at least this many multiply-adds go through torch's CPU kernels, on the
# same memory: at 256x256x256 they take 0.47 ms against OpenBLAS's 0.64 ms here (one thread
# each), which is most of a SAC/TD3 update at SB3's sizes. Smaller products stay in numpy,
# whose call costs less (and whose results the small-net tests pin bit for bit).
LARGE_PRODUCT = 1 << 22


def _product(a: np.ndarray, b: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``a @ b`` (into ``out`` if given), float32."""
    if a.shape[0] * a.shape[1] * b.shape[1] < LARGE_PRODUCT:
        if out is None:
            return a.dot(b)  # ndarray.dot: less call overhead than ``@``
        return np.matmul(a, b, out=out)
    result = torch.mm(torch.from_numpy(a), torch.from_numpy(b))
    if out is None:
        return result.numpy()
    out[...] = result.numpy()
    return out


@lru_cache(maxsize=64)
def _zeros(shape: tuple[int, ...]) -> np.ndarray:
    """A read-only float32 array of zeros of ``shape`` (shared: layer shapes repeat; bounded,
    as ``predict`` may see any batch size)."""
    zeros = np.zeros(shape, dtype=np.float32)
    zeros.flags.writeable = False
    return zeros


@cache
def _ones(n: int) -> np.ndarray:
    """A read-only float32 vector of ``n`` ones (shared: batch sizes repeat)."""
    ones = np.ones(n, dtype=np.float32)
    ones.flags.writeable = False
    return ones
