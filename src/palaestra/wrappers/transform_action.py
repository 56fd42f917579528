"""Stateless action wrappers: each maps the agent's action through one fixed function.

``TransformAction`` is the general one; ``ClipAction``, ``RescaleAction`` and
``DiscretizeAction`` pick the function and the action space the agent sees (Gymnasium 1.x).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from palaestra.core import ActionWrapper, ActType, Env, ObsType, WrapperActType
from palaestra.error import InvalidBound
from palaestra.spaces import Box, Space
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.utils import _as_bound, rescale_box

__all__ = ["ClipAction", "RescaleAction", "TransformAction"]


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
    """Clip actions into the inner ``Box``; the agent sees an unbounded ``Box`` of that shape.

    >>> import palaestra as gym
    >>> env = ClipAction(gym.make("Pendulum-v1"))
    >>> env.action_space, env.action(np.array([5.0], dtype=np.float32))
    (Box(-inf, inf, (1,), float32), array([2.], dtype=float32))
    """

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
    inner ``Box``. Bounds are scalars or arrays of the action shape.

    >>> import palaestra as gym
    >>> env = RescaleAction(gym.make("Pendulum-v1"), np.float32(0), np.float32(1))
    >>> env.action_space, env.action(np.array([0.0, 0.5, 1.0], dtype=np.float32))
    (Box(0.0, 1.0, (1,), float32), array([-2.,  0.,  2.], dtype=float32))
    """

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
