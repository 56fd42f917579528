"""TD3 (Fujimoto et al. 2018) and DDPG (Lillicrap et al. 2016, as SB3 defines it: TD3 with one
critic, no target smoothing and no delay) with Stable-Baselines3's parameters and defaults."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import torch

from palaestra.algos.common.continuous_policies import ContinuousCritic, DeterministicActor
from palaestra.algos.common.off_policy_actor_critic import ActorCriticOffPolicy
from palaestra.algos.common.policies import _numpy_input_problem
from palaestra.algos.common.schedules import Schedule
from palaestra.algos.common.settings import Settings
from palaestra.algos.learners import Group, Net
from palaestra.algos.td3.objective import TD3ActorObjective, TD3CriticObjective
from palaestra.algos.td3.policies import CnnPolicy, MlpPolicy, MultiInputPolicy, TD3Policy

__all__ = ["TD3"]


class TD3(ActorCriticOffPolicy):
    """Twin Delayed DDPG: ``TD3(env, ...)``; arguments as SB3's ``TD3``.

    Kept from SB3: a deterministic tanh actor, twin critics regressed on the minimum of the
    target critics at the target actor's action plus clipped Gaussian noise
    (``target_policy_noise``, ``target_noise_clip``), the actor and the targets updated every
    ``policy_delay`` critic updates (polyak with ``tau``), uniform actions before
    ``learning_starts``, exploration only through ``action_noise``. Changed: noise is drawn
    from the model's generator (same seed, same run, on either learner).
    """

    policy_aliases: ClassVar[dict[str, type[torch.nn.Module]]] = {
        "MlpPolicy": MlpPolicy,
        "CnnPolicy": CnnPolicy,
        "MultiInputPolicy": MultiInputPolicy,
    }
    _policy_class_base = TD3Policy

    def __init__(
        self,
        policy: str | type[TD3Policy],
        env: Any,
        learning_rate: float | Schedule = 1e-3,
        buffer_size: int = 1_000_000,
        learning_starts: int = 100,
        batch_size: int = 256,
        tau: float = 0.005,
        gamma: float = 0.99,
        train_freq: int | tuple[int, str] = 1,
        gradient_steps: int = 1,
        action_noise: Any = None,
        replay_buffer_class: type | str | None = None,
        replay_buffer_kwargs: dict[str, Any] | None = None,
        optimize_memory_usage: bool = False,
        n_steps: int = 1,
        policy_delay: int = 2,
        target_policy_noise: float = 0.2,
        target_noise_clip: float = 0.5,
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
        policy_delay = settings["policy_delay"]
        if isinstance(policy_delay, bool) or not isinstance(policy_delay, int) or policy_delay < 1:
            raise ValueError(f"policy_delay must be a positive int, got {policy_delay!r}")
        for name in ("target_policy_noise", "target_noise_clip"):
            value = settings[name]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0:
                raise ValueError(f"{name} must be a number >= 0, got {value!r}")
        self.policy_delay = policy_delay
        self.target_policy_noise = settings["target_policy_noise"]
        self.target_noise_clip = settings["target_noise_clip"]
        super()._take_settings(settings)

    def _setup_model(self) -> None:
        self._check_action_space()
        self.set_random_seed(self.seed)
        self._use_policy(self._make_policy(**self._policy_parts))
        self._make_replay_buffer()

    _policy_parts = dict(
        actor=DeterministicActor,
        actor_target=DeterministicActor,
        critic=ContinuousCritic,
        critic_target=ContinuousCritic,
    )

    def _use_policy(self, policy: Any) -> None:
        self._check_parts(policy, self._policy_parts)
        actor, actor_target = policy.actor, policy.actor_target
        critic, critic_target = policy.critic, policy.critic_target
        why = self._custom_policy(policy) or _numpy_input_problem(
            self.observation_space, actor.features_extractor, actor.normalize_images
        )
        nets = {
            "actor": Net(
                actor, None if why else [actor.features_extractor, actor.mu], group="actor", why=why
            ),
            "actor_target": Net(
                actor_target,
                None if why else [actor_target.features_extractor, actor_target.mu],
                target_of="actor",
                why=why,
            ),
        }
        critic_nets, critic_params = self._critic_nets(critic, critic_target, policy)
        nets.update(critic_nets)
        actor_params = list(actor.parameters())
        groups = {
            "actor": Group(self._make_optimizer_for(actor_params, policy), actor_params),
            "critic": Group(self._make_optimizer_for(critic_params, policy), critic_params),
        }
        self._set_learner(
            policy,
            groups["actor"].optimizer,
            self.policy_kwargs.get("backend", "auto"),
            nets,
            groups,
        )

    @property
    def actor(self) -> DeterministicActor:
        return self.policy.actor

    @property
    def actor_target(self) -> DeterministicActor:
        return self.policy.actor_target

    @property
    def critic(self) -> Any:
        return self.policy.critic

    @property
    def critic_target(self) -> Any:
        return self.policy.critic_target

    # -- acting ------------------------------------------------------------------------------
    def _policy_actions(self, obs: Any, deterministic: bool) -> np.ndarray:
        return self.learner.forward("actor", obs)  # exploration: action_noise only

    # -- learning ----------------------------------------------------------------------------
    def train(self, gradient_steps: int, batch_size: int = 100) -> None:
        """Critic updates every step; actor and target updates every ``policy_delay``."""
        self._set_training_mode(True)
        for group in ("actor", "critic"):
            self._update_learning_rate(group)
        critic = TD3CriticObjective(self._n_critics, self.gamma)
        actor = TD3ActorObjective(self.action_dim)
        actor_losses, critic_losses = [], []
        with self.learner.session():
            for _ in range(gradient_steps):
                self._n_updates += 1
                batch = self._sample_batch(batch_size)
                noise = self._rng.normal(0.0, self.target_policy_noise, batch["actions"].shape)
                clip = self.target_noise_clip
                batch["target_noise"] = np.clip(noise, -clip, clip).astype(np.float32)
                critic_losses.append(self.learner.update("critic", critic, batch)[0]["critic_loss"])
                if self._n_updates % self.policy_delay == 0:
                    metrics, _ = self.learner.update("actor", actor, batch)
                    actor_losses.append(metrics["actor_loss"])
                    self._polyak_critics()
                    self.learner.polyak("actor_target", self.tau)
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        if actor_losses:
            self.logger.record("train/actor_loss", float(np.mean(actor_losses)))
        self.logger.record("train/critic_loss", float(np.mean(critic_losses)))
