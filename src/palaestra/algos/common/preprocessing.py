"""SB3's ``common.preprocessing`` helpers on palaestra's spaces: image detection, the shapes
buffers store, flattened widths, action widths, the nested-space check, and ``preprocess_obs``.

These are the public functions SB3 users and custom extractors call, with SB3's names,
keywords and results. palaestra's own networks preprocess through
``palaestra.algos.networks.preprocess_obs``, which also turns channel-last images to CHW
(palaestra needs no ``VecTransposeImage``); the ``preprocess_obs`` here does what SB3's does
(no transpose), so code written against SB3 gets SB3's tensors.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import torch
from torch.nn import functional

from palaestra import spaces

__all__ = [
    "check_for_nested_spaces",
    "get_action_dim",
    "get_flattened_obs_dim",
    "get_obs_shape",
    "is_image_space",
    "is_image_space_channels_first",
    "maybe_transpose",
    "preprocess_obs",
]


def is_image_space_channels_first(observation_space: spaces.Box) -> bool:
    """Whether an image space is CHW (True) or HWC (False): the smallest axis holds the
    channels (SB3's heuristic, with its warning when the middle axis is the smallest)."""
    smallest = int(np.argmin(observation_space.shape))
    if smallest == 1:
        warnings.warn(
            "Treating image space as channels-last, while second dimension was smallest of "
            "the three.",
            stacklevel=2,
        )
    return smallest == 0


def is_image_space(
    observation_space: spaces.Space[Any],
    check_channels: bool = False,
    normalized_image: bool = False,
) -> bool:
    """A rank-3 ``Box`` of uint8 in [0, 255] (``normalized_image``: any dtype and bounds);
    ``check_channels`` also asks for 1, 3 or 4 channels (gray, RGB, RGBD), as SB3 decides."""
    if not isinstance(observation_space, spaces.Box) or len(observation_space.shape) != 3:
        return False
    if not normalized_image:
        if observation_space.dtype != np.uint8:
            return False
        if np.any(observation_space.low != 0) or np.any(observation_space.high != 255):
            return False
    if not check_channels:
        return True
    shape = observation_space.shape
    channels = shape[0] if is_image_space_channels_first(observation_space) else shape[-1]
    return channels in (1, 3, 4)


def get_obs_shape(observation_space: spaces.Space[Any]) -> Any:
    """The shape a buffer stores per observation (a dict of shapes for ``Dict`` spaces):
    ``Discrete`` -> ``(1,)``, ``MultiDiscrete`` -> ``(len(nvec),)``, else the space's shape."""
    if isinstance(observation_space, (spaces.Box, spaces.MultiBinary)):
        return tuple(observation_space.shape)
    if isinstance(observation_space, spaces.Discrete):
        return (1,)
    if isinstance(observation_space, spaces.MultiDiscrete):
        return (len(observation_space.nvec),)
    if isinstance(observation_space, spaces.Dict):
        return {key: get_obs_shape(sub) for key, sub in observation_space.spaces.items()}
    raise NotImplementedError(f"{observation_space} observation space is not supported")


def get_flattened_obs_dim(observation_space: spaces.Space[Any]) -> int:
    """The width of a flattened observation (``FlattenExtractor``'s input): the sum of
    ``nvec`` for ``MultiDiscrete`` (one-hot), ``flatdim`` otherwise."""
    if isinstance(observation_space, spaces.MultiDiscrete):
        return int(np.sum(observation_space.nvec))
    return int(spaces.flatdim(observation_space))


def get_action_dim(action_space: spaces.Space[Any]) -> int:
    """The number of numbers in one action: ``prod(shape)`` for ``Box``, 1 for ``Discrete``,
    ``len(nvec)`` for ``MultiDiscrete``, ``n`` for a one-dimensional ``MultiBinary``."""
    if isinstance(action_space, spaces.Box):
        return int(np.prod(action_space.shape))
    if isinstance(action_space, spaces.Discrete):
        return 1
    if isinstance(action_space, spaces.MultiDiscrete):
        return len(action_space.nvec)
    if isinstance(action_space, spaces.MultiBinary):
        if not isinstance(action_space.n, (int, np.integer)):
            raise ValueError(
                f"Multi-dimensional MultiBinary({action_space.n}) action space is not "
                "supported. You can flatten it instead."
            )
        return int(action_space.n)
    raise NotImplementedError(f"{action_space} action space is not supported")


def preprocess_obs(
    obs: Any, observation_space: spaces.Space[Any], normalize_images: bool = True
) -> Any:
    """Observation tensors -> network input, as SB3: images scaled to [0, 1] (not
    transposed), ``Discrete``/``MultiDiscrete`` one-hot, the rest as float."""
    if isinstance(observation_space, spaces.Dict):
        if not isinstance(obs, dict):
            raise TypeError(f"Expected dict, got {type(obs)}")
        return {
            key: preprocess_obs(value, observation_space[key], normalize_images)
            for key, value in obs.items()
        }
    if not isinstance(obs, torch.Tensor):
        raise TypeError(f"Expecting a torch Tensor, but got {type(obs)}")
    if isinstance(observation_space, spaces.Box):
        if normalize_images and is_image_space(observation_space):
            return obs.float() / 255.0
        return obs.float()
    if isinstance(observation_space, spaces.Discrete):
        # palaestra also honours ``start`` (SB3 one-hots the raw value: same for start=0)
        index = obs.long() - int(observation_space.start)
        return functional.one_hot(index, int(observation_space.n)).float()
    if isinstance(observation_space, spaces.MultiDiscrete):
        nvec = np.asarray(observation_space.nvec).reshape(-1)
        start = torch.as_tensor(np.asarray(observation_space.start).reshape(-1), device=obs.device)
        index = obs.long().reshape(obs.shape[0], -1) - start
        parts = [functional.one_hot(index[:, i], int(n)).float() for i, n in enumerate(nvec)]
        return torch.cat(parts, dim=-1)
    if isinstance(observation_space, spaces.MultiBinary):
        return obs.float()
    raise NotImplementedError(f"Preprocessing not implemented for {observation_space}")


def check_for_nested_spaces(obs_space: spaces.Space[Any]) -> None:
    """SB3's ``NotImplementedError`` for a Dict/Tuple inside a Dict/Tuple (the check lives
    with the vec envs, which need it without torch)."""
    from palaestra.vec_env import util  # lazy: import-time — cloudpickle

    util.check_for_nested_spaces(obs_space)


def maybe_transpose(observation: np.ndarray, observation_space: spaces.Space[Any]) -> np.ndarray:
    """An image observation (or batch) given channels-last for a channels-first image space,
    transposed to the space's layout; anything else unchanged (SB3's helper)."""
    if is_image_space(observation_space):
        shape = tuple(observation_space.shape or ())
        if not (observation.shape == shape or observation.shape[1:] == shape):
            # [..., H, W, C] -> [..., C, H, W]; fewer than 3 axes: numpy's ValueError, as SB3's
            axes = (*range(observation.ndim - 3), -1, -3, -2)
            transposed = np.transpose(observation, axes)
            if transposed.shape == shape or transposed.shape[1:] == shape:
                return transposed
    return observation
