"""QR-DQN's policy classes, at sb3-contrib's path (``sb3_contrib.qrdqn.policies``):
``QuantileNetwork``, ``QRDQNPolicy`` and its ``MlpPolicy``/``CnnPolicy``/``MultiInputPolicy``
aliases, with sb3-contrib's constructor parameters and defaults.

A quantile network is DQN's Q-network with ``n_quantiles`` outputs per action: the MLP's last
layer has ``n_quantiles * n_actions`` units, read as ``[n_quantiles, n_actions]`` (quantile
major, as sb3-contrib's ``view``), and an action's value is the mean of its quantiles.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.common import networks
from palaestra.algos.common.networks import (
    BaseFeaturesExtractor,
    CombinedExtractor,
    FlattenExtractor,
    NatureCNN,
)
from palaestra.algos.common.policies import _numpy_input_problem
from palaestra.algos.dqn.policies import DQNPolicy

__all__ = ["CnnPolicy", "MlpPolicy", "MultiInputPolicy", "QRDQNPolicy", "QuantileNetwork"]


class QuantileNetwork(nn.Module):
    """``obs -> quantiles [B, n_quantiles, n_actions]``: the given features extractor, then
    ``quantile_net``, an MLP (``net_arch``, default ``[64, 64]``) ending in a linear layer of
    ``n_quantiles * n_actions`` units. ``forward`` takes raw observation tensors."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Discrete,
        features_extractor: BaseFeaturesExtractor,
        features_dim: int,
        n_quantiles: int = 200,
        net_arch: list[int] | None = None,
        activation_fn: type[nn.Module] = nn.ReLU,
        normalize_images: bool = True,
    ) -> None:
        super().__init__()
        if isinstance(n_quantiles, bool) or not isinstance(n_quantiles, int) or n_quantiles < 1:
            raise ValueError(f"n_quantiles must be a positive int, got {n_quantiles!r}")
        self.observation_space, self.action_space = observation_space, action_space
        self.features_extractor, self.features_dim = features_extractor, features_dim
        self.n_quantiles, self.normalize_images = n_quantiles, normalize_images
        self.net_arch = [64, 64] if net_arch is None else list(net_arch)
        self.activation_fn = activation_fn
        last = self.net_arch[-1] if self.net_arch else features_dim
        head = nn.Linear(last, n_quantiles * int(action_space.n))
        self.quantile_net = nn.Sequential(
            *networks.mlp(features_dim, self.net_arch, activation_fn), head
        )

    def forward(self, obs: Any) -> torch.Tensor:
        x = networks.preprocess_obs(obs, self.observation_space, self.normalize_images)
        out = self.quantile_net(self.features_extractor(x))
        return out.view(-1, self.n_quantiles, int(self.action_space.n))

    def mlp_modules(self) -> tuple[list[nn.Module] | None, str]:
        """The modules the numpy learner reads as an MLP (its output is the flat
        ``[B, n_quantiles * n_actions]``), or None and why."""
        why = _numpy_input_problem(
            self.observation_space, self.features_extractor, self.normalize_images
        )
        return (None, why) if why else ([self.features_extractor, self.quantile_net], "")


class QRDQNPolicy(DQNPolicy):
    """sb3-contrib's ``QRDQNPolicy`` (``palaestra.algos.qrdqn.MlpPolicy``): ``quantile_net`` and
    its frozen copy ``quantile_net_target``, each built by ``make_quantile_net()``, which a
    subclass may override. Everything else is ``DQNPolicy``'s (the two nets are its ``q_net``
    and ``q_net_target``); the optimizer is the algorithm's."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Discrete,
        lr_schedule: Any,
        n_quantiles: int = 200,
        net_arch: list[int] | None = None,
        activation_fn: type[nn.Module] = nn.ReLU,
        features_extractor_class: type[BaseFeaturesExtractor] = FlattenExtractor,
        features_extractor_kwargs: dict[str, Any] | None = None,
        normalize_images: bool = True,
        optimizer_class: type[torch.optim.Optimizer] = torch.optim.Adam,
        optimizer_kwargs: dict[str, Any] | None = None,
    ) -> None:
        self.n_quantiles = n_quantiles  # make_quantile_net reads it inside DQNPolicy.__init__
        super().__init__(
            **{k: v for k, v in locals().items() if k not in ("self", "__class__", "n_quantiles")}
        )

    @property
    def quantile_net(self) -> QuantileNetwork:
        return self.q_net  # type: ignore[return-value]

    @property
    def quantile_net_target(self) -> QuantileNetwork:
        return self.q_net_target  # type: ignore[return-value]

    def make_q_net(self) -> QuantileNetwork:  # type: ignore[override]
        return self.make_quantile_net()

    def make_quantile_net(self) -> QuantileNetwork:
        """A new quantile network with its own features extractor (none after NatureCNN's
        MLP layers unless ``net_arch`` says)."""
        extractor = networks.make_extractor(
            self.features_extractor_class,
            self.observation_space,
            self.features_extractor_kwargs,
            self.normalize_images,
        )
        net_arch = self.net_arch
        if net_arch is None:
            net_arch = [] if self.features_extractor_class is NatureCNN else [64, 64]
        return QuantileNetwork(
            self.observation_space,
            self.action_space,
            extractor,
            extractor.features_dim,
            self.n_quantiles,
            net_arch,
            self.activation_fn,
            self.normalize_images,
        )

    def forward(self, obs: Any, deterministic: bool = True) -> torch.Tensor:
        """The greedy actions ``[B]``: the largest mean over the quantiles."""
        start = int(getattr(self.action_space, "start", 0))
        return self.q_net(obs).mean(dim=1).argmax(dim=1) + start


MlpPolicy = QRDQNPolicy  # sb3-contrib's alias


def _default_extractor(extractor: type[BaseFeaturesExtractor]) -> Callable[..., None]:
    """``QRDQNPolicy.__init__`` with another default ``features_extractor_class``: sb3-contrib's
    ``CnnPolicy`` and ``MultiInputPolicy`` differ from ``QRDQNPolicy`` only there, and keep its
    signature (positional calls included)."""
    signature = inspect.signature(QRDQNPolicy.__init__)
    params = [
        p.replace(default=extractor) if p.name == "features_extractor_class" else p
        for p in signature.parameters.values()
    ]
    signature = signature.replace(parameters=params)

    def __init__(self: QRDQNPolicy, *args: Any, **kwargs: Any) -> None:
        bound = signature.bind(self, *args, **kwargs)
        bound.apply_defaults()
        QRDQNPolicy.__init__(*bound.args, **bound.kwargs)

    __init__.__signature__ = signature  # type: ignore[attr-defined]
    return __init__


class CnnPolicy(QRDQNPolicy):
    """``QRDQNPolicy`` with ``NatureCNN`` as its default features extractor (sb3-contrib's)."""

    default_features_extractor_class = NatureCNN
    __init__ = _default_extractor(NatureCNN)


class MultiInputPolicy(QRDQNPolicy):
    """``QRDQNPolicy`` with ``CombinedExtractor`` as its default features extractor
    (sb3-contrib's)."""

    default_features_extractor_class = CombinedExtractor
    __init__ = _default_extractor(CombinedExtractor)
