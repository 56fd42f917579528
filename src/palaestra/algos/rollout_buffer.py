"""PPO's rollout buffer: ``n_steps`` steps of ``n_envs`` envs, then GAE, then minibatches."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any, NamedTuple

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.ppo_math import gae
from palaestra.algos.spaces_util import allocate

__all__ = ["RolloutBatch", "RolloutBuffer"]

TensorObs = torch.Tensor | dict[str, torch.Tensor]
ArrayBatch = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


class RolloutBatch(NamedTuple):
    """One PPO minibatch on the training device."""

    observations: TensorObs  # [B, *obs_shape]
    actions: torch.Tensor  # [B, *action_shape]
    old_values: torch.Tensor  # [B]
    old_log_prob: torch.Tensor  # [B]
    advantages: torch.Tensor  # [B]
    returns: torch.Tensor  # [B]


def _flatten(store: Any, device: torch.device) -> Any:
    """``[T, N, ...]`` numpy -> ``[T * N, ...]`` tensor; step-major order is fine because
    minibatches are drawn through a random permutation (SB3 swaps to env-major first)."""
    if isinstance(store, dict):
        return {key: _flatten(sub, device) for key, sub in store.items()}
    return torch.as_tensor(store.reshape(-1, *store.shape[2:]), device=device)


def _index(batch: Any, idx: torch.Tensor) -> Any:
    if isinstance(batch, dict):
        return {key: sub[idx] for key, sub in batch.items()}
    return batch[idx]


class RolloutBuffer:
    """Preallocated arrays for one rollout; ``add`` copies a step, ``compute_returns`` runs GAE."""

    def __init__(
        self,
        n_steps: int,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        n_envs: int = 1,
        gamma: float = 0.99,
        gae_lambda: float = 0.95,
        device: torch.device | str = "cpu",
    ) -> None:
        self.n_steps, self.n_envs = n_steps, n_envs
        self.gamma, self.gae_lambda = gamma, gae_lambda
        self.device = torch.device(device)
        lead = (n_steps, n_envs)
        self.observations = allocate(observation_space, lead)
        self.obs_shape = (
            self.observations.shape[2:] if isinstance(self.observations, np.ndarray) else ()
        )
        self.actions = allocate(action_space, lead)
        if isinstance(action_space, spaces.Box):
            self.actions = self.actions.astype(np.float32)  # unclipped Gaussian samples
        self.rewards = np.zeros(lead, dtype=np.float32)
        self.episode_starts = np.zeros(lead, dtype=np.float32)
        self.values = np.zeros(lead, dtype=np.float32)
        self.log_probs = np.zeros(lead, dtype=np.float32)
        self.advantages = np.zeros(lead, dtype=np.float32)
        self.returns = np.zeros(lead, dtype=np.float32)
        self.pos = 0

    @property
    def full(self) -> bool:
        return self.pos == self.n_steps

    def reset(self) -> None:
        self.pos = 0

    def add(
        self,
        obs: Any,
        actions: np.ndarray,
        rewards: np.ndarray,
        episode_starts: np.ndarray,
        values: np.ndarray | None,
        log_probs: np.ndarray,
    ) -> None:
        """Store one step of every env (arrays ``[n_envs, ...]``); ``values=None`` leaves
        them to be written into ``self.values`` later (for the whole rollout at once)."""
        t = self.pos
        if isinstance(self.observations, dict):
            for key, sub in self.observations.items():
                sub[t] = obs[key]
        else:
            self.observations[t] = obs
        self.actions[t] = actions
        self.rewards[t] = rewards
        self.episode_starts[t] = episode_starts
        if values is not None:
            self.values[t] = values
        self.log_probs[t] = log_probs
        self.pos += 1

    # -- a rollout cut short, for exact resume ------------------------------------------
    def _columns(self) -> dict[str, np.ndarray]:
        """The per-step arrays ``add`` writes, by name (dict observations as ``obs/<key>``)."""
        obs = self.observations
        cols = {f"obs/{k}": v for k, v in obs.items()} if isinstance(obs, dict) else {"obs": obs}
        cols.update(
            actions=self.actions,
            rewards=self.rewards,
            episode_starts=self.episode_starts,
            values=self.values,
            log_probs=self.log_probs,
        )
        return cols

    def partial_state(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """The steps stored so far (none once a rollout has been trained on)."""
        if self.pos == 0:
            return {"pos": 0}, {}
        return {"pos": self.pos}, {k: v[: self.pos].copy() for k, v in self._columns().items()}

    def load_partial_state(self, meta: Any, arrays: dict[str, np.ndarray]) -> None:
        """Restore ``partial_state`` output; ``ValueError`` if it does not fit this buffer."""
        pos = meta.get("pos", 0) if isinstance(meta, dict) else None
        if isinstance(pos, bool) or not isinstance(pos, int) or not 0 <= pos <= self.n_steps:
            raise ValueError(f"rollout position {pos!r} is not in [0, {self.n_steps}]")
        cols = self._columns() if pos else {}
        if set(arrays) != set(cols):
            raise ValueError(f"rollout arrays {sorted(arrays)} do not match {sorted(cols)}")
        for key, col in cols.items():
            if arrays[key].shape != col[:pos].shape or arrays[key].dtype != col.dtype:
                raise ValueError(
                    f"rollout {key!r} is {arrays[key].dtype}{list(arrays[key].shape)}, "
                    f"expected {col.dtype}{list(col[:pos].shape)}"
                )
        for key, col in cols.items():
            col[:pos] = arrays[key]
        self.pos = pos

    def compute_returns_and_advantage(self, last_values: np.ndarray, dones: np.ndarray) -> None:
        """GAE over the full rollout; ``last_values``/``dones`` are for the next observation."""
        self.advantages, self.returns = gae(
            self.rewards,
            self.values,
            self.episode_starts,
            np.asarray(last_values, dtype=np.float32),
            np.asarray(dones, dtype=np.float32),
            self.gamma,
            self.gae_lambda,
        )

    def minibatches(self, batch_size: int, rng: np.random.Generator) -> Iterator[RolloutBatch]:
        """Shuffled minibatches over all ``n_steps * n_envs`` samples (the last may be short)."""
        dev = self.device
        obs = _flatten(self.observations, dev)
        cols = [
            _flatten(a, dev)
            for a in (self.actions, self.values, self.log_probs, self.advantages, self.returns)
        ]
        total = self.n_steps * self.n_envs
        perm = torch.as_tensor(rng.permutation(total), device=dev)
        for start in range(0, total, batch_size):
            idx = perm[start : start + batch_size]
            yield RolloutBatch(_index(obs, idx), *(c[idx] for c in cols))

    def minibatch_arrays(self, batch_size: int, rng: np.random.Generator) -> Iterator[ArrayBatch]:
        """``minibatches`` as numpy arrays (array observations; same draws from ``rng``):
        ``(obs, actions, old_values, old_log_prob, advantages, returns)``."""
        assert isinstance(self.observations, np.ndarray)
        obs, act, val, logp, adv, ret = (
            a.reshape(-1, *a.shape[2:])
            for a in (
                self.observations,
                self.actions,
                self.values,
                self.log_probs,
                self.advantages,
                self.returns,
            )
        )
        total = self.n_steps * self.n_envs
        perm = rng.permutation(total)
        for start in range(0, total, batch_size):
            i = perm[start : start + batch_size]
            yield obs[i], act[i], val[i], logp[i], adv[i], ret[i]
