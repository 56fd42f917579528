"""PPO's action head: the output layer for one action space (and the Gaussian's log-std), and
the distribution it parameterises, dispatched to the functions in ``learners.heads``.

Categorical (Discrete), one Categorical per dimension (MultiDiscrete), Bernoulli (MultiBinary)
and a diagonal Gaussian with a state-independent log-std (Box), as in SB3. Actions leave
``sample`` in the env's own terms (``start`` offsets added); ``index`` takes them back.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.learners import heads
from palaestra.error import UnsupportedSpace

__all__ = ["ActionHead"]


class ActionHead(nn.Module):
    """``latent -> distribution parameters`` for one action space."""

    def __init__(self, action_space: spaces.Space[Any], latent_dim: int, log_std_init: float = 0.0):
        super().__init__()
        self.offset: np.ndarray | None = None
        if isinstance(action_space, spaces.Discrete):
            self.kind, self.sizes, out = "categorical", [int(action_space.n)], int(action_space.n)
            self.offset = np.asarray(int(action_space.start)) if int(action_space.start) else None
        elif isinstance(action_space, spaces.MultiDiscrete):
            if action_space.nvec.ndim != 1:
                raise ValueError(
                    f"only 1-D MultiDiscrete action spaces are supported, got {action_space}"
                )
            self.kind, self.sizes = "multi_categorical", [int(n) for n in action_space.nvec]
            out = sum(self.sizes)
            start = np.asarray(action_space.start, dtype=np.int64)
            self.offset = start if start.any() else None
        elif isinstance(action_space, spaces.MultiBinary):
            self.kind, self.sizes = "bernoulli", [int(np.prod(action_space.shape))]
            out = self.sizes[0]
        elif isinstance(action_space, spaces.Box):
            self.kind, self.sizes = "gaussian", [int(np.prod(action_space.shape))]
            out = self.sizes[0]
            self.log_std = nn.Parameter(torch.full((out,), float(log_std_init)))
        else:
            raise UnsupportedSpace(
                f"PPO does not support {type(action_space).__name__} action spaces"
            )
        self.action_shape: tuple[int, ...] = tuple(action_space.shape or ())
        self.net = nn.Linear(latent_dim, out)

    def sample(
        self,
        params: np.ndarray,
        log_std: np.ndarray | None,
        rng: np.random.Generator,
        deterministic: bool,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Actions ``[B, *shape]`` (or their modes) from head outputs ``params``, drawn from
        ``rng``, and their log-probabilities ``[B]`` float32."""
        n = params.shape[0]
        if self.kind == "categorical":
            actions, log_prob = heads.categorical_sample(params, rng, deterministic)
        elif self.kind == "multi_categorical":
            actions, log_prob = heads.multi_categorical_sample(
                params, self.sizes, rng, deterministic
            )
        elif self.kind == "bernoulli":
            actions, log_prob = heads.bernoulli_sample(params, rng, deterministic)
        else:
            assert log_std is not None
            actions, log_prob = heads.gaussian_sample(params, log_std, rng, deterministic)
        if self.offset is not None:
            actions = actions + self.offset
        return actions.reshape(n, *self.action_shape), log_prob

    def index(self, actions: np.ndarray) -> np.ndarray:
        """Env actions (a batch) as the head's operand: 0-based int64 indices, or the float32
        bits or values ``[B, d]``."""
        n = actions.shape[0]
        if self.kind == "categorical":
            idx = actions.reshape(n).astype(np.int64, copy=False)
        elif self.kind == "multi_categorical":
            idx = actions.reshape(n, -1).astype(np.int64, copy=False)
        else:
            return actions.reshape(n, -1).astype(np.float32, copy=False)
        return idx if self.offset is None else idx - self.offset

    def evaluate(self, xp: Any, params: Any, log_std: Any, actions: Any) -> tuple[Any, Any, Any]:
        """``(log_prob [B], entropy, tape)`` of ``index``-ed actions (see ``learners.heads``)."""
        if self.kind == "categorical":
            return heads.categorical_evaluate(xp, params, actions)
        if self.kind == "multi_categorical":
            return heads.multi_categorical_evaluate(xp, params, actions, self.sizes)
        if self.kind == "bernoulli":
            return heads.bernoulli_evaluate(xp, params, actions)
        return heads.gaussian_evaluate(xp, params, log_std, actions)

    def evaluate_vjp(
        self, tape: Any, g_log_prob: np.ndarray, g_mean_entropy: float
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """``(d/d params, d/d log_std or None)``."""
        if self.kind == "categorical":
            return heads.categorical_evaluate_vjp(tape, g_log_prob, g_mean_entropy), None
        if self.kind == "multi_categorical":
            return heads.multi_categorical_evaluate_vjp(tape, g_log_prob, g_mean_entropy), None
        if self.kind == "bernoulli":
            return heads.bernoulli_evaluate_vjp(tape, g_log_prob, g_mean_entropy), None
        return heads.gaussian_evaluate_vjp(tape, g_log_prob, g_mean_entropy)
