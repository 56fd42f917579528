"""SAC's policy classes, at SB3's path (``stable_baselines3.sac.policies``): ``SACPolicy``
and its ``MlpPolicy``/``CnnPolicy``/``MultiInputPolicy`` aliases, the ``Actor`` it builds and
the actor's log-std bounds."""

from __future__ import annotations

from typing import Any

import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.common.continuous_policies import (
    SquashedGaussianActor,
    _ContinuousPolicy,
)
from palaestra.algos.common.networks import (
    BaseFeaturesExtractor,
    CombinedExtractor,
    NatureCNN,
)
from palaestra.algos.learners.heads import LOG_STD_MAX, LOG_STD_MIN

__all__ = [
    "LOG_STD_MAX",
    "LOG_STD_MIN",
    "Actor",
    "CnnPolicy",
    "MlpPolicy",
    "MultiInputPolicy",
    "SACPolicy",
]

Actor = SquashedGaussianActor  # SB3's name for SAC's actor class


class SACPolicy(_ContinuousPolicy):
    """SB3's ``SACPolicy`` (``palaestra.algos.sac.MlpPolicy``): ``actor``, ``critic`` and
    ``critic_target`` (default widths ``[256, 256]``), built by ``make_actor`` and
    ``make_critic``. ``SAC(MyPolicy, env)`` builds it as
    ``MyPolicy(observation_space, action_space, lr_schedule, **policy_kwargs)`` and trains a
    subclass on the torch learner. ``log_std_init``, ``use_expln`` and ``clip_mean`` only
    matter with ``use_sde`` (gSDE), which ``SAC(use_sde=True)`` passes."""

    _frozen = ("critic_target",)
    _not_policy_state = ("ent_coef.",)  # SAC's learned temperature, the algorithm's

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Box,
        lr_schedule: Any = None,
        net_arch: list[int] | dict[str, list[int]] | None = None,
        activation_fn: type[nn.Module] = nn.ReLU,
        use_sde: bool = False,
        log_std_init: float = -3.0,
        use_expln: bool = False,
        clip_mean: float = 2.0,
        features_extractor_class: type[BaseFeaturesExtractor] | None = None,
        features_extractor_kwargs: dict[str, Any] | None = None,
        normalize_images: bool = True,
        optimizer_class: type[torch.optim.Optimizer] = torch.optim.Adam,
        optimizer_kwargs: dict[str, Any] | None = None,
        n_critics: int = 2,
        share_features_extractor: bool = False,
    ) -> None:
        super().__init__(
            observation_space,
            action_space,
            lr_schedule,
            net_arch,
            activation_fn,
            features_extractor_class,
            features_extractor_kwargs,
            normalize_images,
            optimizer_class,
            optimizer_kwargs,
            n_critics,
            share_features_extractor,
        )
        self.log_std_init, self.use_expln, self.clip_mean = log_std_init, use_expln, clip_mean
        self.use_sde = use_sde
        # SB3's order (it sets the parameters a seed gives): actor, critic, critic target.
        self.actor = self.make_actor()
        shared = self.actor.features_extractor if self.share_features_extractor else None
        self.critic = self.make_critic(shared)
        self.critic_target = self.make_critic(None)  # its own extractor, polyak-averaged
        self.critic_target.load_state_dict(self.critic.state_dict())
        self.critic_target.requires_grad_(False)

    def make_actor(
        self, features_extractor: BaseFeaturesExtractor | None = None
    ) -> SquashedGaussianActor:
        """The squashed-Gaussian actor on ``features_extractor`` (None: a new one)."""
        if features_extractor is None:
            features_extractor = self.make_features_extractor()
        return SquashedGaussianActor(
            self.observation_space,
            self.action_dim,
            features_extractor,
            self.actor_arch,
            self.activation_fn,
            self.normalize_images,
            action_space=self.action_space,
            use_sde=self.use_sde,
            log_std_init=self.log_std_init,
            use_expln=self.use_expln,
            clip_mean=self.clip_mean,
        )

    def reset_noise(self, batch_size: int = 1) -> None:
        """New gSDE exploration matrices for the actor (SB3's ``SACPolicy.reset_noise``)."""
        self.actor.reset_noise(batch_size=batch_size)

    def _predict(self, observation: Any, deterministic: bool = False) -> torch.Tensor:
        """The actor's action in ``[-1, 1]`` (SB3's ``SACPolicy._predict``)."""
        return self.actor._predict(observation, deterministic)


MlpPolicy = SACPolicy  # SB3's alias


class CnnPolicy(SACPolicy):
    """``SACPolicy`` with ``NatureCNN`` as its default features extractor (SB3's)."""

    default_features_extractor_class = NatureCNN


class MultiInputPolicy(SACPolicy):
    """``SACPolicy`` with ``CombinedExtractor`` as its default features extractor (SB3's)."""

    default_features_extractor_class = CombinedExtractor
