"""PPO (Schulman et al. 2017) with Stable-Baselines3's parameters, defaults and update rules."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.base import BaseAlgorithm
from palaestra.algos.learners import Group, Net
from palaestra.algos.learners.losses import explained_variance
from palaestra.algos.learners.objectives import PPOObjective
from palaestra.algos.policies import ActorCritic, extractor_class
from palaestra.algos.rollout_buffer import RolloutBuffer
from palaestra.algos.schedules import Schedule, as_schedule

__all__ = ["PPO"]


class PPO(BaseAlgorithm):
    """Proximal Policy Optimization with the clipped surrogate: ``PPO("MlpPolicy", env, ...)``.

    As SB3: rollouts of ``n_steps`` per env, GAE, ``n_epochs`` passes of shuffled minibatches,
    per-minibatch advantage normalisation, optional value clipping, entropy bonus, early stop
    when the approximate KL exceeds ``1.5 * target_kl``, truncated episodes bootstrapped with
    the value of their terminal observation. Box actions are sampled from a Gaussian and
    clipped to the bounds only when sent to the env. ``num_threads``: torch CPU threads
    (default 1 for MlpPolicy).
    """

    supported_action_spaces = (
        spaces.Discrete,
        spaces.Box,
        spaces.MultiDiscrete,
        spaces.MultiBinary,
    )
    _extra_counters: tuple[str, ...] = ()
    policy: ActorCritic

    def __init__(
        self,
        policy: str,
        env: Any,
        learning_rate: float | Schedule = 3e-4,
        n_steps: int = 2048,
        batch_size: int = 64,
        n_epochs: int = 10,
        gamma: float = 0.99,
        gae_lambda: float = 0.95,
        clip_range: float | Schedule = 0.2,
        clip_range_vf: float | Schedule | None = None,
        normalize_advantage: bool = True,
        ent_coef: float = 0.0,
        vf_coef: float = 0.5,
        max_grad_norm: float = 0.5,
        use_sde: bool = False,
        sde_sample_freq: int = -1,
        rollout_buffer_class: None = None,
        rollout_buffer_kwargs: dict[str, Any] | None = None,
        target_kl: float | None = None,
        stats_window_size: int = 100,
        tensorboard_log: str | None = None,
        policy_kwargs: dict[str, Any] | None = None,
        verbose: int = 0,
        seed: int | None = None,
        device: torch.device | str = "auto",
        num_threads: int | None = None,
        _init_setup_model: bool = True,
    ) -> None:
        if use_sde or rollout_buffer_class is not None:
            raise NotImplementedError("use_sde and rollout_buffer_class are not supported yet")
        if normalize_advantage and batch_size <= 1:
            raise ValueError(
                "`batch_size` must be greater than 1 when normalize_advantage=True "
                "(see https://github.com/DLR-RM/stable-baselines3/issues/440)"
            )
        if isinstance(clip_range_vf, (int, float)) and clip_range_vf <= 0:
            raise ValueError(
                "`clip_range_vf` must be positive, pass `None` to deactivate vf clipping"
            )
        self.learning_rate, self.lr_schedule = learning_rate, as_schedule(learning_rate)
        self.n_steps, self.batch_size, self.n_epochs = n_steps, batch_size, n_epochs
        self.gamma, self.gae_lambda = gamma, gae_lambda
        self.clip_range = as_schedule(clip_range)
        self.clip_range_vf = None if clip_range_vf is None else as_schedule(clip_range_vf)
        self.normalize_advantage, self.ent_coef, self.vf_coef = (
            normalize_advantage,
            ent_coef,
            vf_coef,
        )
        self.max_grad_norm, self.target_kl = max_grad_norm, target_kl
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
        if self.env is not None:
            self._check_rollout_size()
        if _init_setup_model:
            if self.env is None:
                raise ValueError("PPO needs an env (an id string, an Env or a VecEnv)")
            self._setup_model()

    def _check_rollout_size(self) -> None:
        size = self.n_steps * self.n_envs
        if size <= 1:
            raise ValueError(
                f"`n_steps * n_envs` must be greater than 1. Currently n_steps="
                f"{self.n_steps} and n_envs={self.n_envs}"
            )
        if size % self.batch_size:
            warnings.warn(
                f"You have specified a mini-batch size of {self.batch_size}, but because "
                f"the rollout buffer is of size `n_steps * n_envs = {size}`, after every "
                f"{size // self.batch_size} untruncated mini-batches, there will be a "
                f"truncated mini-batch of size {size % self.batch_size}",
                stacklevel=3,
            )

    def _setup_model(self) -> None:
        self.set_random_seed(self.seed)
        kwargs = dict(self.policy_kwargs)
        optimizer_class = kwargs.pop("optimizer_class", torch.optim.Adam)
        optimizer_kwargs = dict(kwargs.pop("optimizer_kwargs", None) or {})
        if optimizer_class is torch.optim.Adam:
            optimizer_kwargs.setdefault("eps", 1e-5)  # SB3's ActorCriticPolicy default
        backend = kwargs.pop("backend", "auto")
        kwargs.setdefault("features_extractor_class", extractor_class(self.policy_name))
        policy = ActorCritic(self.observation_space, self.action_space, **kwargs).to(self.device)
        params = list(policy.parameters())
        optimizer = self._make_optimizer(params, optimizer_class, optimizer_kwargs)
        pi_modules, vf_modules, why = policy.mlp_modules()
        head = policy.action_head
        extras = {"log_std": head.log_std} if head.kind == "gaussian" else {}
        if pi_modules is not None and vf_modules is not None:
            # The flat buffer's order (actor, critic, log-std) sets the order in which the
            # gradient norm is summed: kept from the numpy trainer it replaces.
            ordered = [p for m in pi_modules + vf_modules for p in m.parameters()]
            params = list(dict.fromkeys(ordered + list(extras.values()) + params))
        nets = {
            "pi": Net(policy.pi_out, pi_modules, group="policy", why=why),
            "vf": Net(policy.vf_out, vf_modules, group="policy", why=why),
        }
        self._set_learner(
            policy,
            optimizer,
            backend,
            nets,
            {"policy": Group(optimizer, params, extras)},
            joint={("pi", "vf"): policy.pi_and_vf},
        )
        self._head = head
        self._make_rollout_buffer()

    def _make_rollout_buffer(self) -> None:
        self.rollout_buffer = RolloutBuffer(
            self.n_steps,
            self.observation_space,
            self.action_space,
            self.n_envs,
            self.gamma,
            self.gae_lambda,
        )

    def _on_n_envs_changed(self) -> None:
        self._check_rollout_size()
        self._make_rollout_buffer()

    def _sample(self, obs: Any, deterministic: bool) -> tuple[np.ndarray, np.ndarray]:
        """``(actions, log_probs)`` for a batch of raw observations."""
        log_std = self.learner.extra("log_std") if self._head.kind == "gaussian" else None
        return self._head.sample(self.learner.forward("pi", obs), log_std, self._rng, deterministic)

    def _values(self, obs: Any) -> np.ndarray:
        """``V(obs)`` ``[B]``, in chunks (a whole rollout of images may not fit at once)."""
        if isinstance(obs, dict):
            n = len(next(iter(obs.values())))
            chunks = [{k: v[i : i + 8192] for k, v in obs.items()} for i in range(0, n, 8192)]
        else:
            chunks = [obs[i : i + 8192] for i in range(0, len(obs), 8192)]
        with self.learner.session():  # a whole rollout: threads cost more than they save
            out = [self.learner.forward("vf", chunk)[:, 0] for chunk in chunks]
        return out[0] if len(out) == 1 else np.concatenate(out)

    def _predict(self, observation: Any, deterministic: bool) -> np.ndarray:
        return self._sample(observation, deterministic)[0]

    # -- learning ----------------------------------------------------------------------------
    def learn(
        self,
        total_timesteps: int,
        callback: Any = None,
        log_interval: int | None = 1,
        tb_log_name: str = "PPO",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> PPO:
        """Alternate ``n_steps``-per-env rollouts and ``n_epochs`` of minibatch updates.

        A callback that stops training ends the rollout after its step is stored; the partial
        rollout stays in the buffer (and in a saved model), and the next ``learn`` completes it,
        so a stopped and resumed run updates at the same steps as one never stopped."""
        callback = self._setup_learn(
            total_timesteps, callback, reset_num_timesteps, tb_log_name, progress_bar
        )
        callback.on_training_start(self._callback_locals(), {})
        iteration = 0
        with self._learning_session():
            while self.num_timesteps < self._total_timesteps:
                if not self._collect_rollout(callback):
                    break
                iteration += 1
                self._update_progress()
                if log_interval is not None and iteration % log_interval == 0:
                    self.logger.record("time/iterations", iteration, exclude="tensorboard")
                    self._record_episode_stats()
                    self.logger.dump(step=self.num_timesteps)
                self.train()
                self.rollout_buffer.reset()
        callback.on_training_end()
        return self

    def _on_env_reset(self, restart: bool) -> None:
        self.rollout_buffer.reset()  # a partial rollout only continues its own episodes

    def _collect_rollout(self, callback: Any) -> bool:
        """Fill the rest of the rollout buffer; False if a callback asked to stop."""
        env, buf = self.env, self.rollout_buffer
        box = self.action_space if isinstance(self.action_space, spaces.Box) else None
        callback.on_rollout_start()
        # The values of the whole rollout come from one batched forward at its end (the
        # parameters do not change during a rollout): per step, only the policy.
        bits = isinstance(self.action_space, spaces.MultiBinary)
        while not buf.full:
            actions, log_probs = self._sample(self._last_obs, False)
            if bits:
                actions = actions.astype(self.action_space.dtype)  # Bernoulli samples are floats
            env_actions = np.clip(actions, box.low, box.high) if box is not None else actions
            new_obs, rewards, dones, infos = env.step(env_actions)
            running = self._stepped(callback, actions, new_obs, rewards, dones, infos)
            rewards = np.asarray(rewards, dtype=np.float32)
            if np.count_nonzero(dones):  # dones.any() costs ~3x more per step
                rewards = self._bootstrap_truncated(rewards, dones, infos)
            buf.add(
                self._last_obs,
                actions,
                rewards,
                self._last_episode_starts,  # type: ignore[arg-type]
                None,
                log_probs,
            )
            self._last_obs, self._last_episode_starts = new_obs, dones
            if not running:
                return False
        buf.values[...] = self._values(buf.flat_observations()).reshape(buf.values.shape)
        # The last step's dones (also after a resume that found the buffer already full).
        assert self._last_episode_starts is not None
        buf.compute_returns_and_advantage(self._values(self._last_obs), self._last_episode_starts)
        callback.update_locals({"rollout_buffer": buf})
        callback.on_rollout_end()
        return True

    def _bootstrap_truncated(
        self, rewards: np.ndarray, dones: np.ndarray, infos: list[dict[str, Any]]
    ) -> np.ndarray:
        """Add ``gamma * V(terminal_obs)`` where an episode was cut by a time limit (SB3)."""
        idx = [
            i
            for i in np.flatnonzero(dones)
            if infos[i].get("TimeLimit.truncated", False)
            and infos[i].get("terminal_observation") is not None
        ]
        if not idx:
            return rewards
        terminal = [infos[i]["terminal_observation"] for i in idx]
        if isinstance(terminal[0], dict):
            batch: Any = {k: np.stack([t[k] for t in terminal]) for k in terminal[0]}
        else:
            batch = np.stack(terminal)
        rewards = rewards.copy()
        rewards[idx] += self.gamma * self._values(batch)
        return rewards

    def train(self) -> None:
        """``n_epochs`` passes of minibatch updates over the current rollout."""
        self._update_learning_rate("policy")
        clip_range = self.clip_range(self._progress_remaining)
        clip_range_vf = (
            None if self.clip_range_vf is None else self.clip_range_vf(self._progress_remaining)
        )
        kl_limit = None if self.target_kl is None else 1.5 * self.target_kl
        accept = None if kl_limit is None else (lambda m: m["approx_kl"] <= kl_limit)
        objective = PPOObjective(
            self._head,
            clip_range,
            clip_range_vf,
            self.ent_coef,
            self.vf_coef,
            self.normalize_advantage,
        )
        logs: dict[str, list[float]] = {}
        applied = True
        for epoch in range(self.n_epochs):
            with self.learner.session():
                for batch in self.rollout_buffer.minibatch_arrays(self.batch_size, self._rng):
                    batch["actions"] = self._head.index(batch["actions"])
                    metrics, applied = self.learner.update(
                        "policy", objective, batch, self.max_grad_norm, accept
                    )
                    for key, value in metrics.items():
                        logs.setdefault(key, []).append(value)
                    if not applied:
                        break
            self._n_updates += 1
            if not applied:
                if self.verbose >= 1:
                    print(
                        f"Early stopping at step {epoch} due to reaching max kl: "
                        f"{logs['approx_kl'][-1]:.2f}"
                    )
                break
        buf = self.rollout_buffer
        log = self.logger
        log.record("train/entropy_loss", float(np.mean(logs["entropy_loss"])))
        log.record("train/policy_gradient_loss", float(np.mean(logs["policy_loss"])))
        log.record("train/value_loss", float(np.mean(logs["value_loss"])))
        log.record("train/approx_kl", float(np.mean(logs["approx_kl"])))
        log.record("train/clip_fraction", float(np.mean(logs["clip_fraction"])))
        log.record("train/loss", logs["loss"][-1])
        log.record(
            "train/explained_variance", explained_variance(buf.values.ravel(), buf.returns.ravel())
        )
        if self._head.kind == "gaussian":
            log.record("train/std", float(np.exp(self.learner.extra("log_std")).mean()))
        log.record("train/n_updates", self._n_updates, exclude="tensorboard")
        log.record("train/clip_range", clip_range)
        if clip_range_vf is not None:
            log.record("train/clip_range_vf", clip_range_vf)

    # -- persistence ---------------------------------------------------------------------------
    def _hyperparameters(self) -> dict[str, Any]:
        return {
            "n_steps": self.n_steps,
            "batch_size": self.batch_size,
            "n_epochs": self.n_epochs,
            "gamma": self.gamma,
            "gae_lambda": self.gae_lambda,
            "normalize_advantage": self.normalize_advantage,
            "ent_coef": self.ent_coef,
            "vf_coef": self.vf_coef,
            "max_grad_norm": self.max_grad_norm,
            "target_kl": self.target_kl,
            "verbose": self.verbose,
            "seed": self.seed,
            "stats_window_size": self._stats_window_size,
        }

    def _loop_state(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        return self.rollout_buffer.partial_state()

    def _load_loop_state(self, meta: Any, arrays: dict[str, np.ndarray]) -> None:
        self.rollout_buffer.load_partial_state(meta, arrays)

    def _schedules(self) -> dict[str, Any]:
        return {
            "learning_rate": self.lr_schedule,
            "clip_range": self.clip_range,
            "clip_range_vf": self.clip_range_vf,
        }
