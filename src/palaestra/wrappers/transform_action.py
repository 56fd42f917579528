"""Stateless action wrappers: each maps the agent's action through one fixed function.

``TransformAction`` is the general one; ``ClipAction``, ``RescaleAction`` and
``DiscretizeAction`` pick the function and the action space the agent sees (Gymnasium 1.x).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from palaestra.core import ActionWrapper, ActType, Env, ObsType, WrapperActType
from palaestra.error import InvalidAction, InvalidBound
from palaestra.spaces import Box, Discrete, MultiDiscrete, Space
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.transform_observation import _bins_array
from palaestra.wrappers.utils import _as_bound, rescale_box

__all__ = ["ClipAction", "DiscretizeAction", "RescaleAction", "TransformAction"]


class TransformAction(ActionWrapper[ObsType, WrapperActType, ActType], RecordConstructorArgs):
    """Pass ``func(action)`` to the inner env; ``action_space`` is what the agent now sees
    (``None`` keeps the inner one)."""

    def __init__(
        self,
        env: Env[ObsType, ActType],
        func: Callable[[WrapperActType], ActType],
        action_space: Space[WrapperActType] | None,
    ) -> None:
        RecordConstructorArgs.__init__(self, func=func, action_space=action_space)
        ActionWrapper.__init__(self, env)
        if not callable(func):
            raise TypeError(f"Expected `func` to be callable, got {func!r}")
        if action_space is not None:
            self.action_space = action_space
        self.func = func

    def action(self, action: WrapperActType) -> ActType:
        """Return ``func(action)``."""
        return self.func(action)


def _require_box(env: Env[Any, Any], wrapper: str) -> Box:
    space = env.action_space
    if not isinstance(space, Box):
        raise TypeError(f"{wrapper} requires a Box action space, got {type(space)}: {space}")
    return space


class ClipAction(TransformAction[ObsType, WrapperActType, ActType], RecordConstructorArgs):
    """Clip actions into the inner ``Box``; the agent sees an unbounded ``Box`` of that shape."""

    def __init__(self, env: Env[ObsType, ActType]) -> None:
        space = _require_box(env, "ClipAction")
        RecordConstructorArgs.__init__(self)
        low, high = space.low, space.high  # bound once, not looked up every step
        TransformAction.__init__(  # type: ignore[misc]
            self,
            env=env,
            func=lambda action: np.clip(action, low, high),
            action_space=Box(-np.inf, np.inf, shape=space.shape, dtype=space.dtype),
        )


class RescaleAction(TransformAction[ObsType, WrapperActType, ActType], RecordConstructorArgs):
    """Let the agent act in ``[min_action, max_action]``; actions are mapped affinely onto the
    inner ``Box``. Bounds are scalars or arrays of the action shape."""

    def __init__(self, env: Env[ObsType, ActType], min_action: Any, max_action: Any) -> None:
        space = _require_box(env, "RescaleAction")
        RecordConstructorArgs.__init__(self, min_action=min_action, max_action=max_action)
        low = _as_bound(min_action, space.shape, "new_min")
        if np.any(low > _as_bound(max_action, space.shape, "new_max")):
            raise ValueError(
                f"Min action ({min_action}) must be smaller than max action ({max_action})"
            )
        new_space, _, backward = rescale_box(space, min_action, max_action)
        # The wrapper applies the inverse map, which does not exist for a zero-width range.
        if np.any(new_space.low == new_space.high):
            raise InvalidBound(
                f"Min action ({min_action}) must be strictly smaller than max action "
                f"({max_action}), the rescaling has no inverse where they are equal"
            )
        TransformAction.__init__(self, env=env, func=backward, action_space=new_space)  # type: ignore[misc]


class DiscretizeAction(TransformAction[ObsType, WrapperActType, ActType], RecordConstructorArgs):
    """Expose a bounded ``Box`` action space as ``Discrete(prod(bins))`` or ``MultiDiscrete(bins)``.

    Each discrete choice maps to the centre of a uniform bin per dimension; the ``Discrete``
    index is the row-major (C order) flattening of the per-dimension bins, as in Gymnasium 1.4.
    Out-of-range indices raise :class:`palaestra.error.InvalidAction` (Gymnasium clamps them).
    """

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
        else:
            if not np.issubdtype(np.asarray(action).dtype, np.integer) or not 0 <= action < self._n:
                raise InvalidAction(
                    f"Action {action!r} is not in the action space {self.action_space}"
                )
            indices = (int(action) // self._strides) % self.bins
        values = self._centers[self._dims, indices]
        return values.astype(self._inner_dtype).reshape(self._inner_shape)

    def revert_action(self, action: Any) -> Any:
        """The discrete action whose bin centre is closest to the continuous ``action``."""
        x = np.ravel(action)
        indices = np.argmin(np.abs(self._centers - x[:, None]), axis=1)
        if self.multidiscrete:
            return indices.astype(int)
        return np.ravel_multi_index(tuple(indices), tuple(self.bins))
