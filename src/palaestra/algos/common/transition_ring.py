"""The off-policy algorithms' replay memory: preallocated numpy rings of transitions, one
column per env, sampled uniformly (the SB3-compatible class users build is
``palaestra.algos.buffers.ReplayBuffer``; this one feeds the learners and the model files).

Layout follows SB3 (``[buffer_size // n_envs, n_envs, ...]``, next observations stored apart).
Time-limit bootstrapping: a transition that ended by truncation (``TimeLimit.truncated``) is
stored as *not* terminated, so its target still bootstraps from the next observation (SB3's
``handle_timeout_termination``; Pardo et al. 2018, "Time Limits in Reinforcement Learning").
With ``n_steps > 1`` the ring also keeps where episodes ended (terminated or truncated) and
samples n-step returns (``palaestra.algos.common.nstep``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.common.nstep import check_n_steps, n_step_window
from palaestra.algos.common.spaces_util import allocate

__all__ = ["BATCH_KEYS", "TransitionRing"]

# The fields of ``sample_arrays``, by the names the objectives read ("discounts" only with
# n_steps > 1: without it the objectives discount by their gamma).
BATCH_KEYS = ("observations", "actions", "next_observations", "rewards", "terminated", "discounts")

Obs = np.ndarray | dict[str, np.ndarray]


def saved_rows(
    meta: dict[str, Any], arrays: dict[str, np.ndarray], n_envs: int, buffer_size: int
) -> int:
    """The rows a saved replay buffer holds; ``ValueError`` when it was saved with other
    ``n_envs`` or holds more rows than ``buffer_size``."""
    if int(meta["n_envs"]) != n_envs:
        raise ValueError(
            f"replay buffer was saved with n_envs={meta['n_envs']}, this model has n_envs={n_envs}"
        )
    n = int(arrays["rewards"].shape[0])
    if n > buffer_size:
        raise ValueError(f"saved replay buffer holds {n} rows, capacity is {buffer_size}")
    return n


def _write(store: Any, row: int, value: Any) -> None:
    if isinstance(store, dict):
        for key, sub in store.items():
            sub[row] = value[key]
    else:
        store[row] = value


def _take_arrays(store: Any, rows: np.ndarray, cols: np.ndarray) -> Any:
    if isinstance(store, dict):
        return {key: sub[rows, cols] for key, sub in store.items()}
    return store[rows, cols]


def _take_column(store: Any, rows: np.ndarray) -> Any:
    """``_take_arrays(store, rows, zeros)`` of a one-env store."""
    if isinstance(store, dict):
        return {key: sub[:, 0].take(rows, axis=0) for key, sub in store.items()}
    return store[:, 0].take(rows, axis=0)


def check_saved_arrays(arrays: dict[str, np.ndarray], targets: dict[str, np.ndarray]) -> None:
    """``ValueError`` unless a saved buffer has exactly ``targets``' arrays, each of its shape."""
    if set(targets) != set(arrays):
        raise ValueError(f"replay buffer arrays {sorted(arrays)} do not match {sorted(targets)}")
    for key, target in targets.items():
        if arrays[key].shape != target.shape:
            raise ValueError(
                f"replay buffer {key!r} has shape {arrays[key].shape}, expected {target.shape}"
            )


def flat_rows(prefix: str, store: Any, n: int) -> dict[str, np.ndarray]:
    """The first ``n`` rows of an array, or of each array of a dict store as ``prefix/key``."""
    if isinstance(store, dict):
        return {f"{prefix}/{key}": sub[:n] for key, sub in store.items()}
    return {prefix: store[:n]}


class TransitionRing:
    """Fixed-capacity FIFO of transitions from ``n_envs`` envs stepped together."""

    def __init__(
        self,
        buffer_size: int,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        n_envs: int = 1,
        device: torch.device | str = "cpu",
        handle_timeout_termination: bool = True,
        n_steps: int = 1,
        gamma: float = 0.99,
    ) -> None:
        self.buffer_size = max(int(buffer_size) // n_envs, 1)  # rows; SB3 divides the same way
        self.n_steps, self.gamma = check_n_steps(n_steps), float(gamma)
        self.n_envs = n_envs
        self.device = torch.device(device)
        self.handle_timeout_termination = handle_timeout_termination
        self.observation_space, self.action_space = observation_space, action_space
        lead = (self.buffer_size, n_envs)
        self.observations = allocate(observation_space, lead)
        self.next_observations = allocate(observation_space, lead)
        self.actions = allocate(action_space, lead)
        self.rewards = np.zeros(lead, dtype=np.float32)
        self.terminated = np.zeros(lead, dtype=np.float32)
        # Where an episode ended, truncations included: n-step windows stop there.
        self.ended = np.zeros(lead if self.n_steps > 1 else (0, n_envs), dtype=np.float32)
        self.pos, self.full = 0, False

    def size(self) -> int:
        """Number of stored rows (each row holds one transition per env)."""
        return self.buffer_size if self.full else self.pos

    def nbytes(self) -> int:
        """Bytes of every array this buffer holds."""
        stores = [self.observations, self.next_observations, self.actions]
        arrays = [a for st in stores for a in (st.values() if isinstance(st, dict) else [st])]
        return int(sum(a.nbytes for a in [*arrays, self.rewards, self.terminated, self.ended]))

    def add(
        self,
        obs: Obs,
        next_obs: Obs,
        actions: np.ndarray,
        rewards: np.ndarray,
        dones: np.ndarray,
        timeouts: np.ndarray,
    ) -> None:
        """Store one step of every env (arrays ``[n_envs, ...]``); copies into the ring."""
        row = self.pos
        _write(self.observations, row, obs)
        _write(self.next_observations, row, next_obs)
        self.actions[row] = actions
        self.rewards[row] = rewards
        if self.handle_timeout_termination and (
            np.count_nonzero(timeouts) or getattr(dones, "dtype", None) != np.bool_
        ):
            self.terminated[row] = np.logical_and(dones, np.logical_not(timeouts))
        else:  # bool dones and no time-out (nearly every step): what the line above gives
            self.terminated[row] = dones
        if self.n_steps > 1:
            self.ended[row] = dones
        self.pos += 1
        if self.pos == self.buffer_size:
            self.full, self.pos = True, 0

    def sample_arrays(self, batch_size: int, rng: np.random.Generator) -> tuple[Any, ...]:
        """Uniform rows and envs, with replacement, as SB3 samples:
        ``(obs, actions, next_obs, rewards, terminated)``, and ``discounts`` with
        ``n_steps > 1`` (the fields of ``BATCH_KEYS``; see ``get``)."""
        rows = rng.integers(0, self.size(), size=batch_size)
        if self.n_envs == 1 and self.n_steps == 1:
            # integers(0, 1) draws nothing from the stream: the one env's column is taken
            # directly (a quarter of the cost of the [rows, cols] gathers, the same values).
            return (
                _take_column(self.observations, rows),
                self.actions[:, 0].take(rows, axis=0),
                _take_column(self.next_observations, rows),
                self.rewards[:, 0].take(rows, axis=0),
                self.terminated[:, 0].take(rows, axis=0),
            )
        cols = rng.integers(0, self.n_envs, size=batch_size)
        return self.get(rows, cols)

    def get(self, rows: np.ndarray, cols: np.ndarray) -> tuple[Any, ...]:
        """The transitions at ``(rows, cols)``; with ``n_steps > 1`` their n-step windows:
        the discounted reward sums, the next observation and ``terminated`` of each window's
        last transition, and the discount of its target (SB3's ``NStepReplayBuffer``)."""
        if self.n_steps > 1:
            newest = (self.pos - 1) % self.buffer_size
            returns, discounts, last = n_step_window(
                self.rewards, (self.ended,), newest, rows, cols, self.n_steps, self.gamma
            )
            return (
                _take_arrays(self.observations, rows, cols),
                self.actions[rows, cols],
                _take_arrays(self.next_observations, last, cols),
                returns,
                self.terminated[last, cols],
                discounts,
            )
        return (
            _take_arrays(self.observations, rows, cols),
            self.actions[rows, cols],
            _take_arrays(self.next_observations, rows, cols),
            self.rewards[rows, cols],
            self.terminated[rows, cols],
        )

    # -- persistence (plain arrays + JSON metadata; see model_io.save_arrays) -----------------
    def state(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """JSON metadata and the filled part of every array."""
        n = self.size()
        arrays = {
            **flat_rows("observations", self.observations, n),
            **flat_rows("next_observations", self.next_observations, n),
            "actions": self.actions[:n],
            "rewards": self.rewards[:n],
            "terminated": self.terminated[:n],
            **({"ended": self.ended[:n]} if self.n_steps > 1 else {}),
        }
        meta = {
            "buffer_size": self.buffer_size,
            "n_envs": self.n_envs,
            "pos": self.pos,
            "full": self.full,
            "handle_timeout_termination": self.handle_timeout_termination,
        }
        return meta, arrays

    def load_state(self, meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
        """Restore from ``state()`` output; ``ValueError`` if it does not fit this buffer."""
        if meta.get("kind") == "her":
            raise ValueError(
                "the file holds a HerReplayBuffer; this model has no replay_buffer_class "
                "(pass replay_buffer_class=HerReplayBuffer)"
            )
        if meta.get("kind") == "frames":
            raise ValueError(
                "the file holds a frame buffer (optimize_memory_usage=True); "
                "this model uses optimize_memory_usage=False"
            )
        n = saved_rows(meta, arrays, self.n_envs, self.buffer_size)
        targets = {
            **flat_rows("observations", self.observations, n),
            **flat_rows("next_observations", self.next_observations, n),
            "actions": self.actions[:n],
            "rewards": self.rewards[:n],
            "terminated": self.terminated[:n],
        }
        if self.n_steps == 1:  # a buffer saved with n_steps > 1 holds the same transitions
            arrays = {k: v for k, v in arrays.items() if k != "ended"}
        elif "ended" in arrays:
            targets["ended"] = self.ended[:n]
        elif n:
            raise ValueError(
                "the saved replay buffer does not record where episodes ended (saved with "
                f"n_steps=1), which n-step returns need (this model has n_steps={self.n_steps})"
            )
        check_saved_arrays(arrays, targets)
        for key, target in targets.items():
            target[...] = arrays[key]
        pos, full = meta["pos"], meta["full"]
        if not isinstance(full, bool) or isinstance(pos, bool) or not isinstance(pos, int):
            raise ValueError(f"replay buffer position {pos!r}/full {full!r} are malformed")
        if not np.isfinite(arrays["rewards"]).all():
            raise ValueError("replay buffer rewards hold NaN or infinite values")
        if isinstance(self.action_space, spaces.Discrete):
            start, stop = self.action_space.start, self.action_space.start + self.action_space.n
            if n and not ((arrays["actions"] >= start) & (arrays["actions"] < stop)).all():
                raise ValueError(f"replay buffer actions outside {self.action_space}")
        full = full and n == self.buffer_size
        self.full, self.pos = full, pos % self.buffer_size if full else n
