"""DQN updates in numpy for small MLP Q-networks on the CPU.

For a ``[64, 64]`` net and batches of 32-128, torch spends most of an update in framework
overhead (autograd graph, dispatch, optimizer bookkeeping): about 5x the cost of the same
matmuls done by hand. This trainer does the forward pass, the Huber-loss gradient, global
norm clipping and Adam in numpy, on *views* of the torch parameters and of the torch Adam
state (``exp_avg``, ``exp_avg_sq``, ``step``), so the torch model, ``save``/``load``, and a
switch back to the torch path all see the same numbers. Math follows ``torch.optim.Adam``
(non-fused), ``smooth_l1_loss`` (beta 1) and ``clip_grad_norm_``; results agree with the
torch path to float32 rounding (tested), not bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from torch import nn

from palaestra.algos.replay_buffer import ReplayBuffer

__all__ = ["NumpyDQNTrainer"]


def _layers(net: nn.Module) -> list[tuple[nn.Linear, str]] | None:
    """``[(linear, activation after it)]`` for a QNetwork made of Linear/ReLU/Tanh, or None."""
    modules = [m for m in net.modules() if not isinstance(m, (nn.Sequential, nn.Flatten))]
    modules = [m for m in modules if m is not net and type(m).__name__ != "FlattenExtractor"]
    out: list[tuple[nn.Linear, str]] = []
    for m in modules:
        if isinstance(m, nn.Linear):
            out.append((m, "none"))
        elif isinstance(m, (nn.ReLU, nn.Tanh)) and out and out[-1][1] == "none":
            out[-1] = (out[-1][0], "relu" if isinstance(m, nn.ReLU) else "tanh")
        else:
            return None
    return out or None


def _adam_ok(optimizer: torch.optim.Optimizer) -> bool:
    if type(optimizer) is not torch.optim.Adam or len(optimizer.param_groups) != 1:
        return False
    g = optimizer.param_groups[0]
    return not (
        g.get("weight_decay")
        or g.get("amsgrad")
        or g.get("maximize")
        or g.get("differentiable")
        or g.get("capturable")
    )


class NumpyDQNTrainer:
    """Huber-loss Q-learning updates on numpy views of a torch Q-network and its Adam."""

    def __init__(self, q_net: nn.Module, q_target: nn.Module, optimizer: torch.optim.Optimizer):
        self.q_net, self.q_target, self.optimizer = q_net, q_target, optimizer
        self.layers, self.target_layers = _layers(q_net), _layers(q_target)
        self.params = [p for lin, _ in (self.layers or []) for p in (lin.weight, lin.bias)]

    @classmethod
    def build(cls, q_net: nn.Module, q_target: nn.Module, optimizer: Any) -> NumpyDQNTrainer | None:
        """A trainer when the nets are plain CPU float32 MLPs with biases and Adam, else None."""
        trainer = cls(q_net, q_target, optimizer)
        if trainer.layers is None or trainer.target_layers is None or not _adam_ok(optimizer):
            return None
        if any(
            p is None or p.device.type != "cpu" or p.dtype != torch.float32 for p in trainer.params
        ):
            return None
        if len(trainer.params) != len(list(q_net.parameters())):
            return None  # parameters outside the Linear chain: let torch handle them
        return trainer

    @staticmethod
    def _forward(
        layers: list[tuple[np.ndarray, np.ndarray, str]], x: np.ndarray
    ) -> list[np.ndarray]:
        """Activations after each layer (input first)."""
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

    def _adam_state(self) -> list[tuple[np.ndarray, np.ndarray, torch.Tensor]]:
        state = []
        for p in self.params:
            st = self.optimizer.state[p]
            if not st:  # first update: the same zero state torch would create
                st["step"] = torch.tensor(0.0)
                st["exp_avg"] = torch.zeros_like(p, memory_format=torch.preserve_format)
                st["exp_avg_sq"] = torch.zeros_like(p, memory_format=torch.preserve_format)
            state.append((st["exp_avg"].numpy(), st["exp_avg_sq"].numpy(), st["step"]))
        return state

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

        def views(layers: list[tuple[nn.Linear, str]]) -> list[tuple[np.ndarray, np.ndarray, str]]:
            return [
                (lin.weight.detach().numpy(), lin.bias.detach().numpy(), act) for lin, act in layers
            ]

        online, target = views(self.layers or []), views(self.target_layers or [])
        weights = [a for w, b, _ in online for a in (w, b)]
        state = self._adam_state()
        group = self.optimizer.param_groups[0]
        lr, (beta1, beta2), eps = float(group["lr"]), group["betas"], float(group["eps"])
        idx = np.arange(batch_size)
        losses = []
        for _ in range(gradient_steps):
            obs, actions, next_obs, rewards, terminated = buffer.sample_arrays(batch_size, rng)
            next_q = self._forward(target, next_obs.reshape(batch_size, -1).astype(np.float32))[-1]
            y = rewards + (1.0 - terminated) * gamma * next_q.max(axis=1)
            acts = self._forward(online, obs.reshape(batch_size, -1).astype(np.float32))
            a = actions.astype(np.int64) - action_start
            diff = acts[-1][idx, a] - y
            absd = np.abs(diff)
            losses.append(float(np.where(absd < 1.0, 0.5 * diff * diff, absd - 0.5).mean()))
            grad_out = np.zeros_like(acts[-1])
            grad_out[idx, a] = np.clip(diff, -1.0, 1.0) / batch_size  # d(mean Huber)/dQ
            grads: list[np.ndarray] = []
            g = grad_out
            for layer in range(len(online) - 1, -1, -1):
                w, _, _ = online[layer]
                grads[:0] = [g.T @ acts[layer], g.sum(axis=0)]
                if layer:
                    g = g @ w
                    act = online[layer - 1][2]
                    h = acts[layer]
                    if act == "relu":
                        g *= h > 0
                    elif act == "tanh":
                        g *= 1.0 - h * h
            total = np.sqrt(sum(float(np.dot(gr.ravel(), gr.ravel())) for gr in grads))
            coef = min(max_grad_norm / (total + 1e-6), 1.0)  # clip_grad_norm_'s clamp
            for param, grad, (m, v, step) in zip(weights, grads, state):
                if coef < 1.0:
                    grad *= coef
                step += 1
                t = float(step)
                m *= beta1
                m += (1.0 - beta1) * grad
                v *= beta2
                v += (1.0 - beta2) * grad * grad
                denom = np.sqrt(v) / np.sqrt(1.0 - beta2**t) + eps
                param -= (lr / (1.0 - beta1**t)) * m / denom
        return float(np.mean(losses))
