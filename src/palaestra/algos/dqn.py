"""DQN (Mnih et al. 2015) with Stable-Baselines3's parameters, defaults and update rules."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos import model_io
from palaestra.algos.base import BaseAlgorithm
from palaestra.algos.frame_replay_buffer import FrameReplayBuffer, frame_layout
from palaestra.algos.learners import Group, Net
from palaestra.algos.learners.objectives import DQNObjective
from palaestra.algos.policies import QNetwork, extractor_class
from palaestra.algos.replay_buffer import ReplayBuffer
from palaestra.algos.schedules import LinearSchedule, Schedule, as_schedule

__all__ = ["DQN"]


def _train_freq(value: Any) -> tuple[int, str]:
    """``4`` or ``(4, "step")`` or ``(1, "episode")`` -> ``(n, unit)``."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        value = (int(value), "step")
    if (
        not isinstance(value, (tuple, list))
        or len(value) != 2
        or value[1] not in ("step", "episode")
        or int(value[0]) < 1
    ):
        raise ValueError(
            f'train_freq must be a positive int or (n, "step"|"episode"), got {value!r}'
        )
    return int(value[0]), str(value[1])


class DQN(BaseAlgorithm):
    """Deep Q-Network: ``DQN("MlpPolicy", env, ...)``; arguments as SB3's ``DQN``.

    Kept from SB3: uniform random actions before ``learning_starts``; epsilon decays linearly
    from ``exploration_initial_eps`` to ``exploration_final_eps`` over ``exploration_fraction``
    of training; the target net is updated every ``target_update_interval`` env steps
    (polyak with ``tau``); Huber loss; gradients clipped to ``max_grad_norm``; truncated
    episodes bootstrap. Changed: with several envs each env draws its own epsilon coin (SB3
    explores with all envs or none); resuming continues epsilon where it stopped.
    ``optimize_memory_usage=True`` stores each frame of stacked image observations once
    (``FrameReplayBuffer``; exact, terminal observations included, so unlike SB3 it works with
    ``handle_timeout_termination``). ``num_threads`` sets torch's CPU threads (default 1 for
    MlpPolicy).
    """

    supported_action_spaces = (spaces.Discrete,)
    # The collection counters make a run stopped mid-collection train at the same steps
    # after a resume as without the stop.
    _extra_counters = ("_n_calls", "exploration_rate", "_collected_steps", "_collected_episodes")

    def __init__(
        self,
        policy: str,
        env: Any,
        learning_rate: float | Schedule = 1e-4,
        buffer_size: int = 1_000_000,
        learning_starts: int = 100,
        batch_size: int = 32,
        tau: float = 1.0,
        gamma: float = 0.99,
        train_freq: int | tuple[int, str] = 4,
        gradient_steps: int = 1,
        replay_buffer_class: None = None,
        replay_buffer_kwargs: dict[str, Any] | None = None,
        optimize_memory_usage: bool = False,
        n_steps: int = 1,
        target_update_interval: int = 10000,
        exploration_fraction: float = 0.1,
        exploration_initial_eps: float = 1.0,
        exploration_final_eps: float = 0.05,
        max_grad_norm: float = 10,
        stats_window_size: int = 100,
        tensorboard_log: str | None = None,
        policy_kwargs: dict[str, Any] | None = None,
        verbose: int = 0,
        seed: int | None = None,
        device: torch.device | str = "auto",
        num_threads: int | None = None,
        _init_setup_model: bool = True,
    ) -> None:
        if replay_buffer_class is not None or n_steps != 1:
            raise NotImplementedError("replay_buffer_class and n_steps > 1 are not supported yet")
        self.optimize_memory_usage = bool(optimize_memory_usage)
        self.learning_rate, self.lr_schedule = learning_rate, as_schedule(learning_rate)
        self.buffer_size, self.learning_starts, self.batch_size = (
            buffer_size,
            learning_starts,
            batch_size,
        )
        self.tau, self.gamma, self.train_freq = tau, gamma, _train_freq(train_freq)
        self.gradient_steps, self.target_update_interval = gradient_steps, target_update_interval
        self.exploration_fraction = exploration_fraction
        self.exploration_initial_eps, self.exploration_final_eps = (
            exploration_initial_eps,
            exploration_final_eps,
        )
        self.max_grad_norm = max_grad_norm
        self.replay_buffer_kwargs = dict(replay_buffer_kwargs or {})
        self.exploration_schedule = LinearSchedule(
            exploration_initial_eps, exploration_final_eps, exploration_fraction
        )
        self.exploration_rate, self._n_calls = 0.0, 0
        self._collected_steps = self._collected_episodes = 0  # of the collection under way
        self.replay_buffer: ReplayBuffer | FrameReplayBuffer | None = None
        self._init_common(
            policy,
            env,
            policy_kwargs,
            verbose,
            seed,
            device,
            tensorboard_log,
            num_threads,
            stats_window_size,
        )
        if self.env is not None and self.n_envs > target_update_interval:
            warnings.warn(
                f"The number of environments ({self.n_envs}) exceeds "
                f"target_update_interval ({target_update_interval}): the target network "
                "is updated every step",
                stacklevel=2,
            )
        if _init_setup_model:
            if self.env is None:
                raise ValueError("DQN needs an env (an id string, an Env or a VecEnv)")
            self._setup_model()

    def _setup_model(self) -> None:
        if not isinstance(self.action_space, spaces.Discrete):
            raise TypeError(f"DQN only supports Discrete action spaces, got {self.action_space}")
        self.set_random_seed(self.seed)
        kwargs = dict(self.policy_kwargs)
        optimizer_class = kwargs.pop("optimizer_class", torch.optim.Adam)
        optimizer_kwargs = kwargs.pop("optimizer_kwargs", None) or {}
        backend = kwargs.pop("backend", "auto")
        kwargs.setdefault("features_extractor_class", extractor_class(self.policy_name))
        kwargs.pop("share_features_extractor", None)
        q_net = QNetwork(self.observation_space, self.action_space, **kwargs)
        q_net_target = QNetwork(self.observation_space, self.action_space, **kwargs)
        q_net_target.load_state_dict(q_net.state_dict())
        q_net_target.requires_grad_(False)
        policy = torch.nn.ModuleDict({"q_net": q_net, "q_net_target": q_net_target}).to(self.device)
        params = list(q_net.parameters())
        optimizer = self._make_optimizer(params, optimizer_class, optimizer_kwargs)
        modules, why = q_net.mlp_modules()
        target_modules, _ = q_net_target.mlp_modules()
        nets = {
            "q": Net(q_net, modules, group="q", why=why),
            "q_target": Net(q_net_target, target_modules, target_of="q", why=why),
        }
        self._set_learner(policy, optimizer, backend, nets, {"q": Group(optimizer, params)})
        self._make_replay_buffer()

    # SB3's attributes; reading them hands the parameters to torch, as ``policy`` does.
    @property
    def q_net(self) -> QNetwork:
        return self.policy["q_net"]

    @property
    def q_net_target(self) -> QNetwork:
        return self.policy["q_net_target"]

    def _make_replay_buffer(self) -> None:
        self._no_timeouts = np.zeros(self.n_envs, dtype=bool)
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
        self.replay_buffer = ReplayBuffer(
            self.buffer_size,
            self.observation_space,
            self.action_space,
            self.n_envs,
            self.device,
            **self.replay_buffer_kwargs,
        )

    def _on_n_envs_changed(self) -> None:
        if self.replay_buffer is not None and self.replay_buffer.size() > 0:
            warnings.warn("n_envs changed: starting a new, empty replay buffer", stacklevel=3)
        self._make_replay_buffer()

    # -- acting ------------------------------------------------------------------------------
    def _greedy(self, obs: Any) -> np.ndarray:
        return self.learner.forward("q", obs).argmax(axis=1) + int(self.action_space.start)

    def _random_actions(self, n: int) -> np.ndarray:
        return self._rng.integers(0, int(self.action_space.n), size=n) + int(
            self.action_space.start
        )

    def _predict(self, observation: Any, deterministic: bool) -> np.ndarray:
        greedy = self._greedy(observation)
        if deterministic:
            return greedy
        explore = self._rng.random(greedy.shape[0]) < self.exploration_rate
        return np.where(explore, self._random_actions(greedy.shape[0]), greedy)

    def _sample_actions(self) -> np.ndarray:
        if self.num_timesteps < self.learning_starts:
            return self._random_actions(self.n_envs)
        explore = self._rng.random(self.n_envs) < self.exploration_rate
        if explore.all():
            return self._random_actions(self.n_envs)
        return np.where(explore, self._random_actions(self.n_envs), self._greedy(self._last_obs))

    # -- learning ----------------------------------------------------------------------------
    def learn(
        self,
        total_timesteps: int,
        callback: Any = None,
        log_interval: int | None = 4,
        tb_log_name: str = "DQN",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> DQN:
        """Collect ``train_freq`` steps (or episodes), then do ``gradient_steps`` updates.

        A callback that stops training ends the loop after its step is fully recorded (the
        transition stored, counters advanced), so a saved model continues exactly."""
        callback = self._setup_learn(
            total_timesteps, callback, reset_num_timesteps, tb_log_name, progress_bar
        )
        callback.on_training_start(self._callback_locals(), {})
        freq, unit = self.train_freq
        running = True
        with self._learning_session():
            while running and self.num_timesteps < self._total_timesteps:
                callback.on_rollout_start()
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
        n_envs = self.n_envs
        actions = self._sample_actions()
        new_obs, rewards, dones, infos = self.env.step(actions)
        self._collected_steps += 1
        running = self._stepped(callback, actions, new_obs, rewards, dones, infos)
        next_obs, timeouts = new_obs, self._no_timeouts  # [n_envs] all False
        if np.count_nonzero(dones):  # dones.any() costs ~3x more per step
            next_obs, timeouts = self._real_next_obs(new_obs, dones, infos)
        self.replay_buffer.add(self._last_obs, next_obs, actions, rewards, dones, timeouts)
        self._last_obs = new_obs
        self._update_progress()
        self._n_calls += 1
        target_every = max(self.target_update_interval // n_envs, 1)  # in env.step calls, as SB3
        if self._n_calls % target_every == 0:
            self.learner.polyak("q_target", self.tau)
        self.exploration_rate = self.exploration_schedule(self._progress_remaining)
        self.logger.record("rollout/exploration_rate", self.exploration_rate)
        for _ in range(int(dones.sum())):
            self._collected_episodes += 1
            self._episode_num += 1
            if log_interval is not None and self._episode_num % log_interval == 0:
                self._dump_logs()
        return running

    def _on_env_reset(self, restart: bool) -> None:
        # The open collection counted steps of the old episodes (which a buffer loaded from
        # a checkpoint may not hold): start a new one.
        self._collected_steps = self._collected_episodes = 0

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

    def train(self, gradient_steps: int, batch_size: int = 100) -> None:
        """``gradient_steps`` Huber-loss updates on uniform replay minibatches."""
        assert self.replay_buffer is not None
        self._update_learning_rate("q")
        start = int(self.action_space.start)
        objective = DQNObjective(self.gamma)
        losses = []
        with self.learner.session():
            for _ in range(gradient_steps):
                obs, actions, next_obs, rewards, terminated = self.replay_buffer.sample_arrays(
                    batch_size, self._rng
                )
                batch = {
                    "observations": obs,
                    "next_observations": next_obs,
                    "actions": actions.reshape(batch_size).astype(np.int64) - start,
                    "rewards": rewards,
                    "terminated": terminated,
                }
                metrics, _ = self.learner.update("q", objective, batch, self.max_grad_norm)
                losses.append(metrics["loss"])
        self._n_updates += gradient_steps
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        self.logger.record("train/loss", float(np.mean(losses)))

    def _dump_logs(self) -> None:
        self.logger.record("time/episodes", self._episode_num, exclude="tensorboard")
        self._record_episode_stats()
        self.logger.dump(step=self.num_timesteps)

    # -- persistence ---------------------------------------------------------------------------
    def _hyperparameters(self) -> dict[str, Any]:
        return {
            "buffer_size": self.buffer_size,
            "learning_starts": self.learning_starts,
            "batch_size": self.batch_size,
            "tau": self.tau,
            "gamma": self.gamma,
            "train_freq": list(self.train_freq),
            "gradient_steps": self.gradient_steps,
            "target_update_interval": self.target_update_interval,
            "exploration_fraction": self.exploration_fraction,
            "exploration_initial_eps": self.exploration_initial_eps,
            "exploration_final_eps": self.exploration_final_eps,
            "max_grad_norm": self.max_grad_norm,
            "verbose": self.verbose,
            "seed": self.seed,
            "stats_window_size": self._stats_window_size,
            "replay_buffer_kwargs": self.replay_buffer_kwargs,
            "optimize_memory_usage": self.optimize_memory_usage,
        }

    def _schedules(self) -> dict[str, Any]:
        return {"learning_rate": self.lr_schedule}

    def save_replay_buffer(self, path: Any) -> None:
        """Write the replay buffer (pickle-free zip, like model files)."""
        assert self.replay_buffer is not None
        meta, arrays = self.replay_buffer.state()
        model_io.write_archive(path, "replay_buffer", meta, arrays)

    def load_replay_buffer(
        self, path: Any, truncate_last_traj: bool = True, max_bytes: int | None = None
    ) -> None:
        """Restore a buffer written by ``save_replay_buffer`` (its n_envs must match).

        A file may hold at most what this model's buffer holds (``max_bytes`` overrides that
        bound): a crafted file cannot make the reader allocate more than the buffer itself."""
        assert self.replay_buffer is not None
        limit = self.replay_buffer.nbytes() + (1 << 20) if max_bytes is None else max_bytes
        meta, arrays = model_io.read_archive(path, "replay_buffer", max_bytes=limit)
        try:
            self.replay_buffer.load_state(meta, arrays)
        except (KeyError, ValueError, TypeError) as exc:
            raise model_io.ModelFileError(
                f"{path}: replay buffer does not fit this model ({exc})"
            ) from exc
