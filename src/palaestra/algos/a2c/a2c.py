"""A2C (Mnih et al. 2016, synchronous) with Stable-Baselines3's parameters, defaults and update
rule: short rollouts, one gradient step over the whole rollout, RMSprop."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

from palaestra.algos.a2c.objective import A2CObjective
from palaestra.algos.common.on_policy import OnPolicyAlgorithm, default_adam
from palaestra.algos.common.schedules import Schedule
from palaestra.algos.common.settings import Settings
from palaestra.algos.learners.losses import explained_variance

__all__ = ["A2C"]


class A2C(OnPolicyAlgorithm):
    """Advantage Actor-Critic: ``A2C("MlpPolicy", env, ...)``.

    As SB3: rollouts of ``n_steps`` (5) per env, GAE with ``gae_lambda=1`` (n-step returns
    bootstrapped by the critic), one gradient step per rollout on
    ``-mean(adv * log_prob) + ent_coef * entropy_loss + vf_coef * value_loss`` clipped to
    ``max_grad_norm``, advantages not normalised by default, RMSprop with ``alpha=0.99``,
    ``eps=rms_prop_eps`` (``use_rms_prop=False``: the policy's Adam), truncated episodes
    bootstrapped with the value of their terminal observation. Small MLPs train on the numpy
    learner with a flat RMSprop. ``num_threads``: torch CPU threads (default 1 for MlpPolicy).
    """

    def __init__(
        self,
        policy: str | type,
        env: Any,
        learning_rate: float | Schedule = 7e-4,
        n_steps: int = 5,
        gamma: float = 0.99,
        gae_lambda: float = 1.0,
        ent_coef: float = 0.0,
        vf_coef: float = 0.5,
        max_grad_norm: float = 0.5,
        rms_prop_eps: float = 1e-5,
        use_rms_prop: bool = True,
        use_sde: bool = False,
        sde_sample_freq: int = -1,
        rollout_buffer_class: None = None,
        rollout_buffer_kwargs: dict[str, Any] | None = None,
        normalize_advantage: bool = False,
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
            raise NotImplementedError("A2C does not support rollout_buffer_class yet")
        n_steps, rms_prop_eps = settings["n_steps"], settings["rms_prop_eps"]
        if isinstance(n_steps, bool) or not isinstance(n_steps, (int, np.integer)) or n_steps < 1:
            raise ValueError(f"n_steps must be a positive integer, got {n_steps!r}")
        if not _positive_number(rms_prop_eps):
            raise ValueError(f"rms_prop_eps must be a positive finite number, got {rms_prop_eps!r}")
        for name in ("gamma", "gae_lambda"):
            value = settings[name]
            if not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
                raise ValueError(f"{name} must be a number in [0, 1], got {value!r}")
        self.rms_prop_eps, self.use_rms_prop = rms_prop_eps, settings["use_rms_prop"]
        super()._take_settings(settings)
        self.n_steps = int(n_steps)

    def _check_rollout_size(self, stacklevel: int = 3) -> None:
        if self.normalize_advantage and self.n_steps * self.n_envs <= 1:
            raise ValueError(
                "normalize_advantage=True needs more than one sample per rollout, got "
                f"n_steps * n_envs = {self.n_steps} * {self.n_envs}"
            )

    def _optimizer_choice(self, kwargs: dict[str, Any]) -> tuple[type, dict[str, Any]]:
        if self.use_rms_prop and "optimizer_class" not in kwargs:
            # SB3 replaces the policy's optimizer with these (TF's RMSprop, as in the paper).
            kwargs.pop("optimizer_kwargs", None)
            return torch.optim.RMSprop, {"alpha": 0.99, "eps": self.rms_prop_eps, "weight_decay": 0}
        return default_adam(kwargs)

    def learn(
        self,
        total_timesteps: int,
        callback: Any = None,
        log_interval: int | None = 100,
        tb_log_name: str = "A2C",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> A2C:
        """Alternate ``n_steps``-per-env rollouts and one update over each (a stopped
        ``learn`` keeps its partial rollout: see ``OnPolicyAlgorithm._learn``)."""
        self._learn(
            total_timesteps, callback, log_interval, tb_log_name, reset_num_timesteps, progress_bar
        )
        return self

    def train(self) -> None:
        """One gradient step over the whole rollout."""
        self._set_training_mode(True)
        self._update_learning_rate("policy")
        objective = A2CObjective(self._head, self.ent_coef, self.vf_coef, self.normalize_advantage)
        buf = self.rollout_buffer
        batch = buf.whole_batch()
        batch["actions"] = self._head.index(batch["actions"])
        with self.learner.session():
            metrics, _ = self.learner.update("policy", objective, batch, self.max_grad_norm)
        self._n_updates += 1
        log = self.logger
        log.record("train/n_updates", self._n_updates, exclude="tensorboard")
        log.record(
            "train/explained_variance", explained_variance(buf.values.ravel(), buf.returns.ravel())
        )
        log.record("train/entropy_loss", metrics["entropy_loss"])
        log.record("train/policy_loss", metrics["policy_loss"])
        log.record("train/value_loss", metrics["value_loss"])
        if self._head.kind in ("gaussian", "sde"):
            log.record("train/std", float(np.exp(self.learner.extra("log_std")).mean()))


def _positive_number(value: Any) -> bool:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    return ok and math.isfinite(value) and value > 0
