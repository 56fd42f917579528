"""Stateless observation wrappers: each applies one fixed function to every observation.

``TransformObservation`` is the general one; the others are thin named constructors that pick
the function and the new observation space (Gymnasium 1.x semantics and spaces).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import numpy as np

from palaestra.core import ActType, Env, ObservationWrapper, ObsType, WrapperObsType
from palaestra.spaces import Box, Dict, Discrete, MultiBinary, MultiDiscrete, Space, Tuple
from palaestra.spaces.utils import flatten, flatten_space
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.utils import rescale_box

__all__ = [
    "AddRenderObservation",
    "DtypeObservation",
    "FilterObservation",
    "FlattenObservation",
    "GrayscaleObservation",
    "RescaleObservation",
    "ReshapeObservation",
    "TransformObservation",
]


class TransformObservation(
    ObservationWrapper[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Apply ``func`` to every observation from ``reset`` and ``step``.

    Pass the ``observation_space`` of the transformed observations, or ``None`` to keep the
    inner one.
    """

    def __init__(
        self,
        env: Env[ObsType, ActType],
        func: Callable[[ObsType], Any],
        observation_space: Space[WrapperObsType] | None,
    ) -> None:
        RecordConstructorArgs.__init__(self, func=func, observation_space=observation_space)
        ObservationWrapper.__init__(self, env)
        if not callable(func):
            raise TypeError(f"Expected `func` to be callable, got {func!r}")
        if observation_space is not None:
            self.observation_space = observation_space
        self.func = func

    def observation(self, observation: ObsType) -> Any:
        """Return ``func(observation)``."""
        return self.func(observation)


class FilterObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Keep only ``filter_keys`` of a ``Dict`` (str keys) or ``Tuple`` (int indices) observation."""

    def __init__(self, env: Env[ObsType, ActType], filter_keys: Sequence[str | int]) -> None:
        if isinstance(filter_keys, str):
            # A ValueError, as Gymnasium's (which reads "key" as the keys "k", "e", "y").
            raise ValueError(
                f"Expected `filter_keys` to be a sequence of keys, got the string {filter_keys!r}; "
                f"pass [{filter_keys!r}] to keep that one key"
            )
        if not isinstance(filter_keys, Sequence):
            raise TypeError(
                f"Expected `filter_keys` to be a sequence of keys, got {type(filter_keys)}: "
                f"{filter_keys!r}"
            )
        RecordConstructorArgs.__init__(self, filter_keys=filter_keys)
        space = env.observation_space
        keys = tuple(filter_keys)
        new_space: Space[Any]
        func: Callable[[Any], Any]
        if isinstance(space, Dict):
            if not all(isinstance(k, str) for k in keys):
                raise TypeError(
                    f"All filter keys must be strings for a Dict space, got {filter_keys}"
                )
            missing = [k for k in keys if k not in space.spaces]
            if missing:
                raise ValueError(
                    "All the `filter_keys` must be included in the observation space.\n"
                    f"Filter keys: {filter_keys}\n"
                    f"Observation keys: {list(space.spaces)}\n"
                    f"Missing keys: {missing}"
                )
            new_space = Dict({str(k): space[str(k)] for k in keys}, sort_keys=space.sort_keys)
            if len(new_space) == 0:
                raise ValueError("The observation space is empty due to filtering all of the keys.")

            def func(obs: Any) -> Any:
                return {k: obs[k] for k in keys}

        elif isinstance(space, Tuple):
            if not all(isinstance(k, int) and not isinstance(k, bool) for k in keys):
                raise TypeError(
                    f"All filter keys must be integers for a Tuple space, got {filter_keys}"
                )
            if len(set(keys)) != len(keys):
                raise ValueError(f"Duplicate keys exist, filter_keys: {filter_keys}")
            bad = [k for k in keys if not -len(space) <= k < len(space)]  # type: ignore[operator]
            if bad:
                raise ValueError(
                    "All the `filter_keys` must be included in the length of the observation "
                    "space.\n"
                    f"Filter keys: {filter_keys}, length of observation: {len(space)}, "
                    f"missing indexes: {bad}"
                )
            new_space = Tuple(space[k] for k in keys)  # type: ignore[index]
            if len(new_space) == 0:
                raise ValueError("The observation space is empty due to filtering all keys.")

            def func(obs: Any) -> Any:
                return tuple(obs[k] for k in keys)

        else:
            raise ValueError(
                "FilterObservation wrapper is only usable with `Dict` and `Tuple` observations, "
                f"actual type: {type(space)}"
            )
        TransformObservation.__init__(self, env=env, func=func, observation_space=new_space)  # type: ignore[misc]
        self.filter_keys: Sequence[str | int] = filter_keys


class FlattenObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Flatten observations (and the space) to a 1-D array with ``spaces.utils.flatten``."""

    def __init__(self, env: Env[ObsType, ActType]) -> None:
        RecordConstructorArgs.__init__(self)
        space = env.observation_space
        TransformObservation.__init__(
            self, env=env, func=partial(flatten, space), observation_space=flatten_space(space)
        )


class GrayscaleObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Turn ``(H, W, 3) uint8`` RGB observations into ``(H, W)`` (or ``(H, W, 1)``) luminance."""

    # ITU-R BT.709 luma weights, Gymnasium's choice
    _WEIGHTS = np.array([0.2125, 0.7154, 0.0721])

    def __init__(self, env: Env[ObsType, ActType], keep_dim: bool = False) -> None:
        space = env.observation_space
        if not isinstance(space, Box):
            raise TypeError(
                f"GrayscaleObservation requires a Box observation space, got {type(space)}"
            )
        if len(space.shape) != 3 or space.shape[-1] != 3:
            raise ValueError(
                f"GrayscaleObservation requires an image with 3 channels, got shape {space.shape}"
            )
        if not (np.all(space.low == 0) and np.all(space.high == 255) and space.dtype == np.uint8):
            raise ValueError(
                "GrayscaleObservation requires observation bounds 0 to 255 and dtype uint8"
            )
        RecordConstructorArgs.__init__(self, keep_dim=keep_dim)
        self.keep_dim = keep_dim
        shape = space.shape[:2] + ((1,) if keep_dim else ())
        weights = self._WEIGHTS

        def func(obs: Any) -> Any:
            gray = np.sum(np.multiply(obs, weights), axis=-1).astype(np.uint8)
            return gray[..., None] if keep_dim else gray

        TransformObservation.__init__(  # type: ignore[misc]
            self, env=env, func=func, observation_space=Box(0, 255, shape, np.uint8)
        )


class ReshapeObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Reshape ``Box`` observations to ``shape`` (same number of elements; one ``-1`` allowed)."""

    def __init__(self, env: Env[ObsType, ActType], shape: int | tuple[int, ...]) -> None:
        space = env.observation_space
        if not isinstance(space, Box):
            raise TypeError(
                f"ReshapeObservation requires a Box observation space, got {type(space)}"
            )
        if not isinstance(shape, tuple):
            raise TypeError(f"ReshapeObservation requires shape to be a tuple, got {type(shape)}")
        if not all(np.issubdtype(type(d), np.integer) for d in shape):
            raise TypeError(
                f"ReshapeObservation requires shape elements to be integers, got {shape}"
            )
        if not all(d > 0 or d == -1 for d in shape):
            raise ValueError(
                "ReshapeObservation requires shape elements to be greater than 0 or -1, "
                f"got {shape}"
            )
        if -1 not in shape and np.prod(shape) != np.prod(space.shape):
            raise ValueError(
                f"ReshapeObservation requires the product of the new shape {shape} to match the "
                f"original shape {space.shape}"
            )
        new_space = Box(
            low=np.reshape(space.low, shape),
            high=np.reshape(space.high, shape),
            dtype=space.dtype,
        )
        RecordConstructorArgs.__init__(self, shape=shape)
        self.shape = shape
        new_shape = new_space.shape
        TransformObservation.__init__(  # type: ignore[misc]
            self,
            env=env,
            func=lambda obs: np.reshape(np.asarray(obs), new_shape),
            observation_space=new_space,
        )


class RescaleObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Affinely map a ``Box`` observation space onto ``[min_obs, max_obs]``."""

    def __init__(self, env: Env[ObsType, ActType], min_obs: Any, max_obs: Any) -> None:
        space = env.observation_space
        if not isinstance(space, Box):
            raise TypeError(
                f"RescaleObservation requires a Box observation space, got {type(space)}"
            )
        RecordConstructorArgs.__init__(self, min_obs=min_obs, max_obs=max_obs)
        new_space, forward, _ = rescale_box(space, min_obs, max_obs)
        TransformObservation.__init__(self, env=env, func=forward, observation_space=new_space)  # type: ignore[misc]


class DtypeObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Cast observations to ``dtype`` (Box, Discrete, MultiDiscrete and MultiBinary spaces)."""

    def __init__(self, env: Env[ObsType, ActType], dtype: Any) -> None:
        space = env.observation_space
        new_space: Space[Any]
        if isinstance(space, Box):
            new_space = Box(low=space.low, high=space.high, shape=space.shape, dtype=dtype)
        elif isinstance(space, Discrete):
            new_space = Box(low=space.start, high=space.start + space.n - 1, shape=(), dtype=dtype)
        elif isinstance(space, MultiDiscrete):
            new_space = MultiDiscrete(space.nvec, dtype=dtype, start=space.start)
        elif isinstance(space, MultiBinary):
            new_space = Box(low=0, high=1, shape=space.shape, dtype=dtype)
        else:
            raise TypeError(
                "DtypeObservation requires a Box, Discrete, MultiDiscrete, or MultiBinary space, "
                f"got {type(space)}"
            )
        RecordConstructorArgs.__init__(self, dtype=dtype)
        self.dtype = dtype
        cast = new_space.dtype.type
        TransformObservation.__init__(self, env=env, func=cast, observation_space=new_space)  # type: ignore[misc]


class AddRenderObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """The rendered frame as the observation (``render_only``, the default), or added to it:
    ``{obs_key: obs, render_key: frame}``, or the frame as one more key of a ``Dict``
    observation (Gymnasium's wrapper, once ``PixelObservationWrapper``)."""

    def __init__(
        self,
        env: Env[ObsType, ActType],
        render_only: bool = True,
        render_key: str = "pixels",
        obs_key: str = "state",
    ) -> None:
        RecordConstructorArgs.__init__(
            self, render_only=render_only, render_key=render_key, obs_key=obs_key
        )
        if env.render_mode is None or env.render_mode == "human":
            raise ValueError(
                "AddRenderObservation requires render_mode to be not None and not 'human', "
                f"got {env.render_mode}"
            )
        env.reset()  # a frame to size the space from (Gymnasium resets here too)
        pixels = env.render()
        if not isinstance(pixels, np.ndarray):
            raise TypeError(
                "AddRenderObservation expects env.render() to return a numpy array, got "
                f"{type(pixels)}"
            )
        pixel_space = Box(low=0, high=255, shape=pixels.shape, dtype=np.uint8)
        inner = env.observation_space
        space: Any
        func: Callable[[Any], Any]
        if render_only:
            space, func = pixel_space, lambda _: self.render()
        elif isinstance(inner, Dict):
            if render_key in inner.spaces:
                raise ValueError(
                    f"AddRenderObservation render_key {render_key!r} already exists in the "
                    "observation space"
                )
            space = Dict({render_key: pixel_space, **inner.spaces}, sort_keys=inner.sort_keys)
            func = lambda obs: {render_key: self.render(), **obs}  # noqa: E731
        else:
            space = Dict({obs_key: inner, render_key: pixel_space})
            func = lambda obs: {obs_key: obs, render_key: self.render()}  # noqa: E731
        TransformObservation.__init__(self, env, func, space)
