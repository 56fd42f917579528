"""What DQN, SAC, TD3 and DDPG share: collect ``train_freq`` steps (or episodes) into a replay
buffer, then ``gradient_steps`` updates; SB3's ``OffPolicyAlgorithm`` rules.

After each collection, once ``num_timesteps > learning_starts``, ``train(gradient_steps)``
runs (``-1``: as many updates as env steps collected). A transition cut by a time limit is
stored with its true terminal observation and bootstraps (``handle_timeout_termination``). A
callback that stops training ends the loop after its step is fully recorded (the transition
stored, counters advanced), so a saved model continues exactly. ``n_steps > 1``: the
buffer samples n-step returns with each sample's discount (``common.nstep``; SB3 2.x).
"""

from __future__ import annotations

import inspect
import warnings
from typing import Any

import numpy as np
import torch

from palaestra.algos.common import model_io
from palaestra.algos.common.base import BaseAlgorithm, round_up_steps
from palaestra.algos.common.frame_replay_buffer import FrameReplayBuffer, frame_layout
from palaestra.algos.common.nstep import check_n_steps
from palaestra.algos.common.schedules import as_schedule
from palaestra.algos.common.settings import Settings
from palaestra.algos.common.transition_ring import BATCH_KEYS, TransitionRing
from palaestra.algos.her.goal_selection_strategy import GoalSelectionStrategy
from palaestra.algos.her.her_replay_buffer import HerReplayBuffer

__all__ = ["REPLAY_BUFFER_CLASSES", "OffPolicyAlgorithm", "replay_buffer_class", "train_freq_pair"]

# The buffer classes ``replay_buffer_class`` takes, by the names settings files and model
# files use for them (None: palaestra's own ring).
REPLAY_BUFFER_CLASSES: dict[str, type] = {"HerReplayBuffer": HerReplayBuffer}


def replay_buffer_class(value: Any) -> type | None:
    """``replay_buffer_class`` as a class: None, ``HerReplayBuffer`` (or a subclass), or its
    name. Other classes are refused: palaestra's learners sample the buffer as arrays with the
    model's seeded generator and save it without pickle, which SB3's other buffer classes
    (and users' subclasses of them) do not offer."""
    if value is None:
        return None
    if isinstance(value, str) and value in REPLAY_BUFFER_CLASSES:
        return REPLAY_BUFFER_CLASSES[value]
    if isinstance(value, type) and issubclass(value, HerReplayBuffer):
        return value
    raise NotImplementedError(
        f"replay_buffer_class={value!r} is not supported: palaestra's off-policy algorithms "
        f"take None (their own replay buffer) or HerReplayBuffer (also by its name "
        f"'HerReplayBuffer')"
    )


def train_freq_pair(value: Any) -> tuple[int, str]:
    """``4`` or ``(4, "step")`` or ``(1, "episode")`` -> ``(n, unit)``."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        value = (int(value), "step")
    if (
        not isinstance(value, (tuple, list))
        or len(value) != 2
        or value[1] not in ("step", "episode")
        # an int, as SB3 requires: ("1", "episode") is a ValueError there too
        or not isinstance(value[0], (int, np.integer))
        or isinstance(value[0], bool)
        or int(value[0]) < 1
    ):
        raise ValueError(
            f'train_freq must be a positive int or (n, "step"|"episode"), got {value!r}'
        )
    return int(value[0]), str(value[1])


class OffPolicyAlgorithm(BaseAlgorithm):
    """The replay loop; subclasses build their nets in ``_setup_model`` and implement
    ``_sample_actions`` and ``train``, and optionally ``_on_step``/``_on_episode_end``."""

    # The collection counters make a run stopped mid-collection train at the same steps
    # after a resume as without the stop.
    _extra_counters: tuple[str, ...] = ("_n_calls", "_collected_steps", "_collected_episodes")
    replay_buffer: TransitionRing | FrameReplayBuffer | HerReplayBuffer | None

    def _build_policy(self, policy_kwargs: dict[str, Any]) -> Any:
        """The policy module: the class given (or the one its name stands for) built as SB3
        does, ``cls(observation_space, action_space, lr_schedule, **policy_kwargs)``, on the
        model's device. Keys the class does not take are a ``TypeError`` naming them."""
        name = self.policy_name
        cls: Any = name if isinstance(name, type) else self.policy_aliases[name]
        kwargs = dict(policy_kwargs)
        kwargs.pop("backend", None)  # the learner's, not the policy's
        params = inspect.signature(cls).parameters.values()
        if not any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
            takes = {p.name for p in params} - {"observation_space", "action_space"}
            unknown = sorted(set(kwargs) - takes)
            if unknown:
                raise TypeError(
                    f"{type(self).__name__} policy_kwargs got unexpected keys {unknown} "
                    f"({cls.__name__} takes {', '.join(sorted(takes - {'lr_schedule'}))})"
                )
        policy = cls(self.observation_space, self.action_space, self.lr_schedule, **kwargs)
        return policy.to(self.device)

    def _custom_policy(self, policy: torch.nn.Module) -> str:
        """Why the numpy learner cannot run ``policy`` ("" for palaestra's own classes, whose
        networks it knows): a user's subclass may change any of them."""
        if type(policy) in self.policy_aliases.values():
            return ""
        return f"the policy is a custom {type(policy).__name__}"

    def _take_settings(self, settings: Settings) -> None:
        """The settings every off-policy algorithm takes (SB3's names and meanings)."""
        self.replay_buffer_class = replay_buffer_class(settings["replay_buffer_class"])
        self.n_steps = check_n_steps(settings["n_steps"])
        if self.n_steps > 1 and self.replay_buffer_class is not None:
            # SB3's rule and words: a buffer class given sets up its own sampling
            warnings.warn(
                f"`n_steps={self.n_steps}` is ignored because a custom `replay_buffer_class` "
                f"(`{self.replay_buffer_class.__name__}`) was passed: n-step returns are only "
                "set up automatically when `replay_buffer_class` is `None`.",
                stacklevel=4,
            )
        self.optimize_memory_usage = bool(settings["optimize_memory_usage"])
        if self.n_steps > 1 and self.optimize_memory_usage:
            raise NotImplementedError(
                f"n_steps={self.n_steps} is not supported with optimize_memory_usage=True "
                "(as SB3's NStepReplayBuffer)"
            )
        self.learning_rate = settings["learning_rate"]
        self.lr_schedule = as_schedule(self.learning_rate)
        self.buffer_size = settings["buffer_size"]
        self.learning_starts = settings["learning_starts"]
        self.batch_size = settings["batch_size"]
        self.tau, self.gamma = settings["tau"], settings["gamma"]
        self.train_freq = train_freq_pair(settings["train_freq"])
        self.gradient_steps = settings["gradient_steps"]
        self.replay_buffer_kwargs: dict[str, Any] = dict(settings["replay_buffer_kwargs"] or {})
        for key in ("n_steps", "gamma"):  # the algorithm's own (SB3 sets them the same way)
            if key in self.replay_buffer_kwargs:
                raise ValueError(
                    f"replay_buffer_kwargs may not set {key!r} "
                    f"({self.replay_buffer_kwargs[key]!r}): pass {key}= to "
                    f"{type(self).__name__}() instead"
                )
        self._n_calls = 0
        self._collected_steps = self._collected_episodes = 0  # of the collection under way
        self.replay_buffer = None
        super()._take_settings(settings)

    def _make_replay_buffer(self) -> None:
        self._no_timeouts = np.zeros(self.n_envs, dtype=bool)
        if self.replay_buffer_class is not None:  # HerReplayBuffer: SB3's arguments
            self.replay_buffer = self.replay_buffer_class(
                self.buffer_size,
                self.observation_space,
                self.action_space,
                env=self.env,
                device=self.device,
                n_envs=self.n_envs,
                optimize_memory_usage=self.optimize_memory_usage,
                **self.replay_buffer_kwargs,
            )
            return
        if self.optimize_memory_usage:
            self.replay_buffer = FrameReplayBuffer(
                self.buffer_size,
                self.observation_space,
                self.action_space,
                self.n_envs,
                self.device,
                **{"layout": frame_layout(self.observation_space, self.env)}
                | self.replay_buffer_kwargs,
            )
            return
        nstep = {"n_steps": self.n_steps, "gamma": self.gamma} if self.n_steps > 1 else {}
        self.replay_buffer = TransitionRing(
            self.buffer_size,
            self.observation_space,
            self.action_space,
            self.n_envs,
            self.device,
            **self.replay_buffer_kwargs,
            **nstep,
        )

    def _sample_batch(self, batch_size: int) -> dict[str, Any]:
        """A uniform minibatch by the objectives' names (``BATCH_KEYS``); with ``n_steps > 1``
        n-step rewards and next observations, and ``discounts``, each sample's ``gamma^len``."""
        assert self.replay_buffer is not None
        return dict(zip(BATCH_KEYS, self.replay_buffer.sample_arrays(batch_size, self._rng)))

    def final_timesteps(self, total_timesteps: int) -> int:
        freq, unit = self.train_freq
        if unit == "episode":  # unknown in advance: at least the whole steps of every env
            return super().final_timesteps(total_timesteps)
        # Whole collections of train_freq steps per env, from where the open one began.
        start = self.num_timesteps - self._collected_steps * self.n_envs
        return round_up_steps(start, self.num_timesteps, total_timesteps, freq * self.n_envs)

    def _on_n_envs_changed(self) -> None:
        if self.replay_buffer is not None and self.replay_buffer.size() > 0:
            warnings.warn("n_envs changed: starting a new, empty replay buffer", stacklevel=3)
        self._make_replay_buffer()

    def _sample_actions(self) -> tuple[np.ndarray, np.ndarray]:
        """``(actions for the env, actions for the buffer)`` at the current observations."""
        raise NotImplementedError

    def _on_step(self) -> None:
        """After each stored env step (DQN: target net and exploration rate)."""

    def _on_episode_end(self, index: int) -> None:
        """Env ``index`` finished an episode (action noise resets)."""

    def train(self, gradient_steps: int, batch_size: int = 100) -> None:
        raise NotImplementedError

    # -- learning ----------------------------------------------------------------------------
    def learn(
        self,
        total_timesteps: int,
        callback: Any = None,
        log_interval: int | None = 4,
        tb_log_name: str = "",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> Any:
        """Collect ``train_freq`` steps (or episodes), then do ``gradient_steps`` updates.

        A callback that stops training ends the loop after its step is fully recorded (the
        transition stored, counters advanced), so a saved model continues exactly."""
        name = tb_log_name or type(self).__name__
        callback = self._setup_learn(
            total_timesteps, callback, reset_num_timesteps, name, progress_bar
        )
        callback.on_training_start(self._callback_locals(), {})
        freq, unit = self.train_freq
        running = True
        with self._learning_session():
            while running and self.num_timesteps < self._total_timesteps:
                callback.on_rollout_start()
                self._set_training_mode(False)  # SB3: evaluation mode while collecting
                while (
                    running
                    and (self._collected_steps if unit == "step" else self._collected_episodes)
                    < freq
                ):
                    running = self._collect_step(callback, log_interval)
                callback.on_rollout_end()
                if not running:
                    break  # the collection stays open: a resumed run completes it
                if self.num_timesteps > self.learning_starts:
                    steps = self._collected_steps * self.n_envs
                    gradient_steps = self.gradient_steps if self.gradient_steps >= 0 else steps
                    if gradient_steps > 0:
                        self.train(gradient_steps, self.batch_size)
                self._collected_steps = self._collected_episodes = 0
        callback.on_training_end()
        return self

    def _collect_step(self, callback: Any, log_interval: int | None) -> bool:
        """One env step of every env, stored; False if a callback asked to stop."""
        assert self.replay_buffer is not None
        actions, buffer_actions = self._sample_actions()
        new_obs, rewards, dones, infos = self.env.step(actions)
        self._collected_steps += 1
        running = self._stepped(callback, actions, new_obs, rewards, dones, infos)
        next_obs, timeouts = new_obs, self._no_timeouts  # [n_envs] all False
        ended = np.count_nonzero(dones)  # dones.any() costs ~3x more per step
        if ended:
            next_obs, timeouts = self._real_next_obs(new_obs, dones, infos)
        if isinstance(self.replay_buffer, HerReplayBuffer):  # SB3's add: it reads the infos
            self.replay_buffer.add(self._last_obs, next_obs, buffer_actions, rewards, dones, infos)
        else:
            self.replay_buffer.add(
                self._last_obs, next_obs, buffer_actions, rewards, dones, timeouts
            )
        self._last_obs = new_obs
        self._update_progress()
        self._n_calls += 1
        self._on_step()
        for index in np.flatnonzero(dones).tolist() if ended else ():
            self._on_episode_end(index)
            self._collected_episodes += 1
            self._episode_num += 1
            if log_interval is not None and self._episode_num % log_interval == 0:
                self.dump_logs()
        return running

    def _on_env_reset(self, restart: bool) -> None:
        # The open collection counted steps of the old episodes (which a buffer loaded from
        # a checkpoint may not hold): start a new one.
        self._collected_steps = self._collected_episodes = 0
        if isinstance(self.replay_buffer, HerReplayBuffer):
            # The episodes the buffer holds open end here: the env starts new ones (SB3 would
            # join the old and the new steps into one episode).
            self.replay_buffer._close_open_episodes()

    def set_env(self, env: Any, force_reset: bool = True) -> None:
        """Train on another env with the same spaces; a ``HerReplayBuffer`` relabels with the
        new env's ``compute_reward`` from then on."""
        super().set_env(env, force_reset)
        if isinstance(self.replay_buffer, HerReplayBuffer):
            self.replay_buffer.env = self.env

    def _saved_value(self, name: str) -> Any:
        if name == "replay_buffer_class":  # by its name (model files hold data only)
            cls = self.replay_buffer_class
            return None if cls is None else cls.__name__
        value = super()._saved_value(name)
        if name == "replay_buffer_kwargs":
            strategy = value.get("goal_selection_strategy")
            if isinstance(strategy, GoalSelectionStrategy):
                value = {**value, "goal_selection_strategy": strategy.name.lower()}
        return value

    def _real_next_obs(
        self, new_obs: Any, dones: np.ndarray, infos: list[dict[str, Any]]
    ) -> tuple[Any, np.ndarray]:
        """Where an env was reset, the stored next obs is its terminal observation."""
        timeouts = np.array(
            [bool(d and i.get("TimeLimit.truncated", False)) for d, i in zip(dones, infos)]
        )
        if isinstance(new_obs, dict):
            next_obs = {k: v.copy() for k, v in new_obs.items()}
        else:
            next_obs = new_obs.copy()
        for idx in np.flatnonzero(dones):
            terminal = infos[idx].get("terminal_observation")
            if terminal is None:
                continue
            if isinstance(next_obs, dict):
                for key in next_obs:
                    next_obs[key][idx] = terminal[key]
            else:
                next_obs[idx] = terminal
        return next_obs, timeouts

    def dump_logs(self) -> None:
        """Write the episode count and statistics, fps and what was recorded since the last
        dump (SB3's ``dump_logs``)."""
        self.logger.record("time/episodes", self._episode_num, exclude="tensorboard")
        self._record_episode_stats()
        self.logger.dump(step=self.num_timesteps)

    # -- persistence ---------------------------------------------------------------------------
    def save_replay_buffer(self, path: Any) -> None:
        """Write the replay buffer (pickle-free zip, like model files)."""
        if self.replay_buffer is None:
            raise ValueError("this model has no replay buffer to save (replay_buffer is None)")
        meta, arrays = self.replay_buffer.state()
        model_io.write_archive(path, "replay_buffer", meta, arrays)

    def load_replay_buffer(
        self, path: Any, truncate_last_traj: bool = True, max_bytes: int | None = None
    ) -> None:
        """Restore a buffer written by ``save_replay_buffer`` (its n_envs must match).

        ``truncate_last_traj`` (``HerReplayBuffer`` only, as SB3): end the episodes the file
        holds open, for a run that starts new ones; ``False`` when the model continues the
        episodes it was saved in (exact resume). The buffer relabels with this model's env.

        A file may hold at most what this model's buffer holds (``max_bytes`` overrides that
        bound): a crafted file cannot make the reader allocate more than the buffer itself.
        A model whose ``replay_buffer`` is None (set so to free memory) gets a new one with
        its settings first, as SB3 sets the loaded buffer; so does one whose attribute
        was deleted (``del model.replay_buffer``, as SB3's tests do)."""
        if getattr(self, "replay_buffer", None) is None:
            self._make_replay_buffer()
        assert self.replay_buffer is not None
        # A file saved with n_steps > 1 also records where episodes ended (as rewards, float32).
        ended = self.replay_buffer.rewards.nbytes
        limit = self.replay_buffer.nbytes() + ended + (1 << 20) if max_bytes is None else max_bytes
        meta, arrays = model_io.read_archive(path, "replay_buffer", max_bytes=limit)
        try:
            self.replay_buffer.load_state(meta, arrays)
        except (KeyError, ValueError, TypeError) as exc:
            raise model_io.ModelFileError(
                f"{path}: replay buffer does not fit this model ({exc})"
            ) from exc
        # samples go where the model is now (SB3 GH#1561: model.device may have changed)
        self.replay_buffer.device = self.device
        if isinstance(self.replay_buffer, HerReplayBuffer):
            self.replay_buffer.env = self.env
            if truncate_last_traj:
                self.replay_buffer.truncate_last_trajectory()
