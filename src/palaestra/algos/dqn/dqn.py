"""DQN (Mnih et al. 2015) with Stable-Baselines3's parameters, defaults and update rules."""

from __future__ import annotations

import math
import warnings
from typing import Any, ClassVar

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.common.off_policy import OffPolicyAlgorithm
from palaestra.algos.common.schedules import LinearSchedule, Schedule
from palaestra.algos.common.settings import Settings
from palaestra.algos.dqn.objective import DQNObjective
from palaestra.algos.dqn.policies import CnnPolicy, DQNPolicy, MlpPolicy, MultiInputPolicy, QNetwork
from palaestra.algos.learners import Group, Net

__all__ = ["DQN"]


class DQN(OffPolicyAlgorithm):
    """Deep Q-Network: ``DQN(env, ...)``; arguments as SB3's ``DQN``.

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
    policy_aliases: ClassVar[dict[str, type[torch.nn.Module]]] = {
        "MlpPolicy": MlpPolicy,
        "CnnPolicy": CnnPolicy,
        "MultiInputPolicy": MultiInputPolicy,
    }
    _policy_class_base = DQNPolicy
    # The collection counters make a run stopped mid-collection train at the same steps
    # after a resume as without the stop.
    _extra_counters = ("_n_calls", "exploration_rate", "_collected_steps", "_collected_episodes")

    def __init__(
        self,
        policy: str | type[DQNPolicy],
        env: Any,
        learning_rate: float | Schedule = 1e-4,
        buffer_size: int = 1_000_000,
        learning_starts: int = 100,
        batch_size: int = 32,
        tau: float = 1.0,
        gamma: float = 0.99,
        train_freq: int | tuple[int, str] = 4,
        gradient_steps: int = 1,
        replay_buffer_class: type | str | None = None,
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
        self._configure(locals())

    def _take_settings(self, settings: Settings) -> None:
        self.target_update_interval = settings["target_update_interval"]
        self.exploration_fraction = settings["exploration_fraction"]
        self.exploration_initial_eps = settings["exploration_initial_eps"]
        self.exploration_final_eps = settings["exploration_final_eps"]
        self.max_grad_norm = settings["max_grad_norm"]
        self.exploration_schedule = LinearSchedule(
            self.exploration_initial_eps, self.exploration_final_eps, self.exploration_fraction
        )
        self.exploration_rate = 0.0
        super()._take_settings(settings)
        if self.env is not None and self.n_envs > self.target_update_interval:
            warnings.warn(  # SB3's words, which users' warning filters match
                "The number of environments used is greater than the target network update "
                f"interval ({self.n_envs} > {self.target_update_interval}), therefore the target "
                "network will be updated after each call to env.step() which corresponds to "
                f"{self.n_envs} steps.",
                stacklevel=4,  # the user's DQN(...): __init__, _configure, here
            )

    def _setup_model(self) -> None:
        if not isinstance(self.action_space, spaces.Discrete):
            raise TypeError(f"DQN only supports Discrete action spaces, got {self.action_space}")
        self.set_random_seed(self.seed)
        # SB3's DQNPolicy does not take it; palaestra always let it through (and ignores it).
        kwargs = {k: v for k, v in self.policy_kwargs.items() if k != "share_features_extractor"}
        self._use_policy(self._build_policy(kwargs))
        self._make_replay_buffer()

    def _use_policy(self, policy: Any) -> None:
        q_net, q_net_target = policy.q_net, policy.q_net_target
        params = list(q_net.parameters())
        optimizer = self._make_optimizer(params, policy.optimizer_class, policy.optimizer_kwargs)
        custom = self._custom_policy(policy)
        modules, why = (None, custom) if custom else q_net.mlp_modules()
        target_modules = None if custom else q_net_target.mlp_modules()[0]
        nets = {
            "q": Net(q_net, modules, group="q", why=why),
            "q_target": Net(q_net_target, target_modules, target_of="q", why=why),
        }
        backend = self.policy_kwargs.get("backend", "auto")
        self._set_learner(policy, optimizer, backend, nets, {"q": Group(optimizer, params)})

    # SB3's attributes; reading them hands the parameters to torch, as ``policy`` does.
    @property
    def q_net(self) -> QNetwork:
        return self.policy.q_net

    @property
    def q_net_target(self) -> QNetwork:
        return self.policy.q_net_target

    # -- acting ------------------------------------------------------------------------------
    def _greedy(self, obs: Any) -> np.ndarray:
        greedy = self.learner.forward("q", obs).argmax(axis=1)
        start = int(self.action_space.start)
        return greedy + start if start else greedy  # argmax's int64 array as it is for 0

    def _random_actions(self, n: int) -> np.ndarray:
        high = int(self.action_space.n)
        if n == 1:  # a scalar draw: the same number from the stream, in a fifth of the time
            return np.array([self._rng.integers(0, high) + int(self.action_space.start)])
        return self._rng.integers(0, high, size=n) + int(self.action_space.start)

    def _predict(self, observation: Any, deterministic: bool) -> np.ndarray:
        greedy = self._greedy(observation)
        if deterministic:
            return greedy
        explore = self._rng.random(greedy.shape[0]) < self.exploration_rate
        return np.where(explore, self._random_actions(greedy.shape[0]), greedy)

    def _sample_actions(self) -> tuple[np.ndarray, np.ndarray]:
        actions = self._explore()
        return actions, actions

    def _explore(self) -> np.ndarray:
        if self.num_timesteps < self.learning_starts:
            return self._random_actions(self.n_envs)
        if self.n_envs == 1:  # scalar draws, the same numbers as the [1] arrays below
            if self._rng.random() < self.exploration_rate:
                return self._random_actions(1)
            # The random action is drawn either way, as below; unused, it needs no array.
            self._rng.integers(0, int(self.action_space.n))
            return self._greedy(self._last_obs)
        explore = self._rng.random(self.n_envs) < self.exploration_rate
        if explore.all():
            return self._random_actions(self.n_envs)
        return np.where(explore, self._random_actions(self.n_envs), self._greedy(self._last_obs))

    def _on_step(self) -> None:
        target_every = max(self.target_update_interval // self.n_envs, 1)  # env.step calls (SB3)
        if self._n_calls % target_every == 0:
            self.learner.polyak("q_target", self.tau)
        self.exploration_rate = self.exploration_schedule(self._progress_remaining)
        self.logger.record("rollout/exploration_rate", self.exploration_rate)

    def _objective(self) -> Any:
        """The loss and its VJP the updates run (DQN's Huber TD loss)."""
        return DQNObjective(self.gamma)

    def _fixed_batch(self, batch_size: int) -> dict[str, np.ndarray]:
        """Arrays every minibatch adds for the objective (none for DQN)."""
        return {}

    def train(self, gradient_steps: int, batch_size: int = 100) -> None:
        """``gradient_steps`` updates of ``_objective()`` on uniform replay minibatches."""
        assert self.replay_buffer is not None
        self._set_training_mode(True)
        self._update_learning_rate("q")
        start = int(self.action_space.start)
        objective = self._objective()
        fixed = self._fixed_batch(batch_size)
        clip = math.inf if self.max_grad_norm is None else self.max_grad_norm
        losses = []
        with self.learner.session():
            for _ in range(gradient_steps):
                batch = fixed | self._sample_batch(batch_size)
                actions = batch["actions"].reshape(batch_size).astype(np.int64)
                batch["actions"] = actions - start if start else actions
                metrics, _ = self.learner.update("q", objective, batch, clip)
                losses.append(metrics["loss"])
        self._n_updates += gradient_steps
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        # One update per call at most settings: its loss is the mean (np.mean's float64 sum
        # of one float is that float), without np.mean's ~7 µs of Python.
        self.logger.record("train/loss", losses[0] if len(losses) == 1 else float(np.mean(losses)))
