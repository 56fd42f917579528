"""MountainCar-v0: a car in a valley must rock back and forth to reach the flag.

Physics equal to Gymnasium 1.x's ``MountainCarEnv`` (Moore 1990): same constants, same float64
arithmetic in the same order (``math.cos`` there, which numpy matches bit for bit, see
``_ops``), same reset draw, reward -1 per step.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.action_checks import check_discrete_action
from palaestra.envs.classic_control._common import (
    RENDER_MODES,
    ClassicControlEnv,
    expose_params,
    parse_reset_bounds,
    state_array,
)
from palaestra.envs.classic_control._ops import ARRAY, SCALAR
from palaestra.envs.classic_control.batched import BatchedEnv
from palaestra.rendering.scenes import render_mountain_car
from palaestra.spaces import Box, Discrete


@dataclass(frozen=True)
class MountainCarParams:
    """Gymnasium's MountainCar constants."""

    min_position: float = -1.2
    max_position: float = 0.6
    max_speed: float = 0.07
    goal_position: float = 0.5
    goal_velocity: float = 0
    force: float = 0.001
    gravity: float = 0.0025


def step_state(ops: Any, p: MountainCarParams, position: Any, velocity: Any, action: Any) -> Any:
    """One step for scalars or ``[N]`` arrays: ``(position, velocity, terminated)``."""
    # Same association as Gymnasium: v += ((a - 1) * force + cos(3x) * -gravity).
    velocity = velocity + ((action - 1) * p.force + ops.cos(3 * position) * (-p.gravity))
    velocity = ops.clip(velocity, -p.max_speed, p.max_speed)
    position = ops.clip(position + velocity, p.min_position, p.max_position)
    # The left wall is inelastic: a car pushed into it stops.
    velocity = ops.where((position == p.min_position) & (velocity < 0), 0.0, velocity)
    terminated = (position >= p.goal_position) & (velocity >= p.goal_velocity)
    return position, velocity, terminated


RESET_DRAWS = 1


def reset_state(uniforms: np.ndarray, low: float, high: float) -> np.ndarray:
    """Initial states ``[R, 2]`` from ``[R, 1]`` uniforms: position ~ U(low, high), velocity 0.

    ``low + (high - low) * u`` is numpy's ``uniform`` bit for bit, so this is Gymnasium's draw.
    """
    state = np.zeros((len(uniforms), 2))
    state[:, 0] = low + (high - low) * uniforms[:, 0]
    return state


def observation_space(p: MountainCarParams) -> Box:
    """``Box([-1.2 -0.07], [0.6 0.07], (2,), float32)``."""
    low = np.array([p.min_position, -p.max_speed], dtype=np.float32)
    high = np.array([p.max_position, p.max_speed], dtype=np.float32)
    return Box(low, high, dtype=np.float32)


class MountainCarEnv(ClassicControlEnv):
    """Single MountainCar: the Python-float fast path of :func:`step_state`.

    Actions: 0 push left, 1 no push, 2 push right. ``state`` is ``[position, velocity]``.
    """

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 30}
    # Episodes end by termination only at the goal, so "terminated" means "succeeded".
    success_on_termination = True

    def __init__(self, render_mode: str | None = None, goal_velocity: float = 0) -> None:
        self.params = MountainCarParams(goal_velocity=goal_velocity)
        self.action_space = Discrete(3)
        self.observation_space = observation_space(self.params)
        self._init_render(render_mode)
        self._s: tuple[float, float] | None = None

    @property
    def state(self) -> np.ndarray | None:
        """``[position, velocity]`` as float64 (None before the first reset)."""
        return None if self._s is None else state_array(self._s)

    @state.setter
    def state(self, value: Any) -> None:
        self._s = None if value is None else (float(value[0]), float(value[1]))

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Advance one step; an action outside ``Discrete(3)`` raises InvalidAction."""
        if type(action) is not int or not 0 <= action < 3:
            action = check_discrete_action(action, self.action_space, 3)
        if self._s is None:
            raise error.ResetNeeded("Call reset before using step method.")
        position, velocity, terminated = step_state(SCALAR, self.params, *self._s, action)
        self._s = (position, velocity)
        if self.render_mode == "human":
            self.render()
        return np.array(self._s, dtype=np.float32), -1.0, terminated, False, {}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start at position ~ U(-0.6, -0.4) (``options`` low/high override), velocity 0."""
        super().reset(seed=seed)
        low, high = parse_reset_bounds(options, -0.6, -0.4)
        state = reset_state(self.np_random.random((1, RESET_DRAWS)), low, high)
        self._s = (float(state[0, 0]), float(state[0, 1]))
        if self.render_mode == "human":
            self.render()
        return np.array(self._s, dtype=np.float32), {}

    def _frame(self) -> np.ndarray:
        if self._s is None:
            raise error.ResetNeeded("Call reset before render.")
        return render_mountain_car(self._s[0], self.params.goal_position)

    def get_keys_to_action(self) -> dict[tuple[int, ...], int]:
        """Arrow keys for ``play`` (Gymnasium's mapping)."""
        return {(): 1, (276,): 0, (275,): 2, (275, 276): 1}


expose_params(
    MountainCarEnv,
    [
        "min_position",
        "max_position",
        "max_speed",
        "goal_position",
        "goal_velocity",
        "force",
        "gravity",
    ],
)


class MountainCarBatch(BatchedEnv):
    """N MountainCars stepped by :func:`step_state` on ``[N]`` arrays."""

    state_dim = 2
    reset_draws = RESET_DRAWS

    def __init__(self, num_envs: int, goal_velocity: float = 0) -> None:
        self.params = MountainCarParams(goal_velocity=goal_velocity)
        self.single_action_space = Discrete(3)
        self.single_observation_space = observation_space(self.params)
        super().__init__(num_envs)
        self._reward = np.full(self.num_envs, -1.0)  # [N], constant

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture (see :meth:`BatchedEnv.frame`)."""
        return render_mountain_car(self._state[row, 0], self.params.goal_position)

    def _parse_options(self, options: dict[str, Any] | None) -> tuple[float, float]:
        return parse_reset_bounds(options, -0.6, -0.4)

    def _reset_state(self, uniforms: np.ndarray, bounds: tuple[float, float]) -> np.ndarray:
        return reset_state(uniforms, *bounds)

    def _step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        position, velocity = self._cols  # views: written in place below
        new = step_state(ARRAY, self.params, position, velocity, actions)
        position[...], velocity[...], terminated = new
        return self._reward, terminated

    def _observe(self, rows: np.ndarray | None) -> None:
        if rows is None:
            np.copyto(self._obs, self._state)  # float64 -> float32, as np.array(.., f32)
        else:
            self._obs[rows] = self._state[rows]
