"""PPO (Schulman et al. 2017) with Stable-Baselines3's parameters, defaults and update rules."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import torch

from palaestra.algos.common.on_policy import OnPolicyAlgorithm, default_adam
from palaestra.algos.common.schedules import Schedule, as_schedule
from palaestra.algos.common.settings import Settings
from palaestra.algos.learners.losses import explained_variance
from palaestra.algos.ppo.objective import PPOObjective

__all__ = ["PPO"]


class PPO(OnPolicyAlgorithm):
    """Proximal Policy Optimization with the clipped surrogate: ``PPO("MlpPolicy", env, ...)``.

    As SB3: rollouts of ``n_steps`` per env, GAE, ``n_epochs`` passes of shuffled minibatches,
    per-minibatch advantage normalisation, optional value clipping, entropy bonus, early stop
    when the approximate KL exceeds ``1.5 * target_kl``, truncated episodes bootstrapped with
    the value of their terminal observation. Box actions are sampled from a Gaussian and
    clipped to the bounds only when sent to the env. ``num_threads``: torch CPU threads
    (default 1 for MlpPolicy).
    """

    def __init__(
        self,
        policy: str | type,
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
        self._configure(locals())

    def _take_settings(self, settings: Settings) -> None:
        if settings["rollout_buffer_class"] is not None:
            raise NotImplementedError("rollout_buffer_class is not supported yet")
        if settings["normalize_advantage"] and settings["batch_size"] <= 1:
            raise ValueError(
                "`batch_size` must be greater than 1 when normalize_advantage=True "
                "(see https://github.com/DLR-RM/stable-baselines3/issues/440)"
            )
        clip_range_vf = settings["clip_range_vf"]
        if isinstance(clip_range_vf, (int, float)) and clip_range_vf <= 0:
            raise ValueError(
                "`clip_range_vf` must be positive, pass `None` to deactivate vf clipping"
            )
        self.batch_size, self.n_epochs = settings["batch_size"], settings["n_epochs"]
        self.target_kl = settings["target_kl"]
        self.clip_range = as_schedule(settings["clip_range"])
        self.clip_range_vf = None if clip_range_vf is None else as_schedule(clip_range_vf)
        super()._take_settings(settings)

    def _check_rollout_size(self, stacklevel: int = 3) -> None:
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
                stacklevel=stacklevel,
            )

    def _optimizer_choice(self, kwargs: dict[str, Any]) -> tuple[type, dict[str, Any]]:
        return default_adam(kwargs)

    def learn(
        self,
        total_timesteps: int,
        callback: Any = None,
        log_interval: int | None = 1,
        tb_log_name: str = "PPO",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> PPO:
        """Alternate ``n_steps``-per-env rollouts and ``n_epochs`` of minibatch updates (a
        stopped ``learn`` keeps its partial rollout: see ``OnPolicyAlgorithm._learn``)."""
        self._learn(
            total_timesteps, callback, log_interval, tb_log_name, reset_num_timesteps, progress_bar
        )
        return self

    def train(self) -> None:
        """``n_epochs`` passes of minibatch updates over the current rollout."""
        self._set_training_mode(True)
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
        with self.learner.session():  # one BLAS-thread switch for all epochs
            for epoch in range(self.n_epochs):
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
        if self._head.kind in ("gaussian", "sde"):
            log.record("train/std", float(np.exp(self.learner.extra("log_std")).mean()))
        log.record("train/n_updates", self._n_updates, exclude="tensorboard")
        log.record("train/clip_range", clip_range)
        if clip_range_vf is not None:
            log.record("train/clip_range_vf", clip_range_vf)

    # -- persistence ---------------------------------------------------------------------------
    def _schedules(self) -> dict[str, Any]:
        return {
            "learning_rate": self.lr_schedule,
            "clip_range": self.clip_range,
            "clip_range_vf": self.clip_range_vf,
        }
