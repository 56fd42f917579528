"""SB3's ``common.buffers`` API for code written against it (CleanRL's ``dqn.py``, custom
training loops): ``ReplayBuffer``, ``DictReplayBuffer``, ``NStepReplayBuffer``,
``RolloutBuffer``, ``DictRolloutBuffer`` with SB3's constructors, ``add``, ``sample``/``get``,
``size``, ``reset``, ``full``, ``pos`` and torch tensor samples with SB3's field names.

Sampling draws from numpy's global generator (``np.random.randint``/``permutation``) in SB3's
order, so a loop seeded with ``np.random.seed`` draws the same samples as with SB3's buffers:
that is what these classes are for. palaestra's own algorithms use their seeded buffers
(``TransitionRing``, ``RolloutStore``) instead. GAE is ``learners.losses.gae``, the
function PPO and A2C train with. Gymnasium spaces are accepted (converted with
``palaestra.compat.from_gymnasium_space``), so the same loop runs over either library's envs.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any, NamedTuple

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.common.nstep import check_n_steps, n_step_window
from palaestra.algos.common.preprocessing import get_action_dim, get_obs_shape
from palaestra.algos.common.utils import get_device
from palaestra.algos.learners.losses import gae

__all__ = [
    "BaseBuffer",
    "DictReplayBuffer",
    "DictReplayBufferSamples",
    "DictRolloutBuffer",
    "DictRolloutBufferSamples",
    "NStepReplayBuffer",
    "ReplayBuffer",
    "ReplayBufferSamples",
    "RolloutBuffer",
    "RolloutBufferSamples",
]


class ReplayBufferSamples(NamedTuple):
    observations: torch.Tensor  # [B, *obs_shape]
    actions: torch.Tensor  # [B, action_dim]
    next_observations: torch.Tensor
    dones: torch.Tensor  # [B, 1] float: terminated, not cut by a time limit
    rewards: torch.Tensor  # [B, 1]
    discounts: torch.Tensor | None = None  # SB3's n-step buffers only


class DictReplayBufferSamples(NamedTuple):
    observations: dict[str, torch.Tensor]
    actions: torch.Tensor
    next_observations: dict[str, torch.Tensor]
    dones: torch.Tensor
    rewards: torch.Tensor
    discounts: torch.Tensor | None = None


class RolloutBufferSamples(NamedTuple):
    observations: torch.Tensor
    actions: torch.Tensor  # float32, as SB3
    old_values: torch.Tensor  # [B]
    old_log_prob: torch.Tensor
    advantages: torch.Tensor
    returns: torch.Tensor


class DictRolloutBufferSamples(NamedTuple):
    observations: dict[str, torch.Tensor]
    actions: torch.Tensor
    old_values: torch.Tensor
    old_log_prob: torch.Tensor
    advantages: torch.Tensor
    returns: torch.Tensor


def _own_space(space: Any, what: str) -> spaces.Space[Any]:
    if isinstance(space, spaces.Space):
        return space
    if type(space).__module__.startswith("gymnasium"):
        from palaestra.compat import from_gymnasium_space  # lazy: optional-dep — gymnasium

        return from_gymnasium_space(space)
    raise TypeError(f"{what} must be a palaestra or Gymnasium space, got {space!r:.80}")


def _positive(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _zeros(space: Any, shape: Any, lead: tuple[int, int]) -> Any:
    """``[buffer_size, n_envs, *shape]`` storage (a dict of them for Dict spaces)."""
    if isinstance(shape, dict):
        return {k: np.zeros((*lead, *s), dtype=space[k].dtype) for k, s in shape.items()}
    return np.zeros((*lead, *shape), dtype=space.dtype)


def _put(store: Any, index: Any, value: Any, space: Any, n_envs: int) -> None:
    """Copy one step of ``n_envs`` observations in (Discrete ones reshaped to ``[n, 1]``)."""
    if isinstance(store, dict):
        for key, sub in store.items():
            _put(sub, index, value[key], space[key], n_envs)
        return
    value = np.array(value)
    if isinstance(space, spaces.Discrete):
        value = value.reshape(n_envs, 1)
    store[index] = value


def _take(store: Any, *index: Any) -> Any:
    return {k: v[index] for k, v in store.items()} if isinstance(store, dict) else store[index]


class BaseBuffer:
    """What both buffers share: SB3's shapes, counters, device and tensor conversion."""

    def __init__(
        self,
        buffer_size: int,
        observation_space: Any,
        action_space: Any,
        device: torch.device | str = "auto",
        n_envs: int = 1,
    ) -> None:
        self.buffer_size = _positive("buffer_size", buffer_size)
        self.n_envs = _positive("n_envs", n_envs)
        self.observation_space = _own_space(observation_space, "observation_space")
        self.action_space = _own_space(action_space, "action_space")
        self.obs_shape = get_obs_shape(self.observation_space)
        self.action_dim = get_action_dim(self.action_space)
        self.pos, self.full = 0, False
        self.device = get_device(device)

    def _check_dict(self, wanted: bool, name: str) -> None:
        if wanted != isinstance(self.observation_space, spaces.Dict):
            other = f"Dict{name}" if not wanted else name
            raise ValueError(
                f"{type(self).__name__} cannot store {self.observation_space} observations; "
                f"use {other}"
            )

    @staticmethod
    def swap_and_flatten(arr: np.ndarray) -> np.ndarray:
        """``[n_steps, n_envs, ...]`` -> ``[n_envs * n_steps, ...]``, env-major (SB3's order)."""
        shape = arr.shape if arr.ndim >= 3 else (*arr.shape, 1)
        return arr.swapaxes(0, 1).reshape(shape[0] * shape[1], *shape[2:])

    def size(self) -> int:
        """Rows stored (each row holds one step of every env)."""
        return self.buffer_size if self.full else self.pos

    def reset(self) -> None:
        self.pos, self.full = 0, False

    def extend(self, *args: Any) -> None:
        """``add`` each step of batches given along their first axis."""
        for step in zip(*args, strict=True):
            self.add(*step)

    def add(self, *args: Any) -> None:  # pragma: no cover - each buffer defines its own
        raise NotImplementedError

    def to_torch(self, array: np.ndarray, copy: bool = True) -> torch.Tensor:
        """A tensor on the buffer's device (a copy unless ``copy=False``)."""
        if copy:
            return torch.tensor(array, device=self.device)
        return torch.as_tensor(array, device=self.device)

    @staticmethod
    def _normalize_obs(obs: Any, env: Any = None) -> Any:
        return obs if env is None else env.normalize_obs(obs)

    @staticmethod
    def _normalize_reward(reward: np.ndarray, env: Any = None) -> np.ndarray:
        return reward if env is None else env.normalize_reward(reward).astype(np.float32)


class ReplayBuffer(BaseBuffer):
    """SB3's replay buffer: ``buffer_size // n_envs`` rows of ``n_envs`` transitions.

    ``handle_timeout_termination``: a step whose info says ``TimeLimit.truncated`` is sampled
    with ``done = 0`` (the target bootstraps). ``optimize_memory_usage``: next observations
    are the following row of ``observations`` (half the memory; not with timeouts, as SB3)."""

    def __init__(
        self,
        buffer_size: int,
        observation_space: Any,
        action_space: Any,
        device: torch.device | str = "auto",
        n_envs: int = 1,
        optimize_memory_usage: bool = False,
        handle_timeout_termination: bool = True,
    ) -> None:
        super().__init__(buffer_size, observation_space, action_space, device, n_envs)
        self._check_dict(isinstance(self, DictReplayBuffer), "ReplayBuffer")
        self.buffer_size = max(self.buffer_size // self.n_envs, 1)
        if optimize_memory_usage and handle_timeout_termination:
            raise ValueError(
                "ReplayBuffer does not support optimize_memory_usage = True "
                "and handle_timeout_termination = True simultaneously."
            )
        self.optimize_memory_usage = optimize_memory_usage
        self.handle_timeout_termination = handle_timeout_termination
        lead = (self.buffer_size, self.n_envs)
        self.observations = _zeros(self.observation_space, self.obs_shape, lead)
        if not optimize_memory_usage:
            self.next_observations = _zeros(self.observation_space, self.obs_shape, lead)
        dtype = self._maybe_cast_dtype(self.action_space.dtype)
        self.actions = np.zeros((*lead, self.action_dim), dtype=dtype)
        self.rewards = np.zeros(lead, dtype=np.float32)
        self.dones = np.zeros(lead, dtype=np.float32)
        self.timeouts = np.zeros(lead, dtype=np.float32)

    @staticmethod
    def _maybe_cast_dtype(dtype: Any) -> Any:
        """float64 actions are stored as float32 (SB3, GH#1572: a float64 Box action space
        would otherwise feed float64 actions to float32 critics); other dtypes as given.
        Offered under SB3's name because SB3's own tests call it."""
        return np.float32 if dtype is not None and np.dtype(dtype) == np.float64 else dtype

    def add(
        self,
        obs: Any,
        next_obs: Any,
        action: np.ndarray,
        reward: np.ndarray,
        done: np.ndarray,
        infos: list[dict[str, Any]],
    ) -> None:
        """Store one step of every env (arrays ``[n_envs, ...]``, copied)."""
        space, n = self.observation_space, self.n_envs
        _put(self.observations, self.pos, obs, space, n)
        if self.optimize_memory_usage:
            _put(self.observations, (self.pos + 1) % self.buffer_size, next_obs, space, n)
        else:
            _put(self.next_observations, self.pos, next_obs, space, n)
        self.actions[self.pos] = np.array(action).reshape(n, self.action_dim)
        self.rewards[self.pos] = np.array(reward)
        self.dones[self.pos] = np.array(done)
        if self.handle_timeout_termination:
            if not isinstance(infos, (list, tuple)):
                raise TypeError(
                    "infos must be the list of per-env info dicts (SB3's VecEnv), got "
                    f"{type(infos).__name__}; with a Gymnasium vector env pass "
                    "handle_timeout_termination=False and store terminations as dones"
                )
            truncated = [bool(info.get("TimeLimit.truncated", False)) for info in infos]
            self.timeouts[self.pos] = truncated
        self.pos += 1
        if self.pos == self.buffer_size:
            self.full, self.pos = True, 0

    def sample(self, batch_size: int, env: Any = None) -> Any:
        """``batch_size`` transitions, uniformly with replacement (``np.random``, SB3's draws);
        ``env``: a ``VecNormalize`` whose statistics normalize observations and rewards."""
        if not self.optimize_memory_usage:
            rows = np.random.randint(0, self.size(), size=batch_size)  # noqa: NPY002 - SB3's draws
        elif self.full:  # the row at pos holds a next obs without its obs: never sampled
            rows = (np.random.randint(1, self.buffer_size, size=batch_size) + self.pos) % (  # noqa: NPY002
                self.buffer_size
            )
        else:
            rows = np.random.randint(0, self.pos, size=batch_size)  # noqa: NPY002
        return self._get_samples(rows, env)

    def _get_samples(self, rows: np.ndarray, env: Any = None) -> Any:
        cols = np.random.randint(0, high=self.n_envs, size=(len(rows),))  # noqa: NPY002
        if self.optimize_memory_usage:
            next_obs = _take(self.observations, (rows + 1) % self.buffer_size, cols)
        else:
            next_obs = _take(self.next_observations, rows, cols)
        dones = self.dones[rows, cols] * (1 - self.timeouts[rows, cols])
        rewards = self._normalize_reward(self.rewards[rows, cols].reshape(-1, 1), env)
        obs = self._normalize_obs(_take(self.observations, rows, cols), env)
        next_obs = self._normalize_obs(next_obs, env)
        if isinstance(obs, dict):
            return DictReplayBufferSamples(
                {k: self.to_torch(v) for k, v in obs.items()},
                self.to_torch(self.actions[rows, cols]),
                {k: self.to_torch(v) for k, v in next_obs.items()},
                self.to_torch(dones).reshape(-1, 1),
                self.to_torch(rewards),
            )
        fields = (obs, self.actions[rows, cols], next_obs, dones.reshape(-1, 1), rewards)
        return ReplayBufferSamples(*(self.to_torch(f) for f in fields))


class DictReplayBuffer(ReplayBuffer):
    """``ReplayBuffer`` for Dict observations (one array per key); no ``optimize_memory_usage``."""

    def __init__(
        self,
        buffer_size: int,
        observation_space: Any,
        action_space: Any,
        device: torch.device | str = "auto",
        n_envs: int = 1,
        optimize_memory_usage: bool = False,
        handle_timeout_termination: bool = True,
    ) -> None:
        if optimize_memory_usage:
            raise ValueError("DictReplayBuffer does not support optimize_memory_usage")
        super().__init__(
            buffer_size,
            observation_space,
            action_space,
            device,
            n_envs,
            optimize_memory_usage,
            handle_timeout_termination,
        )


class NStepReplayBuffer(ReplayBuffer):
    """SB3's ``NStepReplayBuffer``: ``ReplayBuffer``'s storage sampled as n-step returns, by
    the computation palaestra's algorithms use (``palaestra.algos.common.nstep``): ``rewards``
    the discounted sums over windows of up to ``n_steps`` transitions of one env (cut after a
    termination, a truncation and the newest transition), ``next_observations`` and ``dones``
    of each window's last transition, ``discounts`` ``gamma^len`` for the target."""

    def __init__(
        self,
        buffer_size: int,
        observation_space: Any,
        action_space: Any,
        device: torch.device | str = "auto",
        n_envs: int = 1,
        optimize_memory_usage: bool = False,
        handle_timeout_termination: bool = True,
        n_steps: int = 3,
        gamma: float = 0.99,
    ) -> None:
        if optimize_memory_usage:
            raise NotImplementedError(
                "NStepReplayBuffer doesn't support optimize_memory_usage=True"
            )
        self.n_steps, self.gamma = check_n_steps(n_steps), gamma
        super().__init__(
            buffer_size,
            observation_space,
            action_space,
            device,
            n_envs,
            optimize_memory_usage,
            handle_timeout_termination,
        )

    def _get_samples(self, rows: np.ndarray, env: Any = None) -> Any:
        cols = np.random.randint(0, high=self.n_envs, size=(len(rows),))  # noqa: NPY002 - SB3's
        newest = (self.pos - 1) % self.buffer_size
        returns, discounts, last = n_step_window(
            self.rewards,
            (self.dones, self.timeouts),
            newest,
            rows,
            cols,
            self.n_steps,
            self.gamma,
            None if env is None else lambda r: self._normalize_reward(r, env),
        )
        dones = self.dones[last, cols] * (1 - self.timeouts[last, cols])
        obs = self._normalize_obs(self.observations[rows, cols], env)
        next_obs = self._normalize_obs(self.next_observations[last, cols], env)
        columns = (dones, returns, discounts)  # [B, 1] each, as SB3's
        return ReplayBufferSamples(
            self.to_torch(obs),
            self.to_torch(self.actions[rows, cols]),
            self.to_torch(next_obs),
            *(self.to_torch(c.reshape(-1, 1)) for c in columns),
        )


class RolloutBuffer(BaseBuffer):
    """SB3's on-policy buffer: ``buffer_size`` steps of ``n_envs`` envs with values and
    log-probs, GAE(``gamma``, ``gae_lambda``), then shuffled minibatches from ``get``."""

    observations: Any  # [buffer_size, n_envs, *obs_shape] (a dict per key for Dict spaces)
    actions: np.ndarray  # [buffer_size, n_envs, action_dim]
    rewards: np.ndarray  # [buffer_size, n_envs] float32, as the five below
    returns: np.ndarray
    episode_starts: np.ndarray
    values: np.ndarray
    log_probs: np.ndarray
    advantages: np.ndarray

    def __init__(
        self,
        buffer_size: int,
        observation_space: Any,
        action_space: Any,
        device: torch.device | str = "auto",
        gae_lambda: float = 1,
        gamma: float = 0.99,
        n_envs: int = 1,
    ) -> None:
        super().__init__(buffer_size, observation_space, action_space, device, n_envs)
        self._check_dict(isinstance(self, DictRolloutBuffer), "RolloutBuffer")
        self.gae_lambda, self.gamma = gae_lambda, gamma
        self.reset()

    def reset(self) -> None:
        """Empty, zeroed arrays (SB3 reallocates them: ``get`` flattens them in place)."""
        lead = (self.buffer_size, self.n_envs)
        self.observations = _zeros(self.observation_space, self.obs_shape, lead)
        self.actions = np.zeros((*lead, self.action_dim), dtype=self.action_space.dtype)
        for name in ("rewards", "returns", "episode_starts", "values", "log_probs", "advantages"):
            setattr(self, name, np.zeros(lead, dtype=np.float32))
        self.generator_ready = False
        super().reset()

    def add(
        self,
        obs: Any,
        action: np.ndarray,
        reward: np.ndarray,
        episode_start: np.ndarray,
        value: torch.Tensor,
        log_prob: torch.Tensor,
    ) -> None:
        """Store one step of every env; ``value`` and ``log_prob`` are the policy's tensors."""
        if self.full:
            raise ValueError(f"the rollout buffer is full ({self.buffer_size} steps): reset() it")
        _put(self.observations, self.pos, obs, self.observation_space, self.n_envs)
        self.actions[self.pos] = np.array(action).reshape(self.n_envs, self.action_dim)
        self.rewards[self.pos] = np.array(reward)
        self.episode_starts[self.pos] = np.array(episode_start)
        self.values[self.pos] = value.detach().cpu().numpy().reshape(-1)
        self.log_probs[self.pos] = log_prob.detach().cpu().numpy().reshape(-1)
        self.pos += 1
        if self.pos == self.buffer_size:
            self.full = True

    def compute_returns_and_advantage(self, last_values: torch.Tensor, dones: np.ndarray) -> None:
        """GAE advantages and TD(lambda) returns (``advantages + values``) for the rollout;
        ``last_values``/``dones``: the value and done flag after its last step."""
        last = last_values.detach().cpu().numpy().reshape(-1).astype(np.float32)
        self.advantages, self.returns = gae(
            self.rewards,
            self.values,
            self.episode_starts,
            last,
            np.asarray(dones, dtype=np.float32),
            self.gamma,
            self.gae_lambda,
        )

    def get(self, batch_size: int | None = None) -> Iterator[Any]:
        """Minibatches of ``batch_size`` (None: all) over a ``np.random.permutation`` of the
        ``buffer_size * n_envs`` samples, env-major as SB3 orders them."""
        if not self.full:
            raise ValueError("the rollout buffer is not full yet: add buffer_size steps first")
        total = self.buffer_size * self.n_envs
        indices = np.random.permutation(total)  # noqa: NPY002 - SB3's draws
        if not self.generator_ready:
            for name in ("actions", "values", "log_probs", "advantages", "returns"):
                setattr(self, name, self.swap_and_flatten(getattr(self, name)))
            if isinstance(self.observations, dict):
                self.observations = {
                    k: self.swap_and_flatten(v) for k, v in self.observations.items()
                }
            else:
                self.observations = self.swap_and_flatten(self.observations)
            self.generator_ready = True
        size = total if batch_size is None else _positive("batch_size", batch_size)
        for start in range(0, total, size):
            yield self._get_samples(indices[start : start + size])

    def _get_samples(self, index: np.ndarray, env: Any = None) -> Any:
        rest = (
            self.to_torch(self.actions[index].astype(np.float32, copy=False)),
            self.to_torch(self.values[index].flatten()),
            self.to_torch(self.log_probs[index].flatten()),
            self.to_torch(self.advantages[index].flatten()),
            self.to_torch(self.returns[index].flatten()),
        )
        if isinstance(self.observations, dict):
            obs = {k: self.to_torch(v[index]) for k, v in self.observations.items()}
            return DictRolloutBufferSamples(obs, *rest)
        return RolloutBufferSamples(self.to_torch(self.observations[index]), *rest)


class DictRolloutBuffer(RolloutBuffer):
    """``RolloutBuffer`` for Dict observations (one array per key)."""
