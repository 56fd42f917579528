"""The two policy networks: DQN's Q-network and PPO's actor-critic, built from a policy name
(``"MlpPolicy"``, ``"CnnPolicy"``, ``"MultiInputPolicy"``) and SB3's ``policy_kwargs``."""

from __future__ import annotations

import inspect
import math
import warnings
from typing import Any

import numpy as np
import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.common.base_policy import BaseModel, BasePolicy
from palaestra.algos.common.continuous_policies import ContinuousCritic
from palaestra.algos.common.distributions import ActionHead, Distribution
from palaestra.algos.common.networks import (
    BaseFeaturesExtractor,
    CombinedExtractor,
    FlattenExtractor,
    MlpExtractor,
    NatureCNN,
    make_extractor,
    mlp,
    preprocess_obs,
)
from palaestra.algos.common.spaces_util import is_image_space
from palaestra.algos.learners.xp import torch_ops

__all__ = [
    "POLICY_EXTRACTORS",
    "ActorCritic",
    "ActorCriticCnnPolicy",
    "ActorCriticPolicy",
    "BaseModel",
    "BasePolicy",
    "ContinuousCritic",
    "MultiInputActorCriticPolicy",
    "extractor_class",
]

POLICY_EXTRACTORS: dict[str, type[BaseFeaturesExtractor]] = {
    "MlpPolicy": FlattenExtractor,
    "CnnPolicy": NatureCNN,
    "MultiInputPolicy": CombinedExtractor,
}


def extractor_class(policy: Any) -> type[BaseFeaturesExtractor]:
    """The default features extractor of a policy name (``FlattenExtractor`` for an
    ``ActorCriticPolicy`` subclass, as SB3's); ``ValueError`` for anything else."""
    if isinstance(policy, type) and issubclass(policy, ActorCriticPolicy):
        return FlattenExtractor
    if not isinstance(policy, str) or policy not in POLICY_EXTRACTORS:
        raise ValueError(
            f"Policy {policy!r} unknown: use one of {', '.join(map(repr, POLICY_EXTRACTORS))}"
        )
    return POLICY_EXTRACTORS[policy]


def _numpy_input_problem(
    space: spaces.Space[Any], extractor: nn.Module, normalize_images: bool
) -> str:
    """Why a net's input is not the raw observation flattened to float32 ("" if it is)."""
    if isinstance(extractor, CombinedExtractor) and isinstance(space, spaces.Dict):
        # every entry flattened and cast, side by side in key order: the numpy learner's
        # input (learner._flat_input concatenates a dict's entries in sorted key order)
        if list(space.spaces) != sorted(space.spaces):
            return "the Dict observation's keys are not in sorted order"
        for key, sub in space.spaces.items():
            flat = isinstance(sub, spaces.MultiBinary) or (
                isinstance(sub, spaces.Box) and not is_image_space(sub)
            )
            if not flat or not isinstance(extractor.extractors[key], nn.Flatten):
                return f"the Dict observation's {key!r} entry is {sub}, preprocessed in torch"
        return ""
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


def _sb3_net_arch(net_arch: Any, features_extractor_class: type) -> Any:
    """``net_arch`` as SB3's ActorCriticPolicy keeps it: None becomes the default (so a model
    saved with ``net_arch=None`` loads with it), and the pre-1.8 ``[dict(pi=..., vf=...)]``
    becomes the dict, with SB3's warning."""
    if isinstance(net_arch, list) and net_arch and isinstance(net_arch[0], dict):
        warnings.warn(
            "As shared layers in the mlp_extractor are removed since SB3 v1.8.0, you should "
            "now pass directly a dictionary and not a list (net_arch=dict(pi=..., vf=...) "
            "instead of net_arch=[dict(pi=..., vf=...)])",
            stacklevel=4,
        )
        net_arch = net_arch[0]
    if net_arch is None:
        return [] if features_extractor_class is NatureCNN else {"pi": [64, 64], "vf": [64, 64]}
    return net_arch


def _ortho_init(module: nn.Module, gain: float) -> None:
    """Orthogonal weights, zero biases (OpenAI baselines' PPO init, kept by SB3)."""
    for m in module.modules():
        if isinstance(m, (nn.Linear, nn.Conv2d)):
            nn.init.orthogonal_(m.weight, gain=gain)
            if m.bias is not None:
                m.bias.data.fill_(0.0)


class ActorCritic(BasePolicy):
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
        use_sde: bool = False,
        full_std: bool = True,
        use_expln: bool = False,
        squash_output: bool = False,
    ) -> None:
        super().__init__()
        self.observation_space, self.action_space = observation_space, action_space
        self.use_sde, self.full_std, self.use_expln = use_sde, full_std, use_expln
        self.squash_output = squash_output
        self.normalize_images, self.ortho_init = normalize_images, ortho_init
        self.net_arch = _sb3_net_arch(net_arch, features_extractor_class)
        self.activation_fn = activation_fn
        # Kept under their argument names: ``save`` rebuilds the policy from them.
        self.features_extractor_class = features_extractor_class
        self.features_extractor_kwargs = dict(features_extractor_kwargs or {})
        self.log_std_init, self.share_features_extractor = log_std_init, share_features_extractor
        kwargs, cls = features_extractor_kwargs, features_extractor_class
        self.features_extractor = make_extractor(cls, observation_space, kwargs, normalize_images)
        self.vf_features_extractor = (
            None
            if share_features_extractor
            else make_extractor(cls, observation_space, kwargs, normalize_images)
        )
        self.features_dim = self.features_extractor.features_dim
        self._features_extractor_class = features_extractor_class
        self._build_mlp_extractor()
        latent_pi, latent_vf = self._latent_dims()
        self.action_head = ActionHead(
            action_space, latent_pi, log_std_init, use_sde, full_std, use_expln, squash_output
        )
        self.value_head = nn.Linear(latent_vf, 1)
        if ortho_init:
            # Gains from SB3 / baselines: sqrt(2) body, 0.01 policy output, 1 value output.
            for part, gain in [
                (self.features_extractor, math.sqrt(2)),
                (self.vf_features_extractor, math.sqrt(2)),
                *[(body, math.sqrt(2)) for body in self._bodies()],
                (self.action_head.net, 0.01),
                (self.value_head, 1.0),
            ]:
                if part is not None:
                    _ortho_init(part, gain)

    # -- the actor and critic bodies between the features and the heads (SB3's
    # ``mlp_extractor``; ``ActorCriticPolicy`` builds them SB3's way) ----------------------
    def _build_mlp_extractor(self) -> None:
        pi_arch, vf_arch = _split_arch(self.net_arch, self._features_extractor_class)
        self.pi_net = mlp(self.features_dim, pi_arch, self.activation_fn)
        self.vf_net = mlp(self.features_dim, vf_arch, self.activation_fn)
        self._latent = (
            pi_arch[-1] if pi_arch else self.features_dim,
            vf_arch[-1] if vf_arch else self.features_dim,
        )

    def _latent_dims(self) -> tuple[int, int]:
        return self._latent

    def _bodies(self) -> list[nn.Module]:
        return [self.pi_net, self.vf_net]

    def _pi_latent(self, features: torch.Tensor) -> torch.Tensor:
        return self.pi_net(features)

    def _vf_latent(self, features: torch.Tensor) -> torch.Tensor:
        return self.vf_net(features)

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

    @property
    def action_dist(self) -> Distribution:
        """SB3's ``action_dist``: the distribution object the action head computes with."""
        return self.action_head.dist

    def reset_noise(self, n_envs: int = 1) -> None:
        """Draw new gSDE exploration matrices (one per env) from torch's generator (SB3's
        ``reset_noise``); ``ValueError`` without gSDE."""
        self.action_head.reset_noise(self.action_head.log_std, n_envs)

    def get_distribution(self, obs: Any) -> Distribution:
        """The action distribution for a raw observation batch (SB3's ``get_distribution``)."""
        x = preprocess_obs(obs, self.observation_space, self.normalize_images)
        latent = self._pi_latent(self.features_extractor(x))
        head = self.action_head
        return head.distribution(head.net(latent), getattr(head, "log_std", None), latent)

    def pi_latent(self, obs: Any) -> torch.Tensor:
        """The policy latent (gSDE's ``pi`` net: its variance reads it)."""
        x = preprocess_obs(obs, self.observation_space, self.normalize_images)
        return self._pi_latent(self.features_extractor(x))

    def pi_latent_and_vf(self, obs: Any) -> tuple[torch.Tensor, torch.Tensor]:
        """The policy latent and ``V(obs)``, one pass of a shared features extractor."""
        latent_pi, latent_vf = self._latents(obs)
        return latent_pi, self.value_head(latent_vf)

    def pi_out(self, obs: Any) -> torch.Tensor:
        """The action head's outputs (logits, or the Gaussian's mean) for a raw obs batch."""
        x = preprocess_obs(obs, self.observation_space, self.normalize_images)
        return self.action_head.net(self._pi_latent(self.features_extractor(x)))

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
        return self._pi_latent(features), self._vf_latent(vf_features)

    def evaluate_actions(
        self, obs: Any, actions: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """SB3's ``(values [B], log_prob [B], entropy [B])`` of env actions (torch, autograd):
        the head's ``evaluate`` on the torch namespace."""
        head = self.action_head
        log_std = getattr(head, "log_std", None)
        if head.kind == "sde":
            latent, vf = self.pi_latent_and_vf(obs)
            dist = head.distribution(head.net(latent), log_std, latent)
            return vf.squeeze(1), dist.log_prob(actions), dist.entropy()  # type: ignore[return-value]
        pi, vf = self.pi_and_vf(obs)
        idx = torch.as_tensor(head.index(actions.cpu().numpy()), device=pi.device)
        log_prob, entropy, _ = head.evaluate(torch_ops, pi, log_std, idx)
        return vf.squeeze(1), log_prob, entropy.expand(pi.shape[0])

    def predict_values(self, obs: Any) -> torch.Tensor:
        """``V(obs)`` ``[B]``."""
        return self.value_head(self._latents(obs)[1]).squeeze(1)

    def _predict(self, observation: Any, deterministic: bool = False) -> torch.Tensor:
        """The distribution's mode, or a sample drawn from a generator seeded by torch's
        (so ``torch.manual_seed`` fixes it, as in SB3)."""
        head = self.action_head
        latent = None
        if head.kind == "sde":
            latent_t = self.pi_latent(observation)
            params, latent = head.net(latent_t).cpu().numpy(), latent_t.cpu().numpy()
        else:
            params = self.pi_out(observation).cpu().numpy()
        has_std = head.kind in ("gaussian", "sde")
        log_std = head.log_std.detach().cpu().numpy() if has_std else None
        seed = 0 if deterministic else int(torch.randint(0, 2**62, (1,)).item())
        rng = np.random.default_rng(seed)
        actions, _ = head.sample(params, log_std, rng, deterministic, latent)
        return torch.as_tensor(actions)


class ActorCriticPolicy(ActorCritic):
    """SB3's ``ActorCriticPolicy`` face, for subclasses written by SB3's custom-policy guide:
    the constructor takes ``(observation_space, action_space, lr_schedule, **SB3 kwargs)``,
    the bodies are ``self.mlp_extractor`` (an ``MlpExtractor`` unless ``_build_mlp_extractor``
    is overridden with any module having ``latent_dim_pi``/``latent_dim_vf`` and
    ``forward_actor``/``forward_critic``), over ``self.features_dim`` features.

    ``PPO(MyPolicy, env)`` or ``A2C(...)`` trains it on the torch learner (the numpy learner
    runs only palaestra's own MLP policy). The optimizer stays the algorithm's to build, from
    ``optimizer_class``/``optimizer_kwargs`` in ``policy_kwargs`` as for ``"MlpPolicy"``."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        lr_schedule: Any = None,
        net_arch: Any = None,
        activation_fn: type[nn.Module] = nn.Tanh,
        ortho_init: bool = True,
        use_sde: bool = False,
        log_std_init: float = 0.0,
        full_std: bool = True,
        use_expln: bool = False,
        squash_output: bool = False,
        features_extractor_class: type[BaseFeaturesExtractor] = FlattenExtractor,
        features_extractor_kwargs: dict[str, Any] | None = None,
        share_features_extractor: bool = True,
        normalize_images: bool = True,
        optimizer_class: Any = None,
        optimizer_kwargs: dict[str, Any] | None = None,
    ) -> None:
        self.lr_schedule = lr_schedule
        self.optimizer_class, self.optimizer_kwargs = optimizer_class, optimizer_kwargs
        super().__init__(
            observation_space,
            action_space,
            features_extractor_class,
            features_extractor_kwargs,
            net_arch,
            activation_fn,
            ortho_init,
            log_std_init,
            share_features_extractor,
            normalize_images,
            use_sde,
            full_std,
            use_expln,
            squash_output,
        )

    def _build_mlp_extractor(self) -> None:
        """SB3's default: ``MlpExtractor`` with ``net_arch`` (None: ``[64, 64]`` for both,
        none after ``NatureCNN``)."""
        pi_arch, vf_arch = _split_arch(self.net_arch, self._features_extractor_class)
        arch = {"pi": pi_arch, "vf": vf_arch}
        self.mlp_extractor = MlpExtractor(self.features_dim, arch, self.activation_fn)

    def _latent_dims(self) -> tuple[int, int]:
        for name in ("latent_dim_pi", "latent_dim_vf", "forward_actor", "forward_critic"):
            if not hasattr(self.mlp_extractor, name):
                raise TypeError(
                    f"{type(self).__name__}.mlp_extractor ({type(self.mlp_extractor).__name__}) "
                    f"has no {name}: the actor/critic body needs latent_dim_pi, latent_dim_vf, "
                    "forward_actor and forward_critic (see MlpExtractor)"
                )
        return int(self.mlp_extractor.latent_dim_pi), int(self.mlp_extractor.latent_dim_vf)

    def _bodies(self) -> list[nn.Module]:
        return [self.mlp_extractor]

    def _pi_latent(self, features: torch.Tensor) -> torch.Tensor:
        return self.mlp_extractor.forward_actor(features)

    def _vf_latent(self, features: torch.Tensor) -> torch.Tensor:
        return self.mlp_extractor.forward_critic(features)

    def mlp_modules(self) -> tuple[list[nn.Module] | None, list[nn.Module] | None, str]:
        return None, None, f"the policy is a custom {type(self).__name__}"


# Where ``features_extractor_class`` falls among ActorCriticPolicy's positional arguments.
_EXTRACTOR_ARG = list(inspect.signature(ActorCriticPolicy.__init__).parameters).index(
    "features_extractor_class"
)


def _extractor_default(args: tuple[Any, ...], kwargs: dict[str, Any], default: type) -> None:
    """Give ``kwargs`` the class's default extractor unless the caller named one (by keyword
    or positionally, in SB3's argument order)."""
    if len(args) < _EXTRACTOR_ARG:  # (self is not in args)
        kwargs.setdefault("features_extractor_class", default)


class ActorCriticCnnPolicy(ActorCriticPolicy):
    """SB3's ``ActorCriticCnnPolicy`` (PPO's and A2C's ``CnnPolicy`` class): an
    ``ActorCriticPolicy`` whose features extractor is ``NatureCNN`` unless one is given."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        _extractor_default(args, kwargs, NatureCNN)
        super().__init__(*args, **kwargs)


class MultiInputActorCriticPolicy(ActorCriticPolicy):
    """SB3's ``MultiInputActorCriticPolicy`` (``MultiInputPolicy`` class) for Dict
    observations: its features extractor is ``CombinedExtractor`` unless one is given."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        _extractor_default(args, kwargs, CombinedExtractor)
        super().__init__(*args, **kwargs)
