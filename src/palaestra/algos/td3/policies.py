"""TD3's policy classes, at SB3's path (``stable_baselines3.td3.policies``): ``TD3Policy``
and its ``MlpPolicy``/``CnnPolicy``/``MultiInputPolicy`` aliases."""

from __future__ import annotations

from typing import Any

import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.common.continuous_policies import (
    DeterministicActor,
    _ContinuousPolicy,
)
from palaestra.algos.common.networks import (
    BaseFeaturesExtractor,
    CombinedExtractor,
    NatureCNN,
)

__all__ = ["Actor", "CnnPolicy", "MlpPolicy", "MultiInputPolicy", "TD3Policy"]

Actor = DeterministicActor  # SB3's name for TD3's (and DDPG's) actor class


class TD3Policy(_ContinuousPolicy):
    """SB3's ``TD3Policy`` (``palaestra.algos.td3.MlpPolicy``, DDPG's too): ``actor``,
    ``actor_target``, ``critic`` and ``critic_target`` (default widths ``[400, 300]``), built
    by ``make_actor`` and ``make_critic``; with ``share_features_extractor`` the critic reads
    the actor's extractor and the critic target the actor target's, as in SB3."""

    default_net_arch = (400, 300)
    _frozen = ("actor_target", "critic_target")

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Box,
        lr_schedule: Any = None,
        net_arch: list[int] | dict[str, list[int]] | None = None,
        activation_fn: type[nn.Module] = nn.ReLU,
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
        self.actor = self.make_actor()
        self.actor_target = self.make_actor()
        self.actor_target.load_state_dict(self.actor.state_dict())
        share = self.share_features_extractor
        self.critic = self.make_critic(self.actor.features_extractor if share else None)
        self.critic_target = self.make_critic(
            self.actor_target.features_extractor if share else None
        )
        self.critic_target.load_state_dict(self.critic.state_dict())
        for frozen in (self.actor_target, self.critic_target):
            frozen.requires_grad_(False)

    def make_actor(
        self, features_extractor: BaseFeaturesExtractor | None = None
    ) -> DeterministicActor:
        """The deterministic tanh actor on ``features_extractor`` (None: a new one)."""
        if features_extractor is None:
            features_extractor = self.make_features_extractor()
        return DeterministicActor(
            self.observation_space,
            self.action_dim,
            features_extractor,
            self.actor_arch,
            self.activation_fn,
            self.normalize_images,
            action_space=self.action_space,
        )

    def _predict(self, observation: Any, deterministic: bool = False) -> torch.Tensor:
        """The actor's action in ``[-1, 1]`` (deterministic either way: exploration noise is
        the algorithm's, as in SB3)."""
        return self.actor(observation)


MlpPolicy = TD3Policy  # SB3's alias (DDPG's policies are TD3's, as in SB3)


class CnnPolicy(TD3Policy):
    """``TD3Policy`` with ``NatureCNN`` as its default features extractor (SB3's)."""

    default_features_extractor_class = NatureCNN


class MultiInputPolicy(TD3Policy):
    """``TD3Policy`` with ``CombinedExtractor`` as its default features extractor (SB3's)."""

    default_features_extractor_class = CombinedExtractor
