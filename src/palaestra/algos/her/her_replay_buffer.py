"""``HerReplayBuffer``: SB3's Hindsight Experience Replay buffer (``stable_baselines3.her``),
for SB3 code that builds one and for palaestra's DQN, SAC, TD3 and DDPG
(``replay_buffer_class=HerReplayBuffer``).

Transitions are stored as they happen, with where each one's episode starts and how long it
is, known once the episode ends. A sampled batch is ``1 / (n_sampled_goal + 1)`` real
transitions (the second part of the batch, as in SB3) and the rest virtual ones: a transition
whose ``desired_goal`` (in its observation and its next observation) is replaced by a goal
achieved in its episode (``goal_selection_strategy``: ``future``, inclusive of the
transition's own step as in SB3, ``final`` or ``episode``), and whose reward is the env's
``compute_reward(next achieved goal, new goal, info)`` over the whole batch in one call
(``env.env_method("compute_reward", ..., indices=[0])``, the first env's method).

Bookkeeping as SB3's: only transitions of finished episodes are sampled (sampling before the
first episode ends is SB3's ``RuntimeError``); when the ring overwrites a row of an old episode,
that whole episode stops being sampled; ``truncate_last_trajectory`` ends the open episodes
(after ``load_replay_buffer`` of a run that will not continue them).

Two ways to sample the same thing: ``sample(batch_size, env)`` draws from numpy's global
generator in SB3's order (the same rows and goals as SB3's buffer after ``np.random.seed``)
and returns SB3's torch samples; the algorithms call ``sample_arrays(batch_size, rng)`` with
their seeded generator (exact resume) and get numpy arrays. Files: ``state``/``load_state``
(the model's ``save_replay_buffer``/``load_replay_buffer``, no pickle); ``copy_info_dict``
infos are kept as JSON data (numbers, strings, lists, dicts and numpy arrays).
"""

from __future__ import annotations

import copy
import json
import warnings
from typing import Any

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.common.buffers import DictReplayBuffer, DictReplayBufferSamples
from palaestra.algos.common.transition_ring import check_saved_arrays, flat_rows, saved_rows
from palaestra.algos.her.goal_selection_strategy import GoalSelectionStrategy, goal_strategy

__all__ = ["HerReplayBuffer"]

GOAL_KEYS = ("observation", "achieved_goal", "desired_goal")
_NO_EPISODE = (
    "Unable to sample before the end of the first episode. We recommend choosing a value "
    "for learning_starts that is greater than the maximum number of timesteps in the environment."
)


def _n_sampled_goal(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"n_sampled_goal must be an integer >= 0, got {value!r}")
    return int(value)


class HerReplayBuffer(DictReplayBuffer):
    """SB3's ``HerReplayBuffer(buffer_size, observation_space, action_space, env, device,
    n_envs, optimize_memory_usage, handle_timeout_termination, n_sampled_goal,
    goal_selection_strategy, copy_info_dict)``; ``env`` is the VecEnv whose first env's
    ``compute_reward`` relabels rewards (None until ``set_env``)."""

    env: Any

    def __init__(
        self,
        buffer_size: int,
        observation_space: Any,
        action_space: Any,
        env: Any,
        device: torch.device | str = "auto",
        n_envs: int = 1,
        optimize_memory_usage: bool = False,
        handle_timeout_termination: bool = True,
        n_sampled_goal: int = 4,
        goal_selection_strategy: GoalSelectionStrategy | str = "future",
        copy_info_dict: bool = False,
    ) -> None:
        if optimize_memory_usage:
            raise ValueError(
                "HerReplayBuffer does not support optimize_memory_usage=True "
                "(a DictReplayBuffer, as in SB3)"
            )
        self.goal_selection_strategy = goal_strategy(goal_selection_strategy)
        self.n_sampled_goal = _n_sampled_goal(n_sampled_goal)
        super().__init__(
            buffer_size,
            observation_space,
            action_space,
            device=device,
            n_envs=n_envs,
            optimize_memory_usage=False,
            handle_timeout_termination=handle_timeout_termination,
        )
        assert isinstance(self.observation_space, spaces.Dict)  # DictReplayBuffer checked it
        missing = [k for k in GOAL_KEYS if k not in self.observation_space.spaces]
        if missing:
            raise ValueError(
                f"HerReplayBuffer needs a goal-conditioned Dict observation space with keys "
                f"{list(GOAL_KEYS)}; {self.observation_space} lacks {missing}"
            )
        self.env = env
        self.copy_info_dict = bool(copy_info_dict)
        # The share of each batch that is relabelled (SB3's her_ratio).
        self.her_ratio = 1 - (1.0 / (self.n_sampled_goal + 1))
        lead = (self.buffer_size, self.n_envs)
        # Only with copy_info_dict (SB3 allocates them always): one object per transition.
        self.infos: np.ndarray | None = (
            np.array([[{} for _ in range(self.n_envs)] for _ in range(self.buffer_size)])
            if self.copy_info_dict
            else None
        )
        self.ep_start = np.zeros(lead, dtype=np.int64)
        self.ep_length = np.zeros(lead, dtype=np.int64)  # 0: not sampled (open or forgotten)
        self._current_ep_start = np.zeros(self.n_envs, dtype=np.int64)

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles leave the env out (SB3): ``set_env`` gives it back."""
        state = self.__dict__.copy()
        del state["env"]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self.env = None

    def set_env(self, env: Any) -> None:
        """The VecEnv whose ``compute_reward`` relabels; ``ValueError`` if one is set (SB3)."""
        if self.env is not None:
            raise ValueError("Trying to set env of already initialized environment.")
        self.env = env

    # -- storing -----------------------------------------------------------------------------
    def add(
        self,
        obs: dict[str, np.ndarray],
        next_obs: dict[str, np.ndarray],
        action: np.ndarray,
        reward: np.ndarray,
        done: np.ndarray,
        infos: list[dict[str, Any]],
    ) -> None:
        """Store one step of every env; an env whose ``done`` is set closes its episode."""
        for env_idx in np.flatnonzero(self.ep_length[self.pos]).tolist():
            self._forget_episode(self.pos, env_idx)  # its row is overwritten: all of it goes
        self.ep_start[self.pos] = self._current_ep_start
        if self.infos is not None:
            for env_idx, info in enumerate(infos):
                self.infos[self.pos, env_idx] = info
        super().add(obs, next_obs, action, reward, done, infos)
        for env_idx in np.flatnonzero(np.asarray(done)).tolist():
            self._compute_episode_length(env_idx)

    def _forget_episode(self, row: int, env_idx: int) -> None:
        start, length = self.ep_start[row, env_idx], self.ep_length[row, env_idx]
        self.ep_length[(start + np.arange(length)) % self.buffer_size, env_idx] = 0

    def _compute_episode_length(self, env_idx: int) -> None:
        """Env ``env_idx``'s episode ended at the row before ``pos``: record its length."""
        start = int(self._current_ep_start[env_idx])
        end = self.pos if self.pos >= start else self.pos + self.buffer_size  # SB3's rule
        rows = np.arange(start, end) % self.buffer_size
        self.ep_length[rows, env_idx] = end - start
        self._current_ep_start[env_idx] = self.pos

    def truncate_last_trajectory(self) -> None:
        """End every open episode at the last stored step (``done`` and, with
        ``handle_timeout_termination``, a timeout, so its targets bootstrap), as SB3 does when
        a loaded buffer will not be continued; SB3's warning when there is one."""
        if (self._current_ep_start != self.pos).any():
            warnings.warn(
                "The last trajectory in the replay buffer will be truncated.\n"
                "If you are in the same episode as when the replay buffer was saved,\n"
                "you should use `truncate_last_trajectory=False` to avoid that issue.",
                stacklevel=2,
            )
            self._close_open_episodes()

    def _close_open_episodes(self) -> None:
        last = (self.pos - 1) % self.buffer_size
        for env_idx in np.flatnonzero(self._current_ep_start != self.pos).tolist():
            self.dones[last, env_idx] = True
            self._compute_episode_length(env_idx)
            if self.handle_timeout_termination:
                self.timeouts[last, env_idx] = True  # not a time limit: it bootstraps

    # -- sampling ----------------------------------------------------------------------------
    def _draw(
        self, batch_size: int, choice: Any, randint: Any
    ) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
        """``(rows, cols, n_virtual, new goals)``: ``batch_size`` transitions of finished
        episodes, the first ``n_virtual`` of them relabelled with ``new goals``."""
        is_valid = self.ep_length > 0
        if not is_valid.any():
            raise RuntimeError(_NO_EPISODE)
        picked = choice(np.flatnonzero(is_valid), batch_size)
        rows, cols = np.unravel_index(picked, is_valid.shape)
        n_virtual = int(self.her_ratio * batch_size)
        goals = self._sample_goals(rows[:n_virtual], cols[:n_virtual], randint)
        return rows, cols, n_virtual, goals

    def _sample_goals(self, rows: np.ndarray, cols: np.ndarray, randint: Any) -> np.ndarray:
        """Achieved goals (of next observations) from each transition's episode."""
        start, length = self.ep_start[rows, cols], self.ep_length[rows, cols]
        if self.goal_selection_strategy == GoalSelectionStrategy.FINAL:
            offset = length - 1
        elif self.goal_selection_strategy == GoalSelectionStrategy.FUTURE:
            offset = randint((rows - start) % self.buffer_size, length)
        else:
            offset = randint(0, length)
        return self.next_observations["achieved_goal"][(start + offset) % self.buffer_size, cols]

    def _relabelled_rewards(
        self, rows: np.ndarray, cols: np.ndarray, next_achieved: np.ndarray, goals: np.ndarray
    ) -> np.ndarray:
        if self.env is None:
            raise ValueError(
                "HerReplayBuffer has no env to compute rewards for relabelled transitions: "
                "pass env= (a VecEnv) or call set_env(env)"
            )
        if self.infos is not None:
            infos: Any = copy.deepcopy(self.infos[rows, cols])
        else:
            infos = [{} for _ in range(len(rows))]
        rewards = self.env.env_method("compute_reward", next_achieved, goals, infos, indices=[0])[0]
        return np.asarray(rewards, dtype=np.float32).reshape(len(rows))

    def _batch(
        self, rows: np.ndarray, cols: np.ndarray, n_virtual: int, goals: np.ndarray
    ) -> tuple[Any, ...]:
        """Observations, actions, next observations, rewards and terminations (SB3's order:
        the real transitions first, then the relabelled ones), in the storage's shapes."""
        order = np.concatenate([np.arange(n_virtual, len(rows)), np.arange(n_virtual)])
        rows, cols = rows[order], cols[order]
        n_real = len(rows) - n_virtual
        obs = {k: v[rows, cols] for k, v in self.observations.items()}
        next_obs = {k: v[rows, cols] for k, v in self.next_observations.items()}
        rewards = self.rewards[rows, cols].copy()
        if n_virtual:
            obs["desired_goal"][n_real:] = goals
            next_obs["desired_goal"][n_real:] = goals
            rewards[n_real:] = self._relabelled_rewards(
                rows[n_real:], cols[n_real:], next_obs["achieved_goal"][n_real:], goals
            )
        terminated = self.dones[rows, cols] * (1 - self.timeouts[rows, cols])
        return obs, self.actions[rows, cols], next_obs, rewards, terminated

    def sample(self, batch_size: int, env: Any = None) -> DictReplayBufferSamples:
        """SB3's ``sample``: numpy's global generator, torch tensors (real transitions first),
        observations and rewards normalised by ``env`` (a ``VecNormalize``) when given."""
        rows, cols, n_virtual, goals = self._draw(
            batch_size,
            lambda valid, n: np.random.choice(valid, size=n, replace=True),  # noqa: NPY002
            np.random.randint,
        )
        obs, actions, next_obs, rewards, terminated = self._batch(rows, cols, n_virtual, goals)
        obs, next_obs = self._normalize_obs(obs, env), self._normalize_obs(next_obs, env)
        return DictReplayBufferSamples(
            {k: self.to_torch(v) for k, v in obs.items()},
            self.to_torch(actions),
            {k: self.to_torch(v) for k, v in next_obs.items()},
            self.to_torch(terminated).reshape(-1, 1),
            self.to_torch(self._normalize_reward(rewards.reshape(-1, 1), env)),
        )

    def sample_arrays(self, batch_size: int, rng: np.random.Generator) -> tuple[Any, ...]:
        """What the algorithms train on (``off_policy.BATCH_KEYS``), drawn with ``rng``:
        observations as the envs give them (``Discrete`` entries without SB3's extra axis),
        actions in the action space's shape, rewards and terminations ``[batch]``."""
        rows, cols, n_virtual, goals = self._draw(
            batch_size,
            lambda valid, n: rng.choice(valid, size=n, replace=True),
            rng.integers,
        )
        obs, actions, next_obs, rewards, terminated = self._batch(rows, cols, n_virtual, goals)
        shape = tuple(self.action_space.shape or ())
        return (
            self._space_shaped(obs),
            actions.reshape(batch_size, *shape),
            self._space_shaped(next_obs),
            rewards,
            terminated,
        )

    def _space_shaped(self, obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        assert isinstance(self.observation_space, spaces.Dict)
        space = self.observation_space.spaces
        return {
            k: v.reshape(len(v)) if isinstance(space[k], spaces.Discrete) else v
            for k, v in obs.items()
        }

    # -- files (the model's save_replay_buffer / load_replay_buffer) --------------------------
    def size(self) -> int:
        """Rows stored (each row holds one step of every env)."""
        return self.buffer_size if self.full else self.pos

    def nbytes(self) -> int:
        """Bytes of the arrays a file of this buffer may hold."""
        stores = [*self.observations.values(), *self.next_observations.values()]
        stores += [self.actions, self.rewards, self.dones, self.timeouts]
        stores += [self.ep_start, self.ep_length, self._current_ep_start]
        return int(sum(a.nbytes for a in stores))

    def _saved_arrays(self, n: int) -> dict[str, np.ndarray]:
        """The arrays a saved buffer holds, as views of this buffer's first ``n`` rows."""
        return {
            **flat_rows("observations", self.observations, n),
            **flat_rows("next_observations", self.next_observations, n),
            "actions": self.actions[:n],
            "rewards": self.rewards[:n],
            "dones": self.dones[:n],
            "timeouts": self.timeouts[:n],
            "ep_start": self.ep_start[:n],
            "ep_length": self.ep_length[:n],
            "current_ep_start": self._current_ep_start,
        }

    def state(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """JSON metadata and the filled part of every array."""
        n = self.size()
        arrays = self._saved_arrays(n)
        meta: dict[str, Any] = {
            "kind": "her",
            "buffer_size": self.buffer_size,
            "n_envs": self.n_envs,
            "pos": self.pos,
            "full": self.full,
            "handle_timeout_termination": self.handle_timeout_termination,
            "n_sampled_goal": self.n_sampled_goal,
            "goal_selection_strategy": self.goal_selection_strategy.name.lower(),
            "copy_info_dict": self.copy_info_dict,
        }
        if self.infos is not None:
            meta["infos"] = [[_json_info(i) for i in row] for row in self.infos[:n].tolist()]
        return meta, arrays

    def load_state(self, meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
        """Restore from ``state()``; ``ValueError`` naming what does not fit this buffer."""
        if meta.get("kind") != "her":
            raise ValueError(
                "the file holds a replay buffer without hindsight relabelling; this model uses "
                "HerReplayBuffer (replay_buffer_class)"
            )
        n = saved_rows(meta, arrays, self.n_envs, self.buffer_size)
        targets = self._saved_arrays(n)
        check_saved_arrays(arrays, targets)
        pos, full = meta["pos"], meta["full"]
        if not isinstance(full, bool) or isinstance(pos, bool) or not isinstance(pos, int):
            raise ValueError(f"replay buffer position {pos!r}/full {full!r} are malformed")
        full = full and n == self.buffer_size
        pos = pos % self.buffer_size if full else n
        for key in ("ep_start", "current_ep_start"):  # row indices
            if ((arrays[key] < 0) | (arrays[key] >= self.buffer_size)).any():
                raise ValueError(
                    f"replay buffer {key!r} holds rows outside [0, {self.buffer_size})"
                )
        if ((arrays["ep_length"] < 0) | (arrays["ep_length"] > self.buffer_size)).any():
            raise ValueError(
                f"replay buffer 'ep_length' holds lengths outside [0, {self.buffer_size}]"
            )
        if not np.isfinite(arrays["rewards"]).all():
            raise ValueError("replay buffer rewards hold NaN or infinite values")
        if isinstance(self.action_space, spaces.Discrete):
            start, stop = self.action_space.start, self.action_space.start + self.action_space.n
            if n and not ((arrays["actions"] >= start) & (arrays["actions"] < stop)).all():
                raise ValueError(f"replay buffer actions outside {self.action_space}")
        infos = meta.get("infos")
        if self.infos is not None:
            if not isinstance(infos, list) or len(infos) != n:
                raise ValueError(
                    "the saved replay buffer holds no infos for its rows, which copy_info_dict "
                    "needs"
                )
        for key, target in targets.items():
            target[...] = arrays[key]
        if self.infos is not None:
            for row, values in enumerate(infos):  # type: ignore[arg-type]
                for env_idx, value in enumerate(values):
                    self.infos[row, env_idx] = _info_from_json(value)
        self.full, self.pos = full, pos


# -- infos as data -----------------------------------------------------------------------------
def _json_info(value: Any) -> Any:
    """An info value as JSON data: numpy arrays tagged with their dtype and shape, numpy
    scalars as Python numbers; ``ValueError`` naming anything else (a file holds no objects)."""
    if isinstance(value, dict):
        return {"dict": {str(k): _json_info(v) for k, v in value.items()}}
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "biuf":
            raise ValueError(f"cannot save an info array of dtype {value.dtype} (numbers only)")
        return {"ndarray": value.tolist(), "dtype": value.dtype.str, "shape": list(value.shape)}
    if isinstance(value, np.generic):
        return {"scalar": value.item(), "dtype": value.dtype.str}
    if isinstance(value, (list, tuple)):
        return {"list": [_json_info(v) for v in value]}
    if value is None or isinstance(value, (bool, int, float, str)):
        json.dumps(value)  # NaN and infinities are written as JSON allows Python to
        return {"value": value}
    raise ValueError(
        f"cannot save info value {value!r:.80} of type {type(value).__name__} in a replay buffer "
        "file (copy_info_dict=True keeps numbers, strings, lists, dicts and numeric arrays)"
    )


def _info_from_json(value: Any) -> Any:
    if not isinstance(value, dict) or len(value) not in (1, 2, 3):
        raise ValueError(f"malformed info value {value!r:.80}")
    if "dict" in value:
        return {k: _info_from_json(v) for k, v in value["dict"].items()}
    if "list" in value:
        return [_info_from_json(v) for v in value["list"]]
    if "value" in value:
        return value["value"]
    dtype = np.dtype(str(value["dtype"]))
    if dtype.kind not in "biuf":
        raise ValueError(f"malformed info dtype {value['dtype']!r}")
    if "scalar" in value:
        return dtype.type(value["scalar"])
    return np.array(value["ndarray"], dtype=dtype).reshape(value["shape"])
