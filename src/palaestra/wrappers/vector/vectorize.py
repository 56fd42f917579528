"""Gymnasium's named vector observation/action wrappers: a single-env wrapper per sub-env.

``FlattenObservation(envs)`` is ``VectorizeTransformObservation(envs, wrappers.
FlattenObservation)``, and so on: one definition of each transform (the single-env wrapper),
applied to every row of the batch, as ``gymnasium.wrappers.vector`` does.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from palaestra.vector.vector_env import VectorEnv
from palaestra.wrappers import resize, transform_action, transform_observation
from palaestra.wrappers.vector.transforms import (
    VectorizeTransformAction,
    VectorizeTransformObservation,
)

__all__ = [
    "ClipAction",
    "DtypeObservation",
    "FilterObservation",
    "FlattenObservation",
    "GrayscaleObservation",
    "RescaleAction",
    "RescaleObservation",
    "ReshapeObservation",
    "ResizeObservation",
]


class FilterObservation(VectorizeTransformObservation):
    """Keep only ``filter_keys`` of each sub-env's Dict (or Tuple) observation."""

    def __init__(self, env: VectorEnv[Any, Any, Any], filter_keys: Sequence[str | int]) -> None:
        super().__init__(env, transform_observation.FilterObservation, filter_keys=filter_keys)


class FlattenObservation(VectorizeTransformObservation):
    """Each sub-env's observation flattened to a 1-D array."""

    def __init__(self, env: VectorEnv[Any, Any, Any]) -> None:
        super().__init__(env, transform_observation.FlattenObservation)


class GrayscaleObservation(VectorizeTransformObservation):
    """RGB image observations to grayscale (``keep_dim`` keeps a channel axis of 1)."""

    def __init__(self, env: VectorEnv[Any, Any, Any], keep_dim: bool = False) -> None:
        super().__init__(env, transform_observation.GrayscaleObservation, keep_dim=keep_dim)


class ResizeObservation(VectorizeTransformObservation):
    """Image observations resized to ``shape`` (height, width)."""

    def __init__(self, env: VectorEnv[Any, Any, Any], shape: tuple[int, ...]) -> None:
        super().__init__(env, resize.ResizeObservation, shape=shape)


class ReshapeObservation(VectorizeTransformObservation):
    """Each sub-env's array observation reshaped to ``shape``."""

    def __init__(self, env: VectorEnv[Any, Any, Any], shape: int | tuple[int, ...]) -> None:
        super().__init__(env, transform_observation.ReshapeObservation, shape=shape)


class RescaleObservation(VectorizeTransformObservation):
    """Box observations affinely rescaled into ``[min_obs, max_obs]``."""

    def __init__(
        self,
        env: VectorEnv[Any, Any, Any],
        min_obs: float | np.floating | np.integer | np.ndarray,
        max_obs: float | np.floating | np.integer | np.ndarray,
    ) -> None:
        super().__init__(
            env, transform_observation.RescaleObservation, min_obs=min_obs, max_obs=max_obs
        )


class DtypeObservation(VectorizeTransformObservation):
    """Each sub-env's observation cast to ``dtype``."""

    def __init__(self, env: VectorEnv[Any, Any, Any], dtype: Any) -> None:
        super().__init__(env, transform_observation.DtypeObservation, dtype=dtype)


class ClipAction(VectorizeTransformAction):
    """Actions clipped into each sub-env's Box action space."""

    def __init__(self, env: VectorEnv[Any, Any, Any]) -> None:
        super().__init__(env, transform_action.ClipAction)


class RescaleAction(VectorizeTransformAction):
    """Actions given in ``[min_action, max_action]`` rescaled to the sub-envs' Box bounds."""

    def __init__(
        self,
        env: VectorEnv[Any, Any, Any],
        min_action: float | int | np.ndarray,
        max_action: float | int | np.ndarray,
    ) -> None:
        super().__init__(
            env, transform_action.RescaleAction, min_action=min_action, max_action=max_action
        )
