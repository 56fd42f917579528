"""The networks of SAC, TD3 and DDPG with Stable-Baselines3's layout and defaults: an actor
(SAC: a ReLU MLP with ``mu`` and ``log_std`` heads for a tanh-squashed Gaussian; TD3/DDPG: an
MLP ending in tanh) and ``n_critics`` Q-networks on ``[features, action]``, each with its own
features extractor unless ``share_features_extractor`` (then the critics read the actor's,
without training it, as SB3 does). Actions inside these networks live in ``[-1, 1]``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.common.base_policy import BasePolicy
from palaestra.algos.common.distributions import (
    Distribution,
    SquashedDiagGaussianDistribution,
    StateDependentNoiseDistribution,
)
from palaestra.algos.common.networks import (
    BaseFeaturesExtractor,
    FlattenExtractor,
    make_extractor,
    mlp,
    preprocess_obs,
)
from palaestra.algos.learners.heads import squashed_gaussian_rsample
from palaestra.algos.learners.xp import torch_ops

__all__ = ["ContinuousCritic", "DeterministicActor", "SquashedGaussianActor", "split_net_arch"]


def split_net_arch(net_arch: Any, default: list[int]) -> tuple[list[int], list[int]]:
    """A list (both) or ``dict(pi=[...], qf=[...])`` -> ``(actor, critic)`` widths."""
    if net_arch is None:
        return list(default), list(default)
    if isinstance(net_arch, dict) and set(net_arch) <= {"pi", "qf"}:
        return list(net_arch.get("pi", [])), list(net_arch.get("qf", []))
    if isinstance(net_arch, (list, tuple)) and all(
        isinstance(w, int) and not isinstance(w, bool) and w > 0 for w in net_arch
    ):
        return list(net_arch), list(net_arch)
    raise ValueError(
        f"net_arch must be a list of positive ints or dict(pi=[...], qf=[...]), got {net_arch!r}"
    )


class _Extracting(nn.Module):
    def __init__(
        self,
        observation_space: spaces.Space[Any],
        extractor: BaseFeaturesExtractor,
        normalize_images: bool,
    ) -> None:
        super().__init__()
        self.observation_space, self.normalize_images = observation_space, normalize_images
        self.features_extractor = extractor

    def features(self, obs: Any) -> torch.Tensor:
        x = preprocess_obs(obs, self.observation_space, self.normalize_images)
        return self.features_extractor(x)


class _Actor(_Extracting, BasePolicy):
    """What SB3's SAC and TD3 ``Actor`` (a ``BasePolicy``) offer on their own: ``predict``
    (actions mapped from [-1, 1] to ``action_space``'s bounds), ``device``,
    ``set_training_mode``, ``obs_to_tensor``. A policy file holds the whole policy."""

    squash_output = True

    def _set_action_space(self, action_dim: int, action_space: spaces.Box | None) -> None:
        # None: the actor's own [-1, 1] (an actor built outside a policy)
        self.action_space = action_space or spaces.Box(-1.0, 1.0, (action_dim,), np.float32)

    def save(self, path: Any) -> None:
        """Not offered: save the policy (``model.policy.save(path)``), which holds the actor."""
        raise NotImplementedError(
            f"{type(self).__name__}.save: palaestra saves whole policies; use "
            "model.policy.save(path) and load it with its policy class's load (the actor is "
            "its .actor)"
        )


class SquashedGaussianActor(_Actor):
    """SAC's actor: ``latent_pi`` then ``mu`` and ``log_std`` (clipped later to [-20, 2]).

    With ``use_sde`` (gSDE, SB3's layout): ``mu`` (followed by ``Hardtanh(-clip_mean,
    clip_mean)`` when ``clip_mean > 0``) and a ``log_std`` parameter ``[latent, action_dim]``
    of the exploration weights; ``action_dist`` is the ``StateDependentNoiseDistribution``
    with the features learned and tanh on top, holding the exploration matrices."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_dim: int,
        extractor: BaseFeaturesExtractor,
        net_arch: list[int],
        activation_fn: type[nn.Module],
        normalize_images: bool = True,
        action_space: spaces.Box | None = None,
        use_sde: bool = False,
        log_std_init: float = -3.0,
        full_std: bool = True,
        use_expln: bool = False,
        clip_mean: float = 2.0,
    ) -> None:
        super().__init__(observation_space, extractor, normalize_images)
        self._set_action_space(action_dim, action_space)
        self.latent_pi = mlp(extractor.features_dim, net_arch, activation_fn)
        last = net_arch[-1] if net_arch else extractor.features_dim
        self.use_sde, self.use_expln, self.clip_mean = use_sde, use_expln, clip_mean
        self.full_std = full_std
        self.action_dist: Distribution
        self.mu: nn.Module
        self.log_std: nn.Module | nn.Parameter  # a layer, or gSDE's weights' log-std
        if use_sde:
            self.action_dist = StateDependentNoiseDistribution(
                action_dim, full_std, use_expln, squash_output=True, learn_features=True
            )
            self.mu, self.log_std = self.action_dist.proba_distribution_net(
                last, log_std_init, latent_sde_dim=last
            )
            if clip_mean > 0.0:  # SB3: keeps the Gaussian's mean inside tanh's useful range
                self.mu = nn.Sequential(self.mu, nn.Hardtanh(-clip_mean, clip_mean))
            return
        self.action_dist = SquashedDiagGaussianDistribution(action_dim)
        self.mu = nn.Linear(last, action_dim)
        self.log_std = nn.Linear(last, action_dim)

    def mean_layer(self) -> nn.Linear:
        """The mean's linear layer (without gSDE's clip, which the losses apply)."""
        mu = self.mu
        return mu[0] if isinstance(mu, nn.Sequential) else mu  # type: ignore[return-value]

    def reset_noise(self, batch_size: int = 1) -> None:
        """New gSDE exploration matrices from torch's generator (SB3's ``reset_noise``)."""
        if not isinstance(self.action_dist, StateDependentNoiseDistribution):
            raise ValueError("reset_noise() is only available when using gSDE")
        assert isinstance(self.log_std, nn.Parameter)
        self.action_dist.sample_weights(self.log_std, batch_size=batch_size)

    def latent(self, obs: Any) -> torch.Tensor:
        return self.latent_pi(self.features(obs))

    def forward(self, obs: Any, deterministic: bool = False) -> torch.Tensor:
        """The action in ``[-1, 1]`` for a batch of observation tensors (SB3's
        ``Actor.forward``: a sample, or the mean's tanh when ``deterministic``)."""
        return self._predict(obs, deterministic)

    def get_std(self) -> torch.Tensor:
        """gSDE's exploration std ``[latent, action_dim]`` (SB3's ``Actor.get_std``)."""
        if not isinstance(self.action_dist, StateDependentNoiseDistribution):
            raise ValueError("get_std() is only available when using gSDE (use_sde=True)")
        assert isinstance(self.log_std, nn.Parameter)
        return self.action_dist.get_std(self.log_std)

    def _predict(self, observation: Any, deterministic: bool = False) -> torch.Tensor:
        """``tanh`` of the Gaussian's mean, or of a sample (log-std clipped as in training)."""
        latent = self.latent(observation)
        mean = self.mu(latent)
        if deterministic:
            return torch.tanh(mean)
        if isinstance(self.action_dist, StateDependentNoiseDistribution):
            return torch.tanh(mean + self.action_dist.get_noise(latent))
        assert isinstance(self.log_std, nn.Module)
        log_std = self.log_std(latent)
        return squashed_gaussian_rsample(torch_ops, mean, log_std, torch.randn_like(mean))[0]


class DeterministicActor(_Actor):
    """TD3's and DDPG's actor: an MLP from the features to the action, tanh at the end."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_dim: int,
        extractor: BaseFeaturesExtractor,
        net_arch: list[int],
        activation_fn: type[nn.Module],
        normalize_images: bool = True,
        action_space: spaces.Box | None = None,
    ) -> None:
        super().__init__(observation_space, extractor, normalize_images)
        self._set_action_space(action_dim, action_space)
        body = mlp(extractor.features_dim, net_arch, activation_fn)
        last = net_arch[-1] if net_arch else extractor.features_dim
        self.mu = nn.Sequential(*body, nn.Linear(last, action_dim), nn.Tanh())

    def forward(self, obs: Any) -> torch.Tensor:
        return self.mu(self.features(obs))

    def _predict(self, observation: Any, deterministic: bool = False) -> torch.Tensor:
        """The action in ``[-1, 1]`` (exploration noise is the algorithm's, as in SB3)."""
        return self(observation)


class ContinuousCritic(_Extracting):
    """``n_critics`` Q-networks ``qf{i}: [features, action] -> Q``."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_dim: int,
        extractor: BaseFeaturesExtractor,
        net_arch: list[int],
        activation_fn: type[nn.Module],
        n_critics: int = 2,
        share_features_extractor: bool = False,
        normalize_images: bool = True,
    ) -> None:
        super().__init__(observation_space, extractor, normalize_images)
        if isinstance(n_critics, bool) or not isinstance(n_critics, int) or n_critics < 1:
            raise ValueError(f"n_critics must be a positive int, got {n_critics!r}")
        self.share_features_extractor = share_features_extractor
        dim = extractor.features_dim + action_dim
        last = net_arch[-1] if net_arch else dim
        # Registered as qf0, qf1, ... (SB3's state_dict keys); the list is for indexing.
        self.q_networks: list[nn.Sequential] = []
        for i in range(n_critics):
            q_net = nn.Sequential(*mlp(dim, net_arch, activation_fn), nn.Linear(last, 1))
            self.add_module(f"qf{i}", q_net)
            self.q_networks.append(q_net)

    def q(self, index: int, obs_action: tuple[Any, Any]) -> torch.Tensor:
        """``Q_index(obs, action)`` ``[B, 1]``."""
        obs, action = obs_action
        with torch.set_grad_enabled(torch.is_grad_enabled() and not self.share_features_extractor):
            features = self.features(obs)
        # The replay buffer keeps a float64 Box's actions as float64: the critic's dtype here
        # (SB3 stores them as float32, ReplayBuffer._maybe_cast_dtype)
        action = action.to(features.dtype)
        return self.q_networks[index](torch.cat([features.flatten(1), action], dim=1))

    def forward(self, obs: Any, actions: torch.Tensor) -> tuple[torch.Tensor, ...]:
        """Every critic's ``Q(obs, actions)`` ``[B, 1]`` (SB3's ``ContinuousCritic.forward``)."""
        return tuple(self.q(i, (obs, actions)) for i in range(len(self.q_networks)))

    def q1_forward(self, obs: Any, actions: torch.Tensor) -> torch.Tensor:
        """The first critic's ``Q(obs, actions)`` (SB3's, for TD3's actor loss)."""
        return self.q(0, (obs, actions))

    def flat_input(self) -> bool:
        """Whether ``[flattened obs, action]`` is this critic's MLP input (numpy learner)."""
        return isinstance(self.features_extractor, FlattenExtractor)


class _ContinuousPolicy(BasePolicy):
    """What ``SACPolicy`` and ``TD3Policy`` share: SB3's policy keywords, kept as attributes
    (the algorithm builds its optimizers from ``optimizer_class``/``optimizer_kwargs``), and
    the critic factory. The actor acts in ``[-1, 1]``; ``predict`` maps to the bounds."""

    squash_output = True

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
            self.features_extractor_class,
            self.observation_space,
            self.features_extractor_kwargs,
            self.normalize_images,
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
