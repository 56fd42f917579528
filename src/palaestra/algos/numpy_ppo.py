"""PPO minibatch updates in numpy for small MLP actor-critics on the CPU (Discrete and Box
actions), with the same loss as ``ppo_math.ppo_loss`` and its gradient written out.

Gradient conventions copied from torch so both paths agree to float32 rounding (tested):
``torch.minimum`` splits the gradient evenly on ties, ``clamp`` passes it on its closed
interval, advantages are normalised with the unbiased std. Adam and clipping come from
``numpy_nn`` and work on views of the torch parameters and optimizer state.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

from palaestra.algos.numpy_acting import log_softmax
from palaestra.algos.numpy_nn import (
    FlatAdam,
    LayerViews,
    adam_ok,
    backward,
    forward,
    linear_chain,
)

__all__ = ["NumpyPPOTrainer"]

_LOG_SQRT_2PI = 0.5 * math.log(2 * math.pi)


class NumpyPPOTrainer:
    """Clipped-surrogate updates on numpy views of an ``ActorCritic`` and its Adam."""

    def __init__(self, policy: Any, optimizer: torch.optim.Optimizer, pi_chain: Any, vf_chain: Any):
        self.policy, self.optimizer = policy, optimizer
        self.pi_chain, self.vf_chain = pi_chain, vf_chain
        self.head = policy.action_head
        params = [p for lin, _ in pi_chain + vf_chain for p in (lin.weight, lin.bias)]
        if self.head.kind == "gaussian":
            params.append(self.head.log_std)
        self.adam = FlatAdam(optimizer, params)
        self._views = LayerViews(pi_chain, vf_chain)
        offset = self.head.offset  # a buffer: looked up once, not per minibatch
        self._offset = None if offset is None else int(offset)

    @classmethod
    def build(cls, policy: Any, optimizer: Any) -> NumpyPPOTrainer | None:
        """A trainer for numpy-actable policies with a Categorical or Gaussian head and Adam."""
        if policy.numpy_acting() is None or policy.action_head.kind not in (
            "categorical",
            "gaussian",
        ):
            return None
        pi_chain = linear_chain([policy.pi_net, policy.action_head.net])
        vf_chain = linear_chain([policy.vf_net, policy.value_head])
        if not pi_chain or not vf_chain or not adam_ok(optimizer):
            return None
        trainer = cls(policy, optimizer, pi_chain, vf_chain)
        if len(trainer.adam.params) != len(list(policy.parameters())):
            return None
        return trainer

    def step(
        self,
        obs: np.ndarray,
        actions: np.ndarray,
        old_values: np.ndarray,
        old_log_prob: np.ndarray,
        advantages: np.ndarray,
        returns: np.ndarray,
        clip_range: float,
        clip_range_vf: float | None,
        ent_coef: float,
        vf_coef: float,
        normalize_advantage: bool,
        max_grad_norm: float,
        kl_limit: float | None,
    ) -> tuple[dict[str, float], bool]:
        """One minibatch: the logged values and whether the KL limit stopped it (no update)."""
        n = obs.shape[0]
        x = obs.reshape(n, -1).astype(np.float32, copy=False)
        pi_layers, vf_layers = self._views()
        pi_acts, vf_acts = forward(pi_layers, x), forward(vf_layers, x)
        out, values = pi_acts[-1], vf_acts[-1][:, 0]
        rows = np.arange(n)
        if self.head.kind == "categorical":
            idx = actions.reshape(n).astype(np.int64, copy=False)
            if self._offset is not None:
                idx = idx - self._offset
            logp_all = log_softmax(out)
            probs = np.exp(logp_all)
            log_prob = logp_all[rows, idx]
            # per-row entropies only for the entropy gradient; the mean is one dot product
            entropy = -np.add.reduce(probs * logp_all, axis=1) if ent_coef else None
            mean_entropy = -float(np.dot(probs.ravel(), logp_all.ravel())) / n
        else:
            log_std = self.head.log_std.detach().numpy()
            z = (actions.reshape(out.shape) - out) * np.exp(-log_std)
            log_prob = (-0.5 * z * z - log_std - _LOG_SQRT_2PI).sum(axis=1)
            mean_entropy = float((0.5 + _LOG_SQRT_2PI + log_std).sum())
        adv = advantages
        if normalize_advantage and n > 1:
            # (adv - mean) / (std(ddof=1) + 1e-8), without np.mean/np.std's Python layers
            centred = adv - np.add.reduce(adv) / n
            std = math.sqrt(float(np.dot(centred, centred)) / (n - 1))
            adv = centred / np.float32(std + 1e-8)
        log_ratio = log_prob - old_log_prob
        ratio = np.exp(log_ratio)
        # np.clip's Python layer costs more than these two ufuncs at these sizes
        clipped = np.minimum(np.maximum(ratio, 1 - clip_range), 1 + clip_range)
        s1, s2 = adv * ratio, adv * clipped
        v_pred = values
        if clip_range_vf is not None:
            v_pred = old_values + np.clip(values - old_values, -clip_range_vf, clip_range_vf)
        v_err = v_pred - returns
        metrics = {
            "policy_loss": -float(np.add.reduce(np.minimum(s1, s2))) / n,
            "value_loss": float(np.dot(v_err, v_err)) / n,
            "entropy_loss": -mean_entropy,
            "clip_fraction": float(np.count_nonzero(np.abs(ratio - 1) > clip_range)) / n,
            "approx_kl": float(np.add.reduce((ratio - 1) - log_ratio)) / n,
        }
        metrics["loss"] = (
            metrics["policy_loss"]
            + ent_coef * metrics["entropy_loss"]
            + vf_coef * metrics["value_loss"]
        )
        if kl_limit is not None and metrics["approx_kl"] > kl_limit:
            return metrics, True
        # d(min(s1, s2))/d(ratio) is adv where s1 < s2 or the ratio lies inside the clip range.
        # Inside, clipped == ratio, so s1 == s2 and torch.minimum's even split of the tie gives
        # 1/2 + 1/2 (both sides are the ratio); outside, the clipped side is a constant (a tie
        # there needs adv == 0, a zero gradient either way).
        d_min = adv * ((clipped == ratio) | (s1 < s2))
        neg_d_lp = np.multiply(d_min, ratio, out=d_min)
        neg_d_lp /= n  # -d(policy_loss)/d(log_prob)
        if self.head.kind == "categorical":
            # d_lp * (one_hot - probs) - dH/dlogits * ent_coef / n
            d_out = neg_d_lp[:, None] * probs
            if entropy is not None:
                d_out += (ent_coef / n) * probs * (logp_all + entropy[:, None])
            d_out[rows, idx] -= neg_d_lp
            extra: list[np.ndarray] = []
        else:
            d_lp = -neg_d_lp
            d_out = d_lp[:, None] * z * np.exp(-log_std)
            extra = [(d_lp[:, None] * (z * z - 1.0)).sum(axis=0) - ent_coef]
        d_v = (2.0 * vf_coef / n) * v_err
        if clip_range_vf is not None:
            d_v = d_v * (np.abs(values - old_values) <= clip_range_vf)
        grads = self.adam.grad_views()
        n_pi = 2 * len(pi_layers)
        backward(pi_layers, pi_acts, d_out.astype(np.float32, copy=False), grads[:n_pi])
        backward(vf_layers, vf_acts, d_v[:, None].astype(np.float32, copy=False), grads[n_pi:])
        if extra:
            grads[-1][...] = extra[0]
        self.adam.clip_grad_norm(max_grad_norm)
        self.adam.step()
        return metrics, False
