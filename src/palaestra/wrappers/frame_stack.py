"""``FrameStackObservation``: the last ``stack_size`` observations, batched along a new axis."""

from __future__ import annotations

from collections import deque
from typing import Any, SupportsFloat

import numpy as np

from palaestra.core import ActType, Env, ObsType, Wrapper, WrapperObsType
from palaestra.spaces import Box
from palaestra.spaces.batching import batch_space, concatenate, create_empty_array
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.stateful_observation import _check_int
from palaestra.wrappers.utils import create_zero_array

__all__ = ["FrameStackObservation"]


class FrameStackObservation(
    Wrapper[WrapperObsType, ActType, ObsType, ActType], RecordConstructorArgs
):
    """Return the last ``stack_size`` observations stacked along a new first axis.

    The observation space is ``batch_space(inner_space, stack_size)``, e.g. ``Box (4, 96, 96, 3)``
    for 4 frames of ``(96, 96, 3)``. At reset the older slots are filled with ``padding_type``:
    ``"reset"`` (the first observation repeated, default), ``"zero"`` (the space's zero element)
    or a custom element of the inner observation space.

    >>> import palaestra as gym
    >>> env = FrameStackObservation(gym.make("CartPole-v1"), 3, padding_type="zero")
    >>> env.observation_space.shape
    (3, 4)
    >>> env.reset(seed=123)[0]
    array([[ 0.        ,  0.        ,  0.        ,  0.        ],
           [ 0.        ,  0.        ,  0.        ,  0.        ],
           [ 0.01823519, -0.0446179 , -0.02796401, -0.03156282]],
          dtype=float32)
    """

    def __init__(
        self, env: Env[ObsType, ActType], stack_size: int, *, padding_type: str | ObsType = "reset"
    ) -> None:
        RecordConstructorArgs.__init__(self, stack_size=stack_size, padding_type=padding_type)
        Wrapper.__init__(self, env)
        stack_size = _check_int(stack_size, "stack_size", 1)
        space = env.observation_space
        if isinstance(padding_type, str) and padding_type in ("reset", "zero"):
            self.padding_value: Any = create_zero_array(space)
        elif not isinstance(padding_type, str) and padding_type in space:
            self.padding_value = padding_type
            padding_type = "_custom"
        else:
            raise ValueError(
                "Unexpected `padding_type`, expected 'reset', 'zero' or an element of the "
                f"observation space {space}, actual value: {padding_type!r}"
            )
        self.observation_space = batch_space(space, n=stack_size)
        self.stack_size = stack_size
        self.padding_type: str = padding_type
        self._inner_space = space
        self._box_shape = (stack_size, *space.shape) if isinstance(space, Box) else None
        self.obs_queue: deque[Any] = deque([self.padding_value] * stack_size, maxlen=stack_size)

    def _stacked(self) -> WrapperObsType:
        # A fresh output each call (callers keep observations in replay buffers), written once:
        # no deepcopy of a shared buffer as in Gymnasium. Box observations take the short road
        # (np.array over the deque is ~4x cheaper than the generic batching helpers).
        if self._box_shape is not None:
            out = np.array(self.obs_queue, dtype=self._inner_space.dtype)
            if out.shape != self._box_shape:
                raise ValueError(
                    f"FrameStackObservation got observations of shape {out.shape[1:]}, "
                    f"expected {self._box_shape[1:]} from {self._inner_space}"
                )
            return out  # type: ignore[return-value]
        empty = create_empty_array(self._inner_space, n=self.stack_size)
        return concatenate(self._inner_space, self.obs_queue, empty)

    def step(
        self, action: ActType
    ) -> tuple[WrapperObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner env and push its observation onto the stack."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.obs_queue.append(obs)
        return self._stacked(), reward, terminated, truncated, info

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[WrapperObsType, dict[str, Any]]:
        """Reset the inner env and refill the stack with padding and the first observation."""
        obs, info = self.env.reset(seed=seed, options=options)
        if self.padding_type == "reset":
            self.padding_value = obs
        for _ in range(self.stack_size - 1):
            self.obs_queue.append(self.padding_value)
        self.obs_queue.append(obs)
        return self._stacked(), info
