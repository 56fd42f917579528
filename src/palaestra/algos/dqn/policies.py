"""DQN's policy classes, at SB3's path (``stable_baselines3.dqn.policies``): ``DQNPolicy``
and its ``MlpPolicy``/``CnnPolicy``/``MultiInputPolicy`` aliases."""

from __future__ import annotations

from typing import Any

import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.common.base_policy import BasePolicy
from palaestra.algos.common.networks import (
    BaseFeaturesExtractor,
    CombinedExtractor,
    FlattenExtractor,
    NatureCNN,
    make_extractor,
    mlp,
    preprocess_obs,
)
from palaestra.algos.common.policies import _numpy_input_problem

__all__ = ["CnnPolicy", "DQNPolicy", "MlpPolicy", "MultiInputPolicy", "QNetwork"]


class QNetwork(nn.Module):
    """``obs -> Q(obs, .)``: features extractor, MLP (SB3 default ``[64, 64]`` ReLU; none after
    NatureCNN), linear head. ``forward`` takes raw observation tensors."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Discrete,
        features_extractor_class: type[BaseFeaturesExtractor] = FlattenExtractor,
        features_extractor_kwargs: dict[str, Any] | None = None,
        net_arch: list[int] | None = None,
        activation_fn: type[nn.Module] = nn.ReLU,
        normalize_images: bool = True,
    ) -> None:
        super().__init__()
        self.observation_space, self.normalize_images = observation_space, normalize_images
        self.features_extractor = make_extractor(
            features_extractor_class, observation_space, features_extractor_kwargs, normalize_images
        )
        if net_arch is None:
            net_arch = [] if features_extractor_class is NatureCNN else [64, 64]
        self.mlp = mlp(self.features_extractor.features_dim, list(net_arch), activation_fn)
        last = net_arch[-1] if net_arch else self.features_extractor.features_dim
        self.head = nn.Linear(last, int(action_space.n))

    def forward(self, obs: Any) -> torch.Tensor:
        x = preprocess_obs(obs, self.observation_space, self.normalize_images)
        return self.head(self.mlp(self.features_extractor(x)))

    def mlp_modules(self) -> tuple[list[nn.Module] | None, str]:
        """The modules the numpy learner reads as an MLP (None, and why, where the input is not
        the raw observation as a float vector)."""
        why = _numpy_input_problem(
            self.observation_space, self.features_extractor, self.normalize_images
        )
        return (None, why) if why else ([self.features_extractor, self.mlp, self.head], "")


class DQNPolicy(BasePolicy):
    """SB3's ``DQNPolicy`` (``palaestra.algos.dqn.MlpPolicy``): ``q_net`` and its frozen copy
    ``q_net_target``, each built by ``make_q_net()``, which a subclass may override (it must
    return a ``QNetwork``). ``DQN(MyPolicy, env)`` builds it as
    ``MyPolicy(observation_space, action_space, lr_schedule, **policy_kwargs)`` and trains a
    subclass on the torch learner. The optimizer is the algorithm's, built from
    ``optimizer_class``/``optimizer_kwargs`` (SB3's ``policy.optimizer``: ``model.optimizer``).
    """

    # The extractor when ``features_extractor_class`` is not given (CnnPolicy: NatureCNN).
    default_features_extractor_class: type[BaseFeaturesExtractor] = FlattenExtractor
    _frozen = ("q_net_target",)

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

    def _predict(self, observation: Any, deterministic: bool = True) -> torch.Tensor:
        """Greedy actions whatever ``deterministic`` says: epsilon-greedy exploration is the
        algorithm's (``DQN.predict``), as in SB3."""
        return self(observation)


MlpPolicy = DQNPolicy  # SB3's alias


class CnnPolicy(DQNPolicy):
    """``DQNPolicy`` with ``NatureCNN`` as its default features extractor (SB3's)."""

    default_features_extractor_class = NatureCNN


class MultiInputPolicy(DQNPolicy):
    """``DQNPolicy`` with ``CombinedExtractor`` as its default features extractor (SB3's)."""

    default_features_extractor_class = CombinedExtractor
