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
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.utils import rescale_box

__all__ = [
    "DiscretizeObservation",
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
        if not isinstance(filter_keys, Sequence) or isinstance(filter_keys, str):
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
        from palaestra.spaces.utils import flatten, flatten_space

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


class DiscretizeObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Bin a bounded ``Box`` observation uniformly: one ``Discrete`` index, or ``MultiDiscrete``.

    Each dimension ``i`` is cut into ``bins[i]`` equal intervals between its finite bounds;
    the ``Discrete`` index is the row-major (C order) flattening of the per-dimension indices,
    as in Gymnasium 1.4. Values outside the bounds fall into the first or last bin.
    """

    def __init__(
        self, env: Env[ObsType, ActType], bins: int | tuple[int, ...], multidiscrete: bool = False
    ) -> None:
        space = env.observation_space
        if not isinstance(space, Box):
            raise TypeError(
                f"DiscretizeObservation is only compatible with Box observations, got {space}"
            )
        self.low, self.high = np.ravel(space.low), np.ravel(space.high)
        self.n_dims = int(self.low.size)
        if not (np.all(np.isfinite(self.low)) and np.all(np.isfinite(self.high))):
            raise ValueError(
                "Discretization requires observation space to be finite. "
                f"Found: low={self.low}, high={self.high}"
            )
        self.bins = _bins_array(bins, self.n_dims)
        RecordConstructorArgs.__init__(self, bins=bins, multidiscrete=multidiscrete)
        self.multidiscrete = multidiscrete
        # Inner edges per dimension, padded with +inf so all dimensions vectorize together;
        # the bin index is the number of inner edges <= x, which is what np.digitize returns.
        width = int(self.bins.max()) - 1
        self._edges = np.full((self.n_dims, width), np.inf)
        for i in range(self.n_dims):
            self._edges[i, : self.bins[i] - 1] = np.linspace(
                self.low[i], self.high[i], self.bins[i] + 1
            )[1:-1]
        self._clip_high = self.high - 1e-8  # keeps x == high inside the last bin, as Gymnasium
        self._strides = np.array(
            [int(np.prod(self.bins[i + 1 :])) for i in range(self.n_dims)], dtype=np.int64
        )
        new_space: Space[Any] = (
            MultiDiscrete(self.bins) if multidiscrete else Discrete(int(np.prod(self.bins)))
        )
        TransformObservation.__init__(
            self, env=env, func=self._discretize, observation_space=new_space
        )

    def _discretize(self, observation: Any) -> Any:
        x = np.clip(np.ravel(observation), self.low, self._clip_high)
        indices = np.count_nonzero(self._edges <= x[:, None], axis=1).astype(np.int64)
        if self.multidiscrete:
            return indices
        return int(indices @ self._strides)

    def revert_observation(self, obs: Any) -> tuple[np.ndarray, np.ndarray]:
        """The ``(low, high)`` edges of the bin that the discrete observation ``obs`` stands for."""
        if self.multidiscrete:
            indices = np.asarray(obs, dtype=np.int64)
        else:
            indices = np.array(np.unravel_index(int(obs), tuple(self.bins)), dtype=np.int64)
        lows, highs = np.empty(self.n_dims), np.empty(self.n_dims)
        for i, idx in enumerate(indices):
            edges = np.linspace(self.low[i], self.high[i], self.bins[i] + 1)
            lows[i], highs[i] = edges[idx], edges[idx + 1]
        dtype = self.env.observation_space.dtype
        return lows.astype(dtype), highs.astype(dtype)


def _bins_array(bins: int | tuple[int, ...], n_dims: int) -> np.ndarray:
    """Validate ``bins`` (one count, or one per dimension) and return it as an int array."""
    if np.issubdtype(type(bins), np.integer):
        out = np.full(n_dims, int(bins))  # type: ignore[arg-type]
    else:
        if not isinstance(bins, (tuple, list)) or not all(
            np.issubdtype(type(b), np.integer) for b in bins
        ):
            raise TypeError(f"`bins` must be an int or a tuple of ints, got {bins!r}")
        if len(bins) != n_dims:
            raise ValueError(
                f"bins must match the space dimensions: expected {n_dims}, got {len(bins)}"
            )
        out = np.array(bins, dtype=np.int64)
    if np.any(out < 1):
        raise ValueError(f"Every entry of `bins` must be at least 1, got {bins!r}")
    return out
