"""Observation wrappers with memory across steps (Gymnasium 1.x semantics).

* ``DelayObservation`` - return the observation from ``delay`` steps ago (zeros before that)
* ``TimeAwareObservation`` - append the step count within the episode
* ``NormalizeObservation`` - standardize with a running mean and variance
* ``MaxAndSkipObservation`` - repeat an action ``skip`` times, max over the last two frames

``FrameStackObservation`` lives in :mod:`palaestra.wrappers.frame_stack`.
"""

from __future__ import annotations

from collections import deque
from functools import partial
from typing import Any, SupportsFloat

import numpy as np

from palaestra.core import ActType, Env, ObservationWrapper, ObsType, Wrapper, WrapperObsType
from palaestra.error import InvalidBound
from palaestra.spaces import Box, Dict, Space, Tuple
from palaestra.spaces.utils import flatten as flatten_obs
from palaestra.spaces.utils import flatten_space
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.common import TimeLimit
from palaestra.wrappers.running_mean_std import RunningMeanStd
from palaestra.wrappers.utils import create_zero_array

__all__ = [
    "DelayObservation",
    "MaxAndSkipObservation",
    "NormalizeObservation",
    "TimeAwareObservation",
]


def _check_int(value: Any, name: str, minimum: int) -> int:
    """``value`` as an int, or a TypeError/ValueError naming it and the expectation."""
    if isinstance(value, bool) or not np.issubdtype(type(value), np.integer):
        raise TypeError(f"The {name} is expected to be an integer, actual type: {type(value)}")
    if value < minimum:
        raise ValueError(f"The {name} needs to be at least {minimum}, actual value: {value}")
    return int(value)


class DelayObservation(ObservationWrapper[ObsType, ActType, ObsType], RecordConstructorArgs):
    """Return the observation from ``delay`` steps earlier; the first ``delay`` observations of
    an episode are the zero element of the observation space."""

    def __init__(self, env: Env[ObsType, ActType], delay: int) -> None:
        delay = _check_int(delay, "delay", 0)
        RecordConstructorArgs.__init__(self, delay=delay)
        ObservationWrapper.__init__(self, env)
        self.delay = delay
        self.observation_queue: deque[Any] = deque()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env and forget the queued observations."""
        self.observation_queue.clear()
        return super().reset(seed=seed, options=options)

    def observation(self, observation: ObsType) -> ObsType:
        """Queue ``observation`` and return the one ``delay`` steps old."""
        self.observation_queue.append(observation)
        if len(self.observation_queue) > self.delay:
            return self.observation_queue.popleft()
        # a fresh zero each time: the caller may keep or mutate what we return
        return create_zero_array(self.observation_space)


def _find_max_episode_steps(env: Env[Any, Any]) -> int | None:
    if env.spec is not None and env.spec.max_episode_steps is not None:
        return int(env.spec.max_episode_steps)
    layer: Env[Any, Any] = env
    while isinstance(layer, Wrapper):
        if isinstance(layer, TimeLimit):
            return int(layer._max_episode_steps)
        layer = layer.env
    return None


class TimeAwareObservation(
    ObservationWrapper[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Add the number of steps taken in the episode to each observation.

    ``Dict`` spaces gain the key ``dict_time_key``, ``Tuple`` spaces a last element, others
    become ``Dict(obs=..., time=...)``; ``flatten=True`` (default) flattens the result to a
    ``Box``. Time is an ``int32`` count, or the fraction of the episode's step limit when
    ``normalize_time``. Needs a ``TimeLimit`` in the stack or ``spec.max_episode_steps``.

    >>> import palaestra as gym
    >>> env = TimeAwareObservation(gym.make("CartPole-v1"), flatten=False)
    >>> env.observation_space["time"]
    Box(0, 500, (1,), int32)
    >>> env.reset(seed=42)[0]["time"], env.step(1)[0]["time"]
    (array([0], dtype=int32), array([1], dtype=int32))
    """

    def __init__(
        self,
        env: Env[ObsType, ActType],
        flatten: bool = True,
        normalize_time: bool = False,
        *,
        dict_time_key: str = "time",
    ) -> None:
        RecordConstructorArgs.__init__(
            self, flatten=flatten, normalize_time=normalize_time, dict_time_key=dict_time_key
        )
        ObservationWrapper.__init__(self, env)
        max_steps = _find_max_episode_steps(env)
        if max_steps is None:
            raise ValueError(
                "The environment must be wrapped by a TimeLimit wrapper or the spec specify a "
                "`max_episode_steps`."
            )
        self.max_timesteps = max_steps
        self.flatten = flatten
        self.normalize_time = normalize_time
        self.timesteps = 0

        time_space: Box = Box(0.0, 1.0) if normalize_time else Box(0, max_steps, dtype=np.int32)
        inner = env.observation_space
        space: Space[Any]
        if isinstance(inner, Dict):
            if dict_time_key in inner.spaces:
                raise ValueError(
                    f"The `dict_time_key` ({dict_time_key!r}) already exists in the observation "
                    "space."
                )
            space = Dict({dict_time_key: time_space, **inner.spaces}, sort_keys=inner.sort_keys)
            self._kind = "dict"
        elif isinstance(inner, Tuple):
            space = Tuple((*inner.spaces, time_space))
            self._kind = "tuple"
        else:
            space = Dict(obs=inner, time=time_space)
            self._kind = "obs"
        self._dict_time_key = dict_time_key
        self._unflat_space = space
        if flatten:
            self._flatten = partial(flatten_obs, space)
            self.observation_space = flatten_space(space)
        else:
            self.observation_space = space

    def _time(self) -> np.ndarray:
        if self.normalize_time:
            return np.array([self.timesteps / self.max_timesteps], dtype=np.float32)
        return np.array([self.timesteps], dtype=np.int32)

    def observation(self, observation: ObsType) -> WrapperObsType:
        """Return ``observation`` with the current step count attached."""
        time = self._time()
        out: Any
        if self._kind == "dict":
            out = {self._dict_time_key: time, **observation}  # type: ignore[dict-item]
        elif self._kind == "tuple":
            out = (*observation, time)  # type: ignore[misc]
        else:
            out = {"obs": observation, "time": time}
        return self._flatten(out) if self.flatten else out

    def step(
        self, action: ActType
    ) -> tuple[WrapperObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Count the step, then step the inner env."""
        self.timesteps += 1
        return super().step(action)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[WrapperObsType, dict[str, Any]]:
        """Reset the inner env and the step count."""
        self.timesteps = 0
        return super().reset(seed=seed, options=options)


class NormalizeObservation(
    ObservationWrapper[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Standardize observations with a running mean and variance, cast to ``float32``.

    Set :attr:`update_running_mean` to ``False`` to freeze the statistics (e.g. for evaluation).
    """

    def __init__(self, env: Env[ObsType, ActType], epsilon: float = 1e-8) -> None:
        # epsilon keeps the division away from zero; a non-positive one can make it NaN.
        if not epsilon > 0:
            raise InvalidBound(f"`epsilon` should be strictly positive. Received {epsilon}")
        RecordConstructorArgs.__init__(self, epsilon=epsilon)
        ObservationWrapper.__init__(self, env)
        shape = env.observation_space.shape
        if shape is None:
            raise ValueError(
                "NormalizeObservation wrapper requires the observation space to have a shape, "
                f"got {env.observation_space}"
            )
        self.observation_space = Box(-np.inf, np.inf, shape=shape, dtype=np.float32)
        self.obs_rms = RunningMeanStd(shape=shape, dtype=np.float32)
        self.epsilon = epsilon
        self._update_running_mean = True

    @property
    def update_running_mean(self) -> bool:
        """Whether each observation still updates the statistics."""
        return self._update_running_mean

    @update_running_mean.setter
    def update_running_mean(self, setting: bool) -> None:
        self._update_running_mean = setting

    def observation(self, observation: ObsType) -> WrapperObsType:
        """Update the statistics (unless frozen) and return the standardized observation."""
        obs = np.asarray(observation)
        if self._update_running_mean:
            self.obs_rms.update_one(obs)
        return np.float32(  # type: ignore[return-value]
            (obs - self.obs_rms.mean) / np.sqrt(self.obs_rms.var + self.epsilon)
        )


class MaxAndSkipObservation(
    Wrapper[WrapperObsType, ActType, ObsType, ActType], RecordConstructorArgs
):
    """Repeat each action ``skip`` times, sum the rewards, and return the elementwise max of the
    last two observations (the Atari frame-skip of SB3 and Gymnasium)."""

    def __init__(self, env: Env[ObsType, ActType], skip: int = 4) -> None:
        skip = _check_int(skip, "skip", 2)
        RecordConstructorArgs.__init__(self, skip=skip)
        Wrapper.__init__(self, env)
        shape = env.observation_space.shape
        if shape is None:
            raise ValueError(
                f"The observation space must have a shape, got {env.observation_space}"
            )
        self._skip = skip
        # [2, *obs_shape]: the last two frames. Like Gymnasium, a frame left from an earlier
        # step stays in slot 0 when an episode ends before the second-to-last repeat.
        self._obs_buffer = np.zeros((2, *shape), dtype=env.observation_space.dtype)

    def step(
        self, action: ActType
    ) -> tuple[WrapperObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step ``skip`` times (fewer if the episode ends) with ``action``."""
        total_reward = 0.0
        terminated = truncated = False
        info: dict[str, Any] = {}
        for i in range(self._skip):
            obs, reward, terminated, truncated, info = self.env.step(action)
            if i >= self._skip - 2:
                self._obs_buffer[i - self._skip + 2] = obs
            total_reward += float(reward)
            if terminated or truncated:
                break
        return self._obs_buffer.max(axis=0), total_reward, terminated, truncated, info
