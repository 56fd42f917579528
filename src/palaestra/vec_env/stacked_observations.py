"""``StackedObservations``: SB3's frame-stacking buffer, usable without a ``VecEnv``.

The last ``n_stack`` observations of each of ``num_envs`` envs, concatenated along the channel
axis ("first" or "last"; None: first only for channel-first uint8 images). A ``Dict`` space gets
one stack per key. ``update`` also completes a finished env's ``terminal_observation`` into a
full stack and restarts that env's stack from zeros, as SB3 does.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from palaestra.spaces import Box, Dict

_ORDERS = ("first", "last")


def _channels_first(space: Box, channels_order: str | None) -> bool:
    if channels_order is None:
        # SB3's image test (uint8, rank 3, bounds [0, 255]); channels first when the first
        # axis is the smallest.
        image = (
            len(space.shape) == 3
            and space.dtype == np.uint8
            and bool(np.all(space.low == 0))
            and bool(np.all(space.high == 255))
        )
        return image and int(np.argmin(space.shape)) == 0
    if channels_order not in _ORDERS:
        raise ValueError(
            f"`channels_order` must be one of {_ORDERS} or None, got {channels_order!r}"
        )
    return channels_order == "first"


class StackedObservations:
    """Stacks of observations for ``num_envs`` envs (``stacked_observation_space``: their
    space)."""

    RUN_STATE: tuple[str, ...]  # exact resume (utils.run_state): the stacks, per key for a Dict

    def __init__(
        self,
        num_envs: int,
        n_stack: int,
        observation_space: Box | Dict,
        channels_order: str | Mapping[str, str | None] | None = None,
    ) -> None:
        self.n_stack = n_stack
        self.observation_space = observation_space
        self.stacked_observation_space: Box | Dict
        if isinstance(observation_space, Dict):
            orders = (
                channels_order
                if isinstance(channels_order, Mapping)
                else dict.fromkeys(observation_space.spaces, channels_order)
            )
            self.sub_stacked_observations = {
                key: StackedObservations(num_envs, n_stack, sub, orders[key])  # type: ignore[arg-type]
                for key, sub in observation_space.spaces.items()
            }
            self.stacked_observation_space = Dict(
                {k: s.stacked_observation_space for k, s in self.sub_stacked_observations.items()}
            )
            self.RUN_STATE = ("sub_stacked_observations",)
            return
        if not isinstance(observation_space, Box):
            raise TypeError(
                "StackedObservations only supports Box and Dict as observation spaces. "
                f"{observation_space} was provided."
            )
        if isinstance(channels_order, Mapping):
            raise TypeError("When the observation space is Box, channels_order can't be a dict.")
        (
            self.channels_first,
            self.stack_dimension,
            self.stacked_shape,
            self.repeat_axis,
        ) = self.compute_stacking(n_stack, observation_space, channels_order)
        self.stacked_observation_space = Box(
            low=np.repeat(observation_space.low, n_stack, axis=self.repeat_axis),
            high=np.repeat(observation_space.high, n_stack, axis=self.repeat_axis),
            dtype=observation_space.dtype,
        )
        # [num_envs, *stacked_shape]
        self.stacked_obs = np.zeros((num_envs, *self.stacked_shape), dtype=observation_space.dtype)
        self.RUN_STATE = ("stacked_obs",)

    @staticmethod
    def compute_stacking(
        n_stack: int, observation_space: Box, channels_order: str | None = None
    ) -> tuple[bool, int, tuple[int, ...], int]:
        """``(channels_first, stack_dimension, stacked_shape, repeat_axis)``: the axis of a
        batch to roll (1 or -1) and the axis of one observation to repeat (0 or -1)."""
        first = _channels_first(observation_space, channels_order)
        repeat_axis = 0 if first else -1
        shape = list(observation_space.shape)
        shape[repeat_axis] *= n_stack
        return first, 1 if first else -1, tuple(shape), repeat_axis

    def _write_newest(self, observations: np.ndarray) -> None:
        channels = observations.shape[self.stack_dimension]
        if self.channels_first:
            self.stacked_obs[:, -channels:, ...] = observations
        else:
            self.stacked_obs[..., -channels:] = observations

    def reset(self, observation: Any) -> Any:
        """Zero the stacks, push ``observation`` (a batch); the stacked batch."""
        if isinstance(observation, dict):
            return {k: self.sub_stacked_observations[k].reset(v) for k, v in observation.items()}
        self.stacked_obs[...] = 0
        self._write_newest(observation)
        return self.stacked_obs

    def update(
        self, observations: Any, dones: np.ndarray, infos: list[dict[str, Any]]
    ) -> tuple[Any, list[dict[str, Any]]]:
        """Push a batch; ``(stacked batch, infos)`` with finished envs' terminal observations
        stacked too."""
        if isinstance(observations, dict):
            stacked = {}
            for key, obs in observations.items():
                sub_infos = [
                    {"terminal_observation": info["terminal_observation"][key]}
                    if "terminal_observation" in info
                    else {}
                    for info in infos
                ]
                stacked[key], sub_infos = self.sub_stacked_observations[key].update(
                    obs, dones, sub_infos
                )
                for info, sub in zip(infos, sub_infos):
                    if "terminal_observation" in info:
                        info["terminal_observation"][key] = sub["terminal_observation"]
            return stacked, infos
        shift = -observations.shape[self.stack_dimension]
        self.stacked_obs = np.roll(self.stacked_obs, shift, axis=self.stack_dimension)
        for i in np.flatnonzero(dones).tolist():
            if "terminal_observation" in infos[i]:
                older = (
                    self.stacked_obs[i, :shift, ...]
                    if self.channels_first
                    else self.stacked_obs[i, ..., :shift]
                )
                infos[i]["terminal_observation"] = np.concatenate(
                    (older, infos[i]["terminal_observation"]), axis=self.repeat_axis
                )
            else:
                warnings.warn(
                    "VecFrameStack wrapping a VecEnv without terminal_observation info",
                    stacklevel=2,
                )
            self.stacked_obs[i] = 0
        self._write_newest(observations)
        return self.stacked_obs, infos
