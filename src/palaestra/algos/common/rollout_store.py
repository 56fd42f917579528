"""The on-policy algorithms' rollout storage: ``n_steps`` steps of ``n_envs`` envs as numpy
arrays, then GAE, then minibatches (PPO) or the whole rollout as one batch (A2C). The
SB3-compatible class users build is ``palaestra.algos.buffers.RolloutBuffer``; this one, the
``model.rollout_buffer`` callbacks see, also answers SB3's read-side calls (``size()``,
``buffer_size``, ``full``, ``get(batch_size)`` with SB3's sample tuples)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.common.buffers import (
    BaseBuffer,
    DictRolloutBufferSamples,
    RolloutBufferSamples,
)
from palaestra.algos.common.spaces_util import allocate
from palaestra.algos.learners.losses import gae

__all__ = ["RolloutStore"]


def _flat(store: Any) -> Any:
    """``[T, N, ...]`` -> ``[T * N, ...]`` (views); step-major order is fine because
    minibatches are drawn through a random permutation (SB3 swaps to env-major first)."""
    if isinstance(store, dict):
        return {key: _flat(sub) for key, sub in store.items()}
    return store.reshape(-1, *store.shape[2:])


class RolloutStore:
    """Preallocated arrays for one rollout; ``add`` copies a step, ``compute_returns`` runs GAE."""

    def __init__(
        self,
        n_steps: int,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        n_envs: int = 1,
        gamma: float = 0.99,
        gae_lambda: float = 0.95,
    ) -> None:
        self.n_steps, self.n_envs = n_steps, n_envs
        self.gamma, self.gae_lambda = gamma, gae_lambda
        self.observation_space, self.action_space = observation_space, action_space
        self.device = torch.device("cpu")
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

    # -- SB3's RolloutBuffer face (read side) ------------------------------------------------
    @property
    def buffer_size(self) -> int:
        """Steps per env in one rollout (SB3's name for ``n_steps``)."""
        return self.n_steps

    def size(self) -> int:
        """Steps stored so far (each holds one step of every env)."""
        return self.pos

    swap_and_flatten = staticmethod(BaseBuffer.swap_and_flatten)

    def to_torch(self, array: np.ndarray, copy: bool = True) -> torch.Tensor:
        """A tensor on the CPU (a copy unless ``copy=False``)."""
        return torch.tensor(array) if copy else torch.as_tensor(array)

    def get(self, batch_size: int | None = None) -> Iterator[Any]:
        """SB3's ``RolloutBuffer.get``: ``RolloutBufferSamples`` (or the Dict ones) of
        ``batch_size`` (None: all) over a ``np.random.permutation`` of the samples, env-major
        as SB3 orders them; the arrays themselves are left as they are (the algorithm's)."""
        if not self.full:
            raise ValueError("the rollout buffer is not full yet: add buffer_size steps first")
        total = self.n_steps * self.n_envs
        size = total if batch_size is None else int(batch_size)
        if size < 1:
            raise ValueError(f"batch_size must be a positive integer, got {batch_size!r}")
        indices = np.random.permutation(total)  # noqa: NPY002 - SB3's draws
        flat = self.swap_and_flatten
        obs = self.observations
        obs = {k: flat(v) for k, v in obs.items()} if isinstance(obs, dict) else flat(obs)
        actions = flat(self.actions.reshape(self.n_steps, self.n_envs, -1))
        cols = [flat(a) for a in (self.values, self.log_probs, self.advantages, self.returns)]
        for start in range(0, total, size):
            i = indices[start : start + size]
            rest = (
                self.to_torch(actions[i].astype(np.float32, copy=False)),
                *(self.to_torch(c[i].flatten()) for c in cols),
            )
            if isinstance(obs, dict):
                yield DictRolloutBufferSamples(
                    {k: self.to_torch(v[i]) for k, v in obs.items()}, *rest
                )
            else:
                yield RolloutBufferSamples(self.to_torch(obs[i]), *rest)

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

    def flat_observations(self) -> Any:
        """All stored observations as ``[n_steps * n_envs, ...]`` (views)."""
        return _flat(self.observations)

    def _batch_columns(self) -> dict[str, Any]:
        """All ``n_steps * n_envs`` samples as the learners' batch fields (views)."""
        cols = {
            "actions": self.actions,
            "old_values": self.values,
            "old_log_prob": self.log_probs,
            "advantages": self.advantages,
            "returns": self.returns,
        }
        return {k: _flat(v) for k, v in cols.items()}

    def whole_batch(self) -> dict[str, Any]:
        """The whole rollout as one batch (A2C's single update), step-major."""
        batch = self._batch_columns()
        batch["observations"] = _flat(self.observations)
        return batch

    def minibatch_arrays(
        self, batch_size: int, rng: np.random.Generator
    ) -> Iterator[dict[str, Any]]:
        """Shuffled minibatches over all ``n_steps * n_envs`` samples (the last may be short),
        as the learners' batch fields."""
        obs = _flat(self.observations)
        flat = self._batch_columns()
        total = self.n_steps * self.n_envs
        perm = rng.permutation(total)
        for start in range(0, total, batch_size):
            i = perm[start : start + batch_size]
            batch = {k: v[i] for k, v in flat.items()}
            batch["observations"] = (
                {k: v[i] for k, v in obs.items()} if isinstance(obs, dict) else obs[i]
            )
            yield batch
