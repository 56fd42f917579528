"""Action heads for PPO: one small module per action space, no ``torch.distributions`` objects.

Acting is on the hot path, so sampling and log-probabilities are a few tensor ops each:
Categorical (Discrete), one Categorical per dimension (MultiDiscrete), Bernoulli (MultiBinary)
and a diagonal Gaussian with a state-independent log-std (Box), as in SB3.
Actions leave ``act`` in the env's own terms (``start`` offsets added).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.numpy_acting import sample_categorical

__all__ = ["ActionHead"]

_LOG_SQRT_2PI = 0.5 * math.log(2 * math.pi)


class ActionHead(nn.Module):
    """``latent -> action distribution`` for one action space."""

    def __init__(self, action_space: spaces.Space[Any], latent_dim: int, log_std_init: float = 0.0):
        super().__init__()
        self.offset: torch.Tensor | None
        if isinstance(action_space, spaces.Discrete):
            self.kind, self.sizes, out = "categorical", [int(action_space.n)], int(action_space.n)
            first = int(action_space.start)
            self.register_buffer("offset", torch.tensor(first) if first else None, persistent=False)
        elif isinstance(action_space, spaces.MultiDiscrete):
            if action_space.nvec.ndim != 1:
                raise ValueError(
                    f"only 1-D MultiDiscrete action spaces are supported, got {action_space}"
                )
            self.kind, self.sizes = "multi_categorical", [int(n) for n in action_space.nvec]
            out = sum(self.sizes)
            start = torch.as_tensor(np.asarray(action_space.start, dtype=np.int64))
            self.register_buffer("offset", start if bool(start.any()) else None, persistent=False)
        elif isinstance(action_space, spaces.MultiBinary):
            self.kind, self.sizes = "bernoulli", [int(np.prod(action_space.shape))]
            out = self.sizes[0]
            self.offset = None
        elif isinstance(action_space, spaces.Box):
            self.kind, self.sizes = "gaussian", [int(np.prod(action_space.shape))]
            out = self.sizes[0]
            self.offset = None
            self.log_std = nn.Parameter(torch.full((out,), float(log_std_init)))
        else:
            raise TypeError(f"PPO does not support {type(action_space).__name__} action spaces")
        self.action_shape: tuple[int, ...] = tuple(action_space.shape or ())
        self.net = nn.Linear(latent_dim, out)
        # Checked every env step by ``act_numpy``: a plain attribute, not the buffer lookup.
        self._plain_categorical = self.kind == "categorical" and self.offset is None

    def act(self, latent: torch.Tensor, deterministic: bool) -> tuple[torch.Tensor, torch.Tensor]:
        """Sample (or take the mode of) actions ``[B, *shape]`` and their log-probs ``[B]``."""
        params = self.net(latent)
        if self.kind == "gaussian":
            actions = (
                params if deterministic else params + torch.randn_like(params) * self.log_std.exp()
            )
            return actions.reshape(-1, *self.action_shape), self._gaussian_log_prob(params, actions)
        if self.kind == "bernoulli":
            probs = torch.sigmoid(params)
            actions = (probs > 0.5).float() if deterministic else torch.bernoulli(probs)
            log_prob = -nn.functional.binary_cross_entropy_with_logits(
                params, actions, reduction="none"
            )
            return actions.reshape(-1, *self.action_shape), log_prob.sum(dim=1)
        picks, log_probs = [], []
        for logits in torch.split(params, self.sizes, dim=1):
            logp = torch.log_softmax(logits, dim=1)
            idx = (
                logits.argmax(dim=1)
                if deterministic
                else torch.multinomial(logp.exp(), 1).squeeze(1)
            )
            picks.append(idx)
            log_probs.append(logp.gather(1, idx.unsqueeze(1)).squeeze(1))
        actions = picks[0] if self.kind == "categorical" else torch.stack(picks, dim=1)
        if self.offset is not None:
            actions = actions + self.offset
        return actions, torch.stack(log_probs, dim=0).sum(dim=0)

    def evaluate(
        self, latent: torch.Tensor, actions: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Log-probs ``[B]`` of given env actions and the entropies ``[B]``."""
        params = self.net(latent)
        if self.kind == "gaussian":
            log_prob = self._gaussian_log_prob(params, actions.reshape(params.shape))
            entropy = (0.5 + _LOG_SQRT_2PI + self.log_std).sum().expand(params.shape[0])
            return log_prob, entropy
        if self.kind == "bernoulli":
            actions = actions.reshape(params.shape).float()
            log_prob = -nn.functional.binary_cross_entropy_with_logits(
                params, actions, reduction="none"
            )
            probs = torch.sigmoid(params)
            entropy = nn.functional.binary_cross_entropy_with_logits(
                params, probs, reduction="none"
            )
            return log_prob.sum(dim=1), entropy.sum(dim=1)
        idx = actions.long().reshape(params.shape[0], -1)
        if self.offset is not None:
            idx = idx - self.offset
        log_prob = torch.zeros(params.shape[0], device=params.device)
        entropy = torch.zeros(params.shape[0], device=params.device)
        for i, logits in enumerate(torch.split(params, self.sizes, dim=1)):
            logp = torch.log_softmax(logits, dim=1)
            log_prob = log_prob + logp.gather(1, idx[:, i : i + 1]).squeeze(1)
            entropy = entropy - (logp.exp() * logp).sum(dim=1)
        return log_prob, entropy

    def act_numpy(
        self, params: np.ndarray, rng: np.random.Generator, deterministic: bool
    ) -> tuple[np.ndarray, np.ndarray]:
        """``act`` on head outputs computed in numpy (see ``numpy_acting``): same
        distributions, drawn from ``rng``; returns ``(actions, log_probs [B] float32)``."""
        if self._plain_categorical:  # the common case: one Discrete(n) from 0
            return sample_categorical(params, rng, deterministic)
        n = params.shape[0]
        if self.kind == "gaussian":
            log_std = self.log_std.detach().numpy()
            noise = (
                np.zeros_like(params)
                if deterministic
                else rng.standard_normal(params.shape, np.float32)
            )
            actions = params + noise * np.exp(log_std)
            log_prob = (-0.5 * noise**2 - log_std - _LOG_SQRT_2PI).sum(axis=1)
            return actions.reshape(n, *self.action_shape), log_prob.astype(np.float32)
        if self.kind == "bernoulli":
            if deterministic:
                bits = params > 0.0
            else:
                bits = rng.random(params.shape) < 1.0 / (1.0 + np.exp(-params))
            log_prob = -np.logaddexp(0.0, np.where(bits, -params, params)).sum(axis=1)
            return bits.astype(np.float32).reshape(n, *self.action_shape), log_prob.astype(
                np.float32
            )
        picks, log_prob = [], np.zeros(n, dtype=np.float32)
        for logits in np.split(params, np.cumsum(self.sizes)[:-1], axis=1):
            idx, logp = sample_categorical(logits, rng, deterministic)
            picks.append(idx)
            log_prob += logp
        actions = picks[0] if self.kind == "categorical" else np.stack(picks, axis=1)
        if self.offset is not None:
            actions = actions + self.offset.numpy()
        return actions, log_prob

    def _gaussian_log_prob(self, mean: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
        z = (actions - mean) * torch.exp(-self.log_std)
        return (-0.5 * z.pow(2) - self.log_std - _LOG_SQRT_2PI).sum(dim=1)
