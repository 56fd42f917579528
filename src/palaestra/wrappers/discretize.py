"""Uniform binning of bounded ``Box`` spaces: ``DiscretizeObservation`` and ``DiscretizeAction``.

Both follow Gymnasium 1.4: each dimension ``i`` of the ``Box`` is cut into ``bins[i]`` equal
intervals between its finite bounds, and the single ``Discrete`` index is the row-major (C order)
flattening of the per-dimension indices; ``multidiscrete=True`` exposes ``MultiDiscrete(bins)``
instead. Work is vectorized over dimensions (no per-dimension Python loop per step).
"""

from __future__ import annotations

import operator
from typing import Any

import numpy as np

from palaestra.core import ActType, Env, ObsType, WrapperActType, WrapperObsType
from palaestra.error import InvalidAction
from palaestra.spaces import Box, Discrete, MultiDiscrete, Space
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.transform_action import TransformAction
from palaestra.wrappers.transform_observation import TransformObservation

__all__ = ["DiscretizeAction", "DiscretizeObservation"]


class DiscretizeObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Bin a bounded ``Box`` observation uniformly: one ``Discrete`` index, or ``MultiDiscrete``.

    Each dimension ``i`` is cut into ``bins[i]`` equal intervals between its finite bounds;
    the ``Discrete`` index is the row-major (C order) flattening of the per-dimension indices,
    as in Gymnasium 1.4. Values outside the bounds fall into the first or last bin.

    >>> import palaestra as gym
    >>> env = DiscretizeObservation(gym.make("MountainCar-v0"), bins=10)
    >>> env.observation_space
    Discrete(100)
    >>> env.reset(seed=42)
    (45, {})
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


class DiscretizeAction(TransformAction[ObsType, WrapperActType, ActType], RecordConstructorArgs):
    """Expose a bounded ``Box`` action space as ``Discrete(prod(bins))`` or ``MultiDiscrete(bins)``.

    Each discrete choice maps to the centre of a uniform bin per dimension; the ``Discrete``
    index is the row-major (C order) flattening of the per-dimension bins, as in Gymnasium 1.4.
    Out-of-range indices raise :class:`palaestra.error.InvalidAction` (Gymnasium clamps them).

    >>> import palaestra as gym
    >>> env = DiscretizeAction(gym.make("Pendulum-v1"), bins=5)
    >>> env.action_space, env.action(0), env.action(4)
    (Discrete(5), array([-1.6], dtype=float32), array([1.6], dtype=float32))
    """

    _MAX_TABLE = 1 << 16  # entries of the precomputed action table

    def __init__(
        self, env: Env[ObsType, ActType], bins: int | tuple[int, ...], multidiscrete: bool = False
    ) -> None:
        space = env.action_space
        if not isinstance(space, Box):
            raise TypeError(f"DiscretizeAction is only compatible with Box actions, got {space}")
        self.low, self.high = np.ravel(space.low), np.ravel(space.high)
        self.n_dims = int(self.low.size)
        if not (np.all(np.isfinite(self.low)) and np.all(np.isfinite(self.high))):
            raise ValueError(
                "Discretization requires action space to be finite. "
                f"Found: low={self.low}, high={self.high}"
            )
        self.bins = _bins_array(bins, self.n_dims)
        RecordConstructorArgs.__init__(self, bins=bins, multidiscrete=multidiscrete)
        self.multidiscrete = multidiscrete
        self.bin_centers = []
        # [n_dims, max_bins] centres, +inf padded so revert_action's argmin ignores the padding
        self._centers = np.full((self.n_dims, int(self.bins.max())), np.inf)
        for i in range(self.n_dims):
            edges = np.linspace(self.low[i], self.high[i], self.bins[i] + 1)
            centers = 0.5 * (edges[:-1] + edges[1:])
            self.bin_centers.append(centers)
            self._centers[i, : self.bins[i]] = centers
        self._dims = np.arange(self.n_dims)
        self._strides = np.array(
            [int(np.prod(self.bins[i + 1 :])) for i in range(self.n_dims)], dtype=np.int64
        )
        self._n = int(np.prod(self.bins))
        self._inner_dtype, self._inner_shape = space.dtype, space.shape
        # Every continuous action precomputed when the table is small (a row lookup per step);
        # large products of bins fall back to computing the centres per step.
        self._table: np.ndarray | None = None
        if self._n * self.n_dims <= self._MAX_TABLE:
            all_indices = np.array(np.unravel_index(np.arange(self._n), tuple(self.bins))).T
            self._table = np.stack([self._centers_of(row) for row in all_indices])
        new_space: Space[Any] = MultiDiscrete(self.bins) if multidiscrete else Discrete(self._n)
        TransformAction.__init__(self, env=env, func=self._continuous, action_space=new_space)  # type: ignore[arg-type]

    def _continuous(self, action: Any) -> np.ndarray:
        if self.multidiscrete:
            indices = np.asarray(action, dtype=np.int64).ravel()
            if (
                indices.shape != (self.n_dims,)
                or np.any(indices < 0)
                or np.any(indices >= self.bins)
            ):
                raise InvalidAction(
                    f"Action {action!r} is not in the action space {self.action_space}"
                )
            if self._table is not None:
                return self._table[int(indices @ self._strides)].copy()
        else:
            try:
                index = operator.index(action)  # int, numpy integer or 0-d integer array
            except TypeError:
                index = -1
            if not 0 <= index < self._n:
                raise InvalidAction(
                    f"Action {action!r} is not in the action space {self.action_space}"
                )
            if self._table is not None:
                return self._table[index].copy()  # a fresh array: the env may keep it
            indices = (index // self._strides) % self.bins
        return self._centers_of(indices)

    def _centers_of(self, indices: np.ndarray) -> np.ndarray:
        values = self._centers[self._dims, indices]
        return values.astype(self._inner_dtype).reshape(self._inner_shape)

    def revert_action(self, action: Any) -> Any:
        """The discrete action whose bin centre is closest to the continuous ``action``."""
        x = np.ravel(action)
        indices = np.argmin(np.abs(self._centers - x[:, None]), axis=1)
        if self.multidiscrete:
            return indices.astype(int)
        return np.ravel_multi_index(tuple(indices), tuple(self.bins))
