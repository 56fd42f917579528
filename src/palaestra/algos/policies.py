"""The two policy networks: DQN's Q-network and PPO's actor-critic, built from a policy name
(``"MlpPolicy"``, ``"CnnPolicy"``, ``"MultiInputPolicy"``) and SB3's ``policy_kwargs``."""

from __future__ import annotations

import math
from typing import Any

import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.distributions import ActionHead
from palaestra.algos.networks import (
    BaseFeaturesExtractor,
    CombinedExtractor,
    FlattenExtractor,
    NatureCNN,
    mlp,
    preprocess_obs,
)
from palaestra.algos.spaces_util import is_image_space

__all__ = ["POLICY_EXTRACTORS", "ActorCritic", "QNetwork", "extractor_class"]

POLICY_EXTRACTORS: dict[str, type[BaseFeaturesExtractor]] = {
    "MlpPolicy": FlattenExtractor,
    "CnnPolicy": NatureCNN,
    "MultiInputPolicy": CombinedExtractor,
}


def extractor_class(policy: Any) -> type[BaseFeaturesExtractor]:
    """The default features extractor of a policy name; ``ValueError`` for anything else."""
    if not isinstance(policy, str) or policy not in POLICY_EXTRACTORS:
        raise ValueError(
            f"Policy {policy!r} unknown: use one of {', '.join(map(repr, POLICY_EXTRACTORS))}"
        )
    return POLICY_EXTRACTORS[policy]


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
        self.features_extractor = features_extractor_class(
            observation_space, **(features_extractor_kwargs or {})
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


def _numpy_input_problem(
    space: spaces.Space[Any], extractor: nn.Module, normalize_images: bool
) -> str:
    """Why a net's input is not the raw observation flattened to float32 ("" if it is)."""
    if not isinstance(extractor, FlattenExtractor):
        return f"the features extractor is {type(extractor).__name__}"
    if not isinstance(space, spaces.Box):
        return f"{type(space).__name__} observations are preprocessed (one-hot) in torch"
    if is_image_space(space) and normalize_images:
        return "image observations are scaled in torch"
    return ""


def _split_arch(net_arch: Any, features_extractor_class: type) -> tuple[list[int], list[int]]:
    if net_arch is None:
        return ([], []) if features_extractor_class is NatureCNN else ([64, 64], [64, 64])
    if isinstance(net_arch, dict):
        return list(net_arch.get("pi", [])), list(net_arch.get("vf", []))
    if isinstance(net_arch, (list, tuple)) and all(isinstance(w, int) for w in net_arch):
        return list(net_arch), list(net_arch)  # SB3 >= 1.8: a list means the same arch for both
    raise ValueError(
        f"net_arch must be a list of ints or dict(pi=[...], vf=[...]), got {net_arch!r}"
    )


def _ortho_init(module: nn.Module, gain: float) -> None:
    """Orthogonal weights, zero biases (OpenAI baselines' PPO init, kept by SB3)."""
    for m in module.modules():
        if isinstance(m, (nn.Linear, nn.Conv2d)):
            nn.init.orthogonal_(m.weight, gain=gain)
            if m.bias is not None:
                m.bias.data.fill_(0.0)


class ActorCritic(nn.Module):
    """PPO's policy and value function: separate pi/vf MLPs (SB3 default ``[64, 64]`` Tanh) on
    a features extractor shared by default, an ``ActionHead`` and a linear value head."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        features_extractor_class: type[BaseFeaturesExtractor] = FlattenExtractor,
        features_extractor_kwargs: dict[str, Any] | None = None,
        net_arch: Any = None,
        activation_fn: type[nn.Module] = nn.Tanh,
        ortho_init: bool = True,
        log_std_init: float = 0.0,
        share_features_extractor: bool = True,
        normalize_images: bool = True,
    ) -> None:
        super().__init__()
        self.observation_space, self.normalize_images = observation_space, normalize_images
        kwargs = features_extractor_kwargs or {}
        self.features_extractor = features_extractor_class(observation_space, **kwargs)
        self.vf_features_extractor = (
            None
            if share_features_extractor
            else features_extractor_class(observation_space, **kwargs)
        )
        pi_arch, vf_arch = _split_arch(net_arch, features_extractor_class)
        dim = self.features_extractor.features_dim
        self.pi_net = mlp(dim, pi_arch, activation_fn)
        self.vf_net = mlp(dim, vf_arch, activation_fn)
        self.action_head = ActionHead(action_space, pi_arch[-1] if pi_arch else dim, log_std_init)
        self.value_head = nn.Linear(vf_arch[-1] if vf_arch else dim, 1)
        if ortho_init:
            # Gains from SB3 / baselines: sqrt(2) body, 0.01 policy output, 1 value output.
            for part, gain in [
                (self.features_extractor, math.sqrt(2)),
                (self.vf_features_extractor, math.sqrt(2)),
                (self.pi_net, math.sqrt(2)),
                (self.vf_net, math.sqrt(2)),
                (self.action_head.net, 0.01),
                (self.value_head, 1.0),
            ]:
                if part is not None:
                    _ortho_init(part, gain)

    def mlp_modules(self) -> tuple[list[nn.Module] | None, list[nn.Module] | None, str]:
        """``(pi modules, vf modules, why)``: what the numpy learner reads as the actor and
        critic MLPs, or None and why not."""
        why = _numpy_input_problem(
            self.observation_space, self.features_extractor, self.normalize_images
        )
        if why:
            return None, None, why
        vf_extractor = self.vf_features_extractor or self.features_extractor
        return (
            [self.features_extractor, self.pi_net, self.action_head.net],
            [vf_extractor, self.vf_net, self.value_head],
            "",
        )

    def pi_out(self, obs: Any) -> torch.Tensor:
        """The action head's outputs (logits, or the Gaussian's mean) for a raw obs batch."""
        x = preprocess_obs(obs, self.observation_space, self.normalize_images)
        return self.action_head.net(self.pi_net(self.features_extractor(x)))

    def vf_out(self, obs: Any) -> torch.Tensor:
        """``V(obs)`` as ``[B, 1]``."""
        return self.value_head(self._latents(obs)[1])

    def pi_and_vf(self, obs: Any) -> tuple[torch.Tensor, torch.Tensor]:
        """Both outputs with one pass of a shared features extractor."""
        latent_pi, latent_vf = self._latents(obs)
        return self.action_head.net(latent_pi), self.value_head(latent_vf)

    def _latents(self, obs: Any) -> tuple[torch.Tensor, torch.Tensor]:
        x = preprocess_obs(obs, self.observation_space, self.normalize_images)
        features = self.features_extractor(x)
        vf_features = (
            features if self.vf_features_extractor is None else self.vf_features_extractor(x)
        )
        return self.pi_net(features), self.vf_net(vf_features)

    def evaluate_actions(
        self, obs: Any, actions: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """SB3's ``(values [B], log_prob [B], entropy [B])`` of env actions (torch, autograd):
        the head's ``evaluate`` on the torch namespace."""
        from palaestra.algos.learners.xp import torch_ops

        pi, vf = self.pi_and_vf(obs)
        log_std = getattr(self.action_head, "log_std", None)
        idx = torch.as_tensor(self.action_head.index(actions.cpu().numpy()), device=pi.device)
        log_prob, entropy, _ = self.action_head.evaluate(torch_ops, pi, log_std, idx)
        return vf.squeeze(1), log_prob, entropy.expand(pi.shape[0])

    def predict_values(self, obs: Any) -> torch.Tensor:
        """``V(obs)`` ``[B]``."""
        return self.value_head(self._latents(obs)[1]).squeeze(1)
