"""SB3's policy classes of the off-policy algorithms: ``DQNPolicy`` (``q_net`` and
``q_net_target``, from ``make_q_net``), ``SACPolicy`` (``actor``, ``critic``,
``critic_target``) and ``TD3Policy`` (also ``actor_target``; DDPG's too), from ``make_actor``
and ``make_critic``. A subclass overriding those (SB3's custom-policy guide) is passed as an
algorithm's ``policy``; the names users import are ``palaestra.algos.dqn.DQNPolicy``,
``palaestra.algos.sac.SACPolicy``, ``palaestra.algos.td3.TD3Policy`` and their
``MlpPolicy``/``CnnPolicy``/``MultiInputPolicy`` aliases, at SB3's paths.

Each keeps SB3's constructor ``(observation_space, action_space, lr_schedule, **kwargs)`` and
builds its parts in SB3's order (which sets the weights a seed gives). The optimizers stay the
algorithm's, built from ``optimizer_class``/``optimizer_kwargs`` kept here.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.common.continuous_policies import (
    ContinuousCritic,
    DeterministicActor,
    SquashedGaussianActor,
    split_net_arch,
)
from palaestra.algos.common.networks import BaseFeaturesExtractor, FlattenExtractor, make_extractor
from palaestra.algos.common.policies import QNetwork

__all__ = ["DQNPolicy", "SACPolicy", "TD3Policy"]


class DQNPolicy(nn.Module):
    """SB3's ``DQNPolicy`` (``palaestra.algos.dqn.MlpPolicy``): ``q_net`` and its frozen copy
    ``q_net_target``, each built by ``make_q_net()``, which a subclass may override (it must
    return a ``QNetwork``). ``DQN(MyPolicy, env)`` builds it as
    ``MyPolicy(observation_space, action_space, lr_schedule, **policy_kwargs)`` and trains a
    subclass on the torch learner. The optimizer is the algorithm's, built from
    ``optimizer_class``/``optimizer_kwargs`` (SB3's ``policy.optimizer``: ``model.optimizer``).
    """

    # The extractor when ``features_extractor_class`` is not given (CnnPolicy: NatureCNN).
    default_features_extractor_class: type[BaseFeaturesExtractor] = FlattenExtractor

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Discrete,
        lr_schedule: Any = None,
        net_arch: list[int] | None = None,
        activation_fn: type[nn.Module] = nn.ReLU,
        features_extractor_class: type[BaseFeaturesExtractor] | None = None,
        features_extractor_kwargs: dict[str, Any] | None = None,
        normalize_images: bool = True,
        optimizer_class: type[torch.optim.Optimizer] = torch.optim.Adam,
        optimizer_kwargs: dict[str, Any] | None = None,
    ) -> None:
        super().__init__()
        self.observation_space, self.action_space = observation_space, action_space
        self.lr_schedule = lr_schedule
        self.net_arch, self.activation_fn = net_arch, activation_fn
        self.features_extractor_class = (
            features_extractor_class or self.default_features_extractor_class
        )
        self.features_extractor_kwargs = dict(features_extractor_kwargs or {})
        self.normalize_images = normalize_images
        self.optimizer_class, self.optimizer_kwargs = optimizer_class, dict(optimizer_kwargs or {})
        self.q_net: QNetwork = self._checked(self.make_q_net(), "q_net")
        self.q_net_target: QNetwork = self._checked(self.make_q_net(), "q_net_target")
        self.q_net_target.load_state_dict(self.q_net.state_dict())
        self.q_net_target.requires_grad_(False)

    def _checked(self, net: Any, name: str) -> Any:
        if not isinstance(net, nn.Module):  # a subclass's make_q_net
            raise TypeError(
                f"{type(self).__name__}.{name} must be a torch.nn.Module mapping observations "
                f"to Q-values (a QNetwork, from make_q_net), got {type(net).__name__}"
            )
        return net

    def make_q_net(self) -> QNetwork:
        """A new Q-network with its own features extractor."""
        return QNetwork(
            self.observation_space,
            self.action_space,
            self.features_extractor_class,
            self.features_extractor_kwargs,
            self.net_arch,
            self.activation_fn,
            self.normalize_images,
        )

    def forward(self, obs: Any, deterministic: bool = True) -> torch.Tensor:
        """The greedy actions ``[B]`` for a raw observation batch (SB3's ``policy(obs)``)."""
        start = int(getattr(self.action_space, "start", 0))
        return self.q_net(obs).argmax(dim=1) + start


class _ContinuousPolicy(nn.Module):
    """What ``SACPolicy`` and ``TD3Policy`` share: SB3's policy keywords, kept as attributes
    (the algorithm builds its optimizers from ``optimizer_class``/``optimizer_kwargs``), and
    the critic factory."""

    # The extractor when ``features_extractor_class`` is not given (CnnPolicy: NatureCNN).
    default_features_extractor_class: type[BaseFeaturesExtractor] = FlattenExtractor
    default_net_arch: tuple[int, ...] = (256, 256)

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Box,
        lr_schedule: Any,
        net_arch: Any,
        activation_fn: type[nn.Module],
        features_extractor_class: type[BaseFeaturesExtractor] | None,
        features_extractor_kwargs: dict[str, Any] | None,
        normalize_images: bool,
        optimizer_class: type[torch.optim.Optimizer],
        optimizer_kwargs: dict[str, Any] | None,
        n_critics: int,
        share_features_extractor: bool,
    ) -> None:
        super().__init__()
        if not isinstance(action_space, spaces.Box):
            raise TypeError(f"{type(self).__name__} needs a Box action space, got {action_space}")
        self.observation_space, self.action_space = observation_space, action_space
        self.action_dim = int(np.prod(action_space.shape))
        self.lr_schedule, self.net_arch, self.activation_fn = lr_schedule, net_arch, activation_fn
        self.actor_arch, self.critic_arch = split_net_arch(net_arch, list(self.default_net_arch))
        self.features_extractor_class = (
            features_extractor_class or self.default_features_extractor_class
        )
        self.features_extractor_kwargs = dict(features_extractor_kwargs or {})
        self.normalize_images = normalize_images
        self.optimizer_class, self.optimizer_kwargs = optimizer_class, dict(optimizer_kwargs or {})
        self.n_critics, self.share_features_extractor = n_critics, bool(share_features_extractor)

    def make_features_extractor(self) -> BaseFeaturesExtractor:
        """A new features extractor of the policy's class and keywords."""
        return make_extractor(
            self.features_extractor_class, self.observation_space, self.features_extractor_kwargs
        )

    def make_critic(
        self, features_extractor: BaseFeaturesExtractor | None = None
    ) -> ContinuousCritic:
        """``n_critics`` Q-networks on ``features_extractor`` (None: a new one)."""
        if features_extractor is None:
            features_extractor = self.make_features_extractor()
        return ContinuousCritic(
            self.observation_space,
            self.action_dim,
            features_extractor,
            self.critic_arch,
            self.activation_fn,
            n_critics=self.n_critics,
            share_features_extractor=self.share_features_extractor,
            normalize_images=self.normalize_images,
        )


class SACPolicy(_ContinuousPolicy):
    """SB3's ``SACPolicy`` (``palaestra.algos.sac.MlpPolicy``): ``actor``, ``critic`` and
    ``critic_target`` (default widths ``[256, 256]``), built by ``make_actor`` and
    ``make_critic``. ``SAC(MyPolicy, env)`` builds it as
    ``MyPolicy(observation_space, action_space, lr_schedule, **policy_kwargs)`` and trains a
    subclass on the torch learner. ``log_std_init``, ``use_expln`` and ``clip_mean`` only
    matter with ``use_sde``, which is not supported yet."""

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
        if use_sde:
            raise NotImplementedError("use_sde (gSDE) is not supported by palaestra's SAC yet")
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
        )


class TD3Policy(_ContinuousPolicy):
    """SB3's ``TD3Policy`` (``palaestra.algos.td3.MlpPolicy``, DDPG's too): ``actor``,
    ``actor_target``, ``critic`` and ``critic_target`` (default widths ``[400, 300]``), built
    by ``make_actor`` and ``make_critic``; with ``share_features_extractor`` the critic reads
    the actor's extractor and the critic target the actor target's, as in SB3."""

    default_net_arch = (400, 300)

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
        )
