"""Action wrappers with memory: ``StickyAction`` and ``RepeatAction`` (Gymnasium 1.x)."""

from __future__ import annotations

from typing import Any, SupportsFloat

import numpy as np

from palaestra.core import ActionWrapper, ActType, Env, ObsType, Wrapper
from palaestra.error import InvalidBound, InvalidProbability
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.stateful_observation import _check_int

__all__ = ["RepeatAction", "StickyAction"]


class StickyAction(ActionWrapper[ObsType, ActType, ActType], RecordConstructorArgs):
    """With probability ``repeat_action_probability`` the env repeats the previous action
    instead of the agent's (Machado et al., 2018, section 5.2), for ``repeat_action_duration``
    steps: an int, or an inclusive ``(low, high)`` range drawn from per repeat series.

    Draws come from the env's ``np_random``, so a seeded env sticks at the same steps as
    Gymnasium's wrapper.
    """

    def __init__(
        self,
        env: Env[ObsType, ActType],
        repeat_action_probability: float,
        repeat_action_duration: int | tuple[int, int] = 1,
    ) -> None:
        if not 0 <= repeat_action_probability < 1:
            raise InvalidProbability(
                "`repeat_action_probability` should be in the interval [0,1). "
                f"Received {repeat_action_probability}"
            )
        if isinstance(repeat_action_duration, (int, np.integer)):
            duration = (int(repeat_action_duration), int(repeat_action_duration))
        elif isinstance(repeat_action_duration, tuple):  # not a list: Gymnasium refuses one
            if len(repeat_action_duration) != 2:
                raise ValueError(
                    "`repeat_action_duration` should be a tuple or a list of two integers. "
                    f"Received {repeat_action_duration}"
                )
            duration = (repeat_action_duration[0], repeat_action_duration[1])
        else:
            raise ValueError(
                "`repeat_action_duration` should be either an integer or a tuple. "
                f"Received {repeat_action_duration}"
            )
        if duration[0] > duration[1]:
            raise InvalidBound(
                f"`repeat_action_duration` is not a valid bound. Received {repeat_action_duration}"
            )
        if duration[0] < 1:
            raise ValueError(
                "`repeat_action_duration` should be larger or equal than 1. "
                f"Received {repeat_action_duration}"
            )
        RecordConstructorArgs.__init__(
            self,
            repeat_action_probability=repeat_action_probability,
            repeat_action_duration=repeat_action_duration,
        )
        ActionWrapper.__init__(self, env)
        self.repeat_action_probability = repeat_action_probability
        self.repeat_action_duration_range = duration
        self.last_action: ActType | None = None
        self.is_sticky_actions = False  # inside a series of repeats
        self.num_repeats = 0  # length of the current series
        self.repeats_taken = 0  # repeats done in the current series

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env; the next action is never sticky."""
        self.last_action = None
        self.is_sticky_actions = False
        self.num_repeats = 0
        self.repeats_taken = 0
        return super().reset(seed=seed, options=options)

    def action(self, action: ActType) -> ActType:
        """The action to execute: the agent's, or the previous one while stuck."""
        # The uniform draw happens only outside a series, exactly where Gymnasium draws, so
        # seeded runs consume the generator identically.
        if self.is_sticky_actions or (
            self.last_action is not None
            and self.np_random.uniform() < self.repeat_action_probability
        ):
            if self.num_repeats == 0:
                low, high = self.repeat_action_duration_range
                self.num_repeats = int(self.np_random.integers(low, high + 1))
            action = self.last_action  # type: ignore[assignment]
            self.is_sticky_actions = True
            self.repeats_taken += 1
        if self.is_sticky_actions and self.num_repeats == self.repeats_taken:
            self.is_sticky_actions = False
            self.num_repeats = 0
            self.repeats_taken = 0
        self.last_action = action
        return action


class RepeatAction(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Execute each action ``num_repeats`` times, summing the rewards; stops early when the
    episode terminates or is truncated and returns the last observation and info."""

    def __init__(self, env: Env[ObsType, ActType], num_repeats: int) -> None:
        num_repeats = _check_int(num_repeats, "num_repeats", 1)
        RecordConstructorArgs.__init__(self, num_repeats=num_repeats)
        Wrapper.__init__(self, env)
        self.num_repeats = num_repeats

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step ``num_repeats`` times (fewer if the episode ends) with ``action``."""
        total_reward = 0.0
        for _ in range(self.num_repeats):
            obs, reward, terminated, truncated, info = self.env.step(action)
            total_reward += float(reward)
            if terminated or truncated:
                break
        return obs, total_reward, terminated, truncated, info
