"""DQN updates in numpy for small MLP Q-networks on the CPU.

For a ``[64, 64]`` net and batches of 32-128, torch spends most of an update in framework
overhead (autograd graph, dispatch, optimizer bookkeeping): several times the cost of the
same matmuls done by hand. This trainer does the forward pass, the Huber-loss gradient,
global-norm clipping and Adam in numpy (``numpy_nn``) on views of the torch parameters and
Adam state, so the torch model, ``save``/``load`` and the torch path see the same numbers.
Results agree with the torch path to float32 rounding (tested), not bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from torch import nn

from palaestra.algos.numpy_nn import (
    FlatAdam,
    LayerViews,
    adam_ok,
    backward,
    forward,
    linear_chain,
    one_blas_thread,
)
from palaestra.algos.replay_buffer import ReplayBuffer

__all__ = ["NumpyDQNTrainer"]


class NumpyDQNTrainer:
    """Huber-loss Q-learning updates on numpy views of a torch Q-network and its Adam."""

    def __init__(
        self,
        q_net: nn.Module,
        q_target: nn.Module,
        optimizer: torch.optim.Optimizer,
        chain: list[tuple[nn.Linear, str]],
        target_chain: list[tuple[nn.Linear, str]],
    ):
        self.chain, self.target_chain = chain, target_chain
        self.adam = FlatAdam(optimizer, [p for lin, _ in chain for p in (lin.weight, lin.bias)])
        self._views = LayerViews(chain, target_chain)

    @classmethod
    def build(cls, q_net: nn.Module, q_target: nn.Module, optimizer: Any) -> NumpyDQNTrainer | None:
        """A trainer when the nets are plain CPU float32 MLPs and the optimizer plain Adam."""
        chain, target_chain = linear_chain([q_net]), linear_chain([q_target])
        if not chain or not target_chain or not adam_ok(optimizer):
            return None
        if 2 * len(chain) != len(list(q_net.parameters())):
            return None
        return cls(q_net, q_target, optimizer, chain, target_chain)

    def train(
        self,
        buffer: ReplayBuffer,
        gradient_steps: int,
        batch_size: int,
        rng: np.random.Generator,
        gamma: float,
        max_grad_norm: float,
        action_start: int,
    ) -> float:
        """``gradient_steps`` updates; returns the mean loss."""
        online, target = self._views()
        idx = np.arange(batch_size)
        losses = []
        with one_blas_thread():
            for _ in range(gradient_steps):
                obs, actions, next_obs, rewards, terminated = buffer.sample_arrays(batch_size, rng)
                next_q = forward(target, next_obs.reshape(batch_size, -1).astype(np.float32))[-1]
                y = rewards + (1.0 - terminated) * gamma * next_q.max(axis=1)
                acts = forward(online, obs.reshape(batch_size, -1).astype(np.float32))
                a = actions.astype(np.int64) - action_start
                diff = acts[-1][idx, a] - y
                absd = np.abs(diff)
                losses.append(float(np.where(absd < 1.0, 0.5 * diff * diff, absd - 0.5).mean()))
                grad_out = np.zeros_like(acts[-1])
                grad_out[idx, a] = np.clip(diff, -1.0, 1.0) / batch_size  # d(mean Huber)/dQ
                backward(online, acts, grad_out, self.adam.grad_views())
                self.adam.clip_grad_norm(max_grad_norm)
                self.adam.step()
        return float(np.mean(losses))
