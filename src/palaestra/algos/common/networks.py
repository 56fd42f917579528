"""Network building blocks: observation preprocessing, feature extractors, MLPs.

Extractors follow SB3's: ``FlattenExtractor`` (MlpPolicy), ``NatureCNN`` (CnnPolicy; Mnih et al.
2015) and ``CombinedExtractor`` (MultiInputPolicy: a CNN per image key, flatten for the rest).
Images are scaled by 1/255 and channel-last images are permuted here, inside the network, so no
``VecTransposeImage`` wrapper is needed and ``predict`` accepts the env's own layout.
"""

from __future__ import annotations

import itertools
from typing import Any

import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.common.spaces_util import is_image_space, is_image_space_channels_first

__all__ = [
    "BaseFeaturesExtractor",
    "CombinedExtractor",
    "FlattenExtractor",
    "MlpExtractor",
    "NatureCNN",
    "create_mlp",
    "extractor_space",
    "get_actor_critic_arch",
    "make_extractor",
    "mlp",
    "preprocess_obs",
    "preprocessed_dim",
]


def preprocess_obs(obs: Any, space: spaces.Space[Any], normalize_images: bool = True) -> Any:
    """Batch of raw observations -> float tensors: images /255 (and CHW), discrete one-hot."""
    if isinstance(space, spaces.Dict):
        return {k: preprocess_obs(obs[k], s, normalize_images) for k, s in space.spaces.items()}
    if isinstance(space, spaces.Box):
        if is_image_space(space):
            if not is_image_space_channels_first(space):
                obs = obs.permute(0, 3, 1, 2)
            return obs.float() / 255.0 if normalize_images else obs.float()
        return obs.float()
    if isinstance(space, spaces.Discrete):
        return nn.functional.one_hot(
            (obs.long() - int(space.start)).reshape(-1), int(space.n)
        ).float()
    if isinstance(space, spaces.MultiDiscrete):
        flat = (obs.long() - torch.as_tensor(space.start, device=obs.device)).reshape(
            obs.shape[0], -1
        )
        nvec = space.nvec.reshape(-1).tolist()
        return torch.cat(
            [nn.functional.one_hot(flat[:, i], int(n)).float() for i, n in enumerate(nvec)], dim=1
        )
    if isinstance(space, spaces.MultiBinary):
        return obs.float().reshape(obs.shape[0], -1)
    raise TypeError(f"unsupported observation space {space}")


def preprocessed_dim(space: spaces.Space[Any]) -> int:
    """Width of a flattened, preprocessed observation of a non-image space."""
    if isinstance(space, spaces.Discrete):
        return int(space.n)
    if isinstance(space, spaces.MultiDiscrete):
        return int(space.nvec.sum())
    shape = tuple(space.shape or ())
    return int(torch.Size(shape).numel())


class BaseFeaturesExtractor(nn.Module):
    """Maps a preprocessed observation batch to ``[B, features_dim]``.

    SB3's base class: a subclass may set ``self._features_dim`` after ``__init__`` (SB3's
    custom-policy guide does), ``features_dim`` reads it. Images reach ``forward`` as CHW
    floats and ``observation_space`` describes them so (SB3's ``VecTransposeImage`` view),
    whatever layout the env has (see ``extractor_space``)."""

    def __init__(self, observation_space: spaces.Space[Any], features_dim: int = 0) -> None:
        super().__init__()
        if isinstance(features_dim, bool) or not isinstance(features_dim, int) or features_dim < 1:
            raise ValueError(f"features_dim must be a positive integer, got {features_dim!r}")
        self.observation_space = observation_space
        self._features_dim = features_dim

    @property
    def features_dim(self) -> int:
        """The width of the features this extractor outputs."""
        return self._features_dim


def extractor_space(space: spaces.Space[Any]) -> spaces.Space[Any]:
    """The space a features extractor is built for: channel-last image boxes as CHW (the
    layout ``preprocess_obs`` hands the extractor, and what SB3's ``VecTransposeImage`` shows
    SB3's extractors), Dict spaces key by key, anything else as it is."""
    if isinstance(space, spaces.Dict):
        return spaces.Dict({k: extractor_space(s) for k, s in space.spaces.items()})
    if isinstance(space, spaces.Box) and is_image_space(space):
        if not is_image_space_channels_first(space):
            order = (2, 0, 1)
            low, high = space.low.transpose(order), space.high.transpose(order)
            return spaces.Box(low, high, low.shape, space.dtype)
    return space


def make_extractor(
    extractor_class: Any,
    space: spaces.Space[Any],
    kwargs: dict[str, Any] | None = None,
    normalize_images: bool = True,
) -> BaseFeaturesExtractor:
    """``extractor_class(extractor_space(space), **kwargs)``, checked: a ``TypeError`` naming the
    value unless it is a ``torch.nn.Module`` class whose instances have a positive integer
    ``features_dim`` (a ``BaseFeaturesExtractor`` or one shaped like it), which would
    otherwise fail later, obscurely, inside a network. With ``normalize_images=False`` the
    image extractors take images already normalised (``normalized_image=True``, as SB3's
    policies pass it): float images from ``VecNormalize``."""
    expected = "a BaseFeaturesExtractor subclass (palaestra.algos.networks)"
    if not (isinstance(extractor_class, type) and issubclass(extractor_class, nn.Module)):
        raise TypeError(f"features_extractor_class must be {expected}, got {extractor_class!r}")
    if not normalize_images and issubclass(extractor_class, (NatureCNN, CombinedExtractor)):
        kwargs = {**(kwargs or {}), "normalized_image": True}
    extractor: Any = extractor_class(extractor_space(space), **(kwargs or {}))
    dim = getattr(extractor, "features_dim", None)
    if isinstance(dim, bool) or not isinstance(dim, int) or dim < 1:
        raise TypeError(
            f"features_extractor_class {extractor_class.__qualname__} built an extractor whose "
            f"features_dim is {dim!r}; expected {expected} or a module with a positive int "
            "features_dim"
        )
    return extractor


class MlpExtractor(nn.Module):
    """SB3's actor and critic MLPs over the features: ``net_arch`` a list (both) or
    ``dict(pi=[...], vf=[...])``; ``latent_dim_pi``/``latent_dim_vf`` are their widths
    (the features' width where a list is empty)."""

    def __init__(
        self,
        feature_dim: int,
        net_arch: list[int] | dict[str, list[int]],
        activation_fn: type[nn.Module],
        device: torch.device | str = "auto",
    ) -> None:
        super().__init__()
        if isinstance(net_arch, dict):
            pi_arch, vf_arch = list(net_arch.get("pi", [])), list(net_arch.get("vf", []))
        else:
            pi_arch = vf_arch = list(net_arch)
        self.policy_net = mlp(feature_dim, pi_arch, activation_fn)
        self.value_net = mlp(feature_dim, vf_arch, activation_fn)
        self.latent_dim_pi = pi_arch[-1] if pi_arch else feature_dim
        self.latent_dim_vf = vf_arch[-1] if vf_arch else feature_dim
        if device != "auto":
            self.to(device)

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.forward_actor(features), self.forward_critic(features)

    def forward_actor(self, features: torch.Tensor) -> torch.Tensor:
        return self.policy_net(features)

    def forward_critic(self, features: torch.Tensor) -> torch.Tensor:
        return self.value_net(features)


class FlattenExtractor(BaseFeaturesExtractor):
    """Flatten, nothing else (MlpPolicy)."""

    def __init__(self, observation_space: spaces.Space[Any]) -> None:
        super().__init__(observation_space, preprocessed_dim(observation_space))
        self.flatten = nn.Flatten()

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.flatten(obs)


def _chw(space: spaces.Box) -> tuple[int, int, int]:
    shape = tuple(int(d) for d in space.shape)
    if is_image_space(space) and not is_image_space_channels_first(space):
        return shape[2], shape[0], shape[1]
    return shape[0], shape[1], shape[2]


class NatureCNN(BaseFeaturesExtractor):
    """Three conv layers and a linear layer, as in the DQN Nature paper (Mnih et al. 2015)."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        features_dim: int = 512,
        normalized_image: bool = False,
    ) -> None:
        super().__init__(observation_space, features_dim)
        if not isinstance(observation_space, spaces.Box) or len(observation_space.shape) != 3:
            raise ValueError(
                f"NatureCNN needs an image observation space (rank-3 Box), got "
                f"{observation_space}; use 'MlpPolicy' for vector observations"
            )
        if not normalized_image and not is_image_space(observation_space):
            # SB3 refuses these too (an AssertionError): they would reach the network unscaled
            raise ValueError(
                f"NatureCNN with normalize_images=True needs uint8 images with bounds 0..255, "
                f"got {observation_space}; for images already normalised (VecNormalize, "
                "float images) pass policy_kwargs=dict(normalize_images=False)"
            )
        c, h, w = _chw(observation_space)
        self.cnn = nn.Sequential(
            nn.Conv2d(c, 32, kernel_size=8, stride=4),
            nn.ReLU(),
            nn.Conv2d(32, 64, kernel_size=4, stride=2),
            nn.ReLU(),
            nn.Conv2d(64, 64, kernel_size=3, stride=1),
            nn.ReLU(),
            nn.Flatten(),
        )
        with torch.no_grad():
            n_flatten = self.cnn(torch.zeros(1, c, h, w)).shape[1]
        self.linear = nn.Sequential(nn.Linear(n_flatten, features_dim), nn.ReLU())

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.linear(self.cnn(obs))


class CombinedExtractor(BaseFeaturesExtractor):
    """Dict observations: NatureCNN(``cnn_output_dim``) per image key, flatten the others."""

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        cnn_output_dim: int = 256,
        normalized_image: bool = False,
    ) -> None:
        if not isinstance(observation_space, spaces.Dict):
            raise ValueError(
                f"MultiInputPolicy needs a Dict observation space, got {observation_space}"
            )
        extractors: dict[str, nn.Module] = {}
        total = 0
        for key, sub in observation_space.spaces.items():
            # normalised images: any rank-3 Box (SB3's is_image_space(normalized_image=True))
            rank3 = isinstance(sub, spaces.Box) and len(sub.shape) == 3
            if is_image_space(sub) or (normalized_image and rank3):
                extractors[key] = NatureCNN(sub, cnn_output_dim, normalized_image)
                total += cnn_output_dim
            else:
                extractors[key] = nn.Flatten()
                total += preprocessed_dim(sub)
        super().__init__(observation_space, total)
        self.extractors = nn.ModuleDict(extractors)

    def forward(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        return torch.cat([net(obs[key]) for key, net in self.extractors.items()], dim=1)


def create_mlp(
    input_dim: int,
    output_dim: int,
    net_arch: list[int],
    activation_fn: type[nn.Module] = nn.ReLU,
    squash_output: bool = False,
    with_bias: bool = True,
    pre_linear_modules: list[type[nn.Module]] | None = None,
    post_linear_modules: list[type[nn.Module]] | None = None,
) -> list[nn.Module]:
    """SB3's MLP as a list of layers: ``Linear -> activation`` per width of ``net_arch``, then
    a ``Linear`` to ``output_dim`` when it is positive, then ``Tanh`` if ``squash_output``.

    ``pre_linear_modules`` (e.g. ``BatchNorm1d``) are built with each linear layer's input
    width and go before it (the output layer's too); ``post_linear_modules`` (``LayerNorm``,
    ``Dropout``) with its output width, between a hidden layer and its activation.
    """
    pre, post = pre_linear_modules or [], post_linear_modules or []
    layers: list[nn.Module] = []
    widths = [input_dim, *net_arch]
    for in_dim, out_dim in itertools.pairwise(widths):
        layers += [module(in_dim) for module in pre]
        layers.append(nn.Linear(in_dim, out_dim, bias=with_bias))
        layers += [module(out_dim) for module in post]
        layers.append(activation_fn())
    if output_dim > 0:
        layers += [module(widths[-1]) for module in pre]
        layers.append(nn.Linear(widths[-1], output_dim, bias=with_bias))
    if squash_output:
        layers.append(nn.Tanh())
    return layers


def mlp(in_dim: int, hidden: list[int], activation_fn: type[nn.Module]) -> nn.Sequential:
    """``Linear -> activation`` for each hidden width (empty list: identity)."""
    return nn.Sequential(*create_mlp(in_dim, 0, hidden, activation_fn))


def get_actor_critic_arch(
    net_arch: list[int] | dict[str, list[int]],
) -> tuple[list[int], list[int]]:
    """SAC/TD3/DDPG's ``net_arch``: a list (actor and critic alike) or
    ``dict(pi=[...], qf=[...])`` -> ``(actor widths, critic widths)``."""
    if isinstance(net_arch, list):
        return net_arch, net_arch
    if not isinstance(net_arch, dict):
        raise TypeError(
            f"net_arch must be a list of ints or dict(pi=[...], qf=[...]), got {net_arch!r}"
        )
    for key, net in (("pi", "actor"), ("qf", "critic")):
        if key not in net_arch:
            raise ValueError(
                f"Error: no key '{key}' was provided in net_arch for the {net} network: "
                f"got {net_arch!r}"
            )
    return net_arch["pi"], net_arch["qf"]
