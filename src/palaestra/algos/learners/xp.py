"""Array namespaces: the few operations the networks, heads and losses are written in, for numpy
and for torch, so that each of those functions exists once and runs on either backend.

The numpy namespace binds numpy's ufuncs and their ``reduce`` methods directly (at the batch
sizes of small-net training, the Python layers of ``np.sum``/``np.clip`` cost more than the
arithmetic); the torch namespace binds the torch functions whose gradients the hand-written
vector-Jacobian products reproduce (``torch.minimum`` splits a tie's gradient evenly,
``torch.clamp`` passes it on its closed interval). Arithmetic operators need no entry: they
mean the same on both arrays.
"""

from __future__ import annotations

import contextlib
import math
from functools import cache
from types import SimpleNamespace
from typing import Any

import numpy as np
import torch

__all__ = ["numpy_ops", "row_indices", "torch_ops"]


@cache
def row_indices(n: int) -> np.ndarray:
    """A read-only ``arange(n)`` (int64), shared: the losses pick one entry per row of every
    minibatch, and batch sizes repeat, so the index is built once per size."""
    rows = np.arange(n)
    rows.flags.writeable = False
    return rows


def _np_mean(x: np.ndarray) -> float:
    """A Python float: numpy means feed logs and comparisons, never gradients."""
    return float(np.add.reduce(x, axis=None)) / x.size


def _np_take_rows(x: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``x[i, idx[i]]`` for each row."""
    return x[row_indices(x.shape[0]), idx]


def _np_clip(x: np.ndarray, low: float, high: float) -> np.ndarray:
    return np.minimum(np.maximum(x, low), high)


def _np_softplus(x: np.ndarray) -> np.ndarray:
    return np.logaddexp(np.float32(0.0), x)


def _np_log_softmax(x: np.ndarray) -> np.ndarray:
    shifted = x - np.maximum.reduce(x, axis=1, keepdims=True)
    return shifted - np.log(np.add.reduce(np.exp(shifted), axis=1, keepdims=True))


def _np_standardize(x: np.ndarray) -> np.ndarray:
    """SB3's per-minibatch advantage normalisation: ``(x - mean) / (std(ddof=1) + 1e-8)``."""
    n = x.shape[0]
    centred = x - np.add.reduce(x) / n
    std = math.sqrt(float(np.dot(centred, centred)) / (n - 1))
    return centred / np.float32(std + 1e-8)


numpy_ops = SimpleNamespace(
    name="numpy",
    exp=np.exp,
    log=np.log,
    tanh=np.tanh,
    sqrt=np.sqrt,
    log1p=np.log1p,
    abs=np.abs,
    minimum=np.minimum,
    maximum=np.maximum,
    where=np.where,
    clip=_np_clip,
    softplus=_np_softplus,
    log_softmax=_np_log_softmax,
    sum_rows=lambda x: np.add.reduce(x, axis=1),
    repeat_cols=lambda x, n: np.repeat(x, n, axis=1),
    sum=lambda x: np.add.reduce(x, axis=None),
    mean=_np_mean,
    max_rows=lambda x: np.maximum.reduce(x, axis=1),
    take_rows=_np_take_rows,
    standardize=_np_standardize,
    count_mean=lambda mask: float(np.count_nonzero(mask)) / mask.size,
    scalar=float,
    stop_gradient=lambda x: x,
    no_grad=contextlib.nullcontext,
)


def _torch_ops() -> SimpleNamespace:
    def standardize(x: Any) -> Any:
        return (x - x.mean()) / (x.std() + 1e-8)

    return SimpleNamespace(
        name="torch",
        exp=torch.exp,
        log=torch.log,
        tanh=torch.tanh,
        sqrt=torch.sqrt,
        log1p=torch.log1p,
        abs=torch.abs,
        minimum=torch.minimum,
        maximum=torch.maximum,
        where=torch.where,
        clip=torch.clamp,
        softplus=torch.nn.functional.softplus,
        log_softmax=lambda x: torch.log_softmax(x, dim=1),
        sum_rows=lambda x: x.sum(dim=1),
        repeat_cols=lambda x, n: x.repeat(1, n),
        sum=torch.sum,
        mean=torch.mean,
        max_rows=lambda x: x.max(dim=1).values,
        take_rows=lambda x, idx: x.gather(1, idx.long().reshape(-1, 1)).squeeze(1),
        standardize=standardize,
        count_mean=lambda mask: mask.float().mean(),
        scalar=lambda x: float(x.detach()) if hasattr(x, "detach") else float(x),
        stop_gradient=lambda x: x.detach(),
        no_grad=torch.no_grad,
    )


torch_ops = _torch_ops()
