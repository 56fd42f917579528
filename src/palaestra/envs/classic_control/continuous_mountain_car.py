"""MountainCarContinuous-v0: MountainCar with a continuous force in [-1, 1].

Gymnasium 1.x's ``Continuous_MountainCarEnv`` mixes float32 and float64 in a way its results
depend on, and we reproduce it exactly:

* the reset state is float64, but every step stores ``np.array([pos, vel], float32)``, so from
  the second step of an episode on the arithmetic runs on numpy float32 scalars, where numpy 2
  (NEP 50) rounds to float32 after each operation and compares against float32-rounded Python
  constants;
* a force inside [-1, 1] stays a float32, so the acceleration is float32 arithmetic; a clipped
  force is a Python float, so the acceleration is float64;
* the reward uses the *unclipped* action: ``100 * terminated - 0.1 * action**2``.

``step_state`` expresses this with ``R`` = "round like the stored state" (identity on the first
step after reset, float32 afterwards). Rounding a float64 result of one +, -, * of two float32
values to float32 equals numpy's float32 operation (53 >= 2*24 + 2, so double rounding is
innocuous). Finite out-of-range actions are clipped as in Gymnasium; NaN/inf are refused.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from palaestra import error
from palaestra.envs.classic_control._common import (
    RENDER_MODES,
    ClassicControlEnv,
    check_box_action,
    expose_params,
    parse_reset_bounds,
    state_array,
)
from palaestra.envs.classic_control._ops import ARRAY, SCALAR
from palaestra.envs.classic_control.batched import BatchedEnv
from palaestra.envs.classic_control.mountain_car import RESET_DRAWS, reset_state
from palaestra.spaces import Box


class Limits(NamedTuple):
    """The Python constants a step compares the state with, as numpy compares them."""

    max_speed: Any
    max_position: Any
    min_position: Any
    goal_position: Any
    goal_velocity: Any


@dataclass(frozen=True)
class ContinuousMountainCarParams:
    """Gymnasium's constants."""

    min_action: float = -1.0
    max_action: float = 1.0
    min_position: float = -1.2
    max_position: float = 0.6
    max_speed: float = 0.07
    goal_position: float = 0.45
    goal_velocity: float = 0
    power: float = 0.0015
    gravity: float = 0.0025  # a literal in Gymnasium's step

    def limits(self, ops: Any) -> Limits:
        """The limits rounded with ``ops.f32``: what a float32 state is compared with."""
        return Limits(*(ops.f32(float(getattr(self, name))) for name in Limits._fields))


def step_state(
    ops: Any,
    p: ContinuousMountainCarParams,
    position: Any,
    velocity: Any,
    action: Any,
    rnd: Callable[[Any], Any],
    lim: Any,
) -> Any:
    """One step: ``(position, velocity, terminated, reward)``, state rounded to float32.

    ``action`` holds float32 values. ``rnd`` rounds like the stored state and ``lim`` are the
    limits as compared with it: identity and ``p`` itself on the first step after a reset
    (float64 state), float32 rounding and ``p.limits(ops)`` afterwards -- see :func:`precision`.
    """
    cos = ops.cos(rnd(3 * position))
    in_range = (action >= p.min_action) & (action <= p.max_action)
    power32 = ops.f32(p.power)
    acc = ops.where(
        in_range,
        ops.f32(ops.f32(action * power32) - ops.f32(p.gravity * cos)),  # float32 force
        ops.clip(action, p.min_action, p.max_action) * p.power - p.gravity * cos,  # Python force
    )
    v1 = rnd(velocity + rnd(acc))
    too_fast, too_slow = v1 > lim.max_speed, v1 < -lim.max_speed
    v2 = ops.where(too_fast, p.max_speed, ops.where(too_slow, -p.max_speed, v1))
    p1 = rnd(position + rnd(v2))
    pos = ops.where(
        p1 > lim.max_position,
        p.max_position,
        ops.where(p1 < lim.min_position, p.min_position, p1),
    )
    stop = (p1 <= lim.min_position) & (v2 < 0)  # the inelastic left wall
    vel = ops.where(stop, 0.0, v2)
    # A velocity replaced by a Python constant is compared in float64, a float32 one in float32.
    python_vel = stop | too_fast | too_slow
    vel_ok = ops.where(python_vel, vel >= p.goal_velocity, vel >= lim.goal_velocity)
    terminated = (p1 >= lim.goal_position) & vel_ok
    reward = ops.where(terminated, 100.0, 0.0) - action * action * 0.1
    return ops.f32(pos), ops.f32(vel), terminated, reward


def precision(ops: Any, p: ContinuousMountainCarParams, fresh: Any) -> tuple[Any, Limits]:
    """``(rnd, lim)`` for :func:`step_state` given which rows are fresh from a reset."""
    lim32 = p.limits(ops)
    if isinstance(fresh, bool):
        return (_identity, p) if fresh else (ops.f32, lim32)  # type: ignore[return-value]

    def rnd(x: Any) -> Any:
        return ops.where(fresh, x, ops.f32(x))

    exact = Limits(*(float(getattr(p, name)) for name in Limits._fields))
    return rnd, Limits(*(ops.where(fresh, a, b) for a, b in zip(exact, lim32)))


def _identity(x: Any) -> Any:
    return x


def spaces(p: ContinuousMountainCarParams) -> tuple[Box, Box]:
    """``(observation_space, action_space)`` as Gymnasium builds them."""
    low = np.array([p.min_position, -p.max_speed], dtype=np.float32)
    high = np.array([p.max_position, p.max_speed], dtype=np.float32)
    obs = Box(low, high, dtype=np.float32)
    return obs, Box(p.min_action, p.max_action, shape=(1,), dtype=np.float32)


class Continuous_MountainCarEnv(ClassicControlEnv):
    """Single continuous MountainCar: the Python-float path of :func:`step_state`."""

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 30}

    def __init__(self, render_mode: str | None = None, goal_velocity: float = 0) -> None:
        self.params = ContinuousMountainCarParams(goal_velocity=goal_velocity)
        self.observation_space, self.action_space = spaces(self.params)
        self._init_render(render_mode)
        self._s: tuple[float, float] | None = None
        self._fresh = True
        self._lim32 = (self.params, self.params.limits(SCALAR))

    @property
    def state(self) -> np.ndarray | None:
        """``[position, velocity]``: float64 after reset, float32 after a step (as Gymnasium)."""
        if self._s is None:
            return None
        return state_array(self._s, np.float64 if self._fresh else np.float32)

    @state.setter
    def state(self, value: Any) -> None:
        arr = None if value is None else np.asarray(value)
        self._fresh = arr is None or arr.dtype != np.float32
        self._s = None if arr is None else (float(arr[0]), float(arr[1]))

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Advance one step; a wrongly shaped or non-finite action raises InvalidAction."""
        a = check_box_action(action, self.action_space)
        if self._s is None:
            raise error.ResetNeeded("Call reset before using step method.")
        p = self.params
        lim: Any
        if self._fresh:
            rnd, lim = _identity, p  # p has the limits as attributes
        else:
            if self._lim32[0] is not p:  # params replaced (env.unwrapped.power = ...)
                self._lim32 = (p, p.limits(SCALAR))
            rnd, lim = SCALAR.f32, self._lim32[1]
        pos, vel, terminated, reward = step_state(SCALAR, p, *self._s, a, rnd, lim)
        self._s, self._fresh = (pos, vel), False
        if self.render_mode == "human":
            self.render()
        return np.array(self._s, dtype=np.float32), reward, terminated, False, {}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start at position ~ U(-0.6, -0.4) (``options`` low/high override), velocity 0."""
        super().reset(seed=seed)
        low, high = parse_reset_bounds(options, -0.6, -0.4)
        state = reset_state(self.np_random.random((1, RESET_DRAWS)), low, high)  # as MountainCar
        self._s, self._fresh = (float(state[0, 0]), float(state[0, 1])), True
        if self.render_mode == "human":
            self.render()
        return np.array(self._s, dtype=np.float32), {}

    def _frame(self) -> np.ndarray:
        from palaestra.rendering.scenes import render_mountain_car

        if self._s is None:
            raise error.ResetNeeded("Call reset before render.")
        return render_mountain_car(self._s[0], self.params.goal_position)


expose_params(
    Continuous_MountainCarEnv,
    [
        "min_action",
        "max_action",
        "min_position",
        "max_position",
        "max_speed",
        "goal_position",
        "goal_velocity",
        "power",
    ],
)


class ContinuousMountainCarBatch(BatchedEnv):
    """N continuous MountainCars stepped by :func:`step_state` on ``[N]`` arrays."""

    state_dim = 2
    reset_draws = RESET_DRAWS

    def __init__(self, num_envs: int, goal_velocity: float = 0) -> None:
        self.params = ContinuousMountainCarParams(goal_velocity=goal_velocity)
        self.single_observation_space, self.single_action_space = spaces(self.params)
        super().__init__(num_envs)
        self._fresh = np.ones(self.num_envs, dtype=bool)  # [N] no step since reset

    def _parse_options(self, options: dict[str, Any] | None) -> tuple[float, float]:
        return parse_reset_bounds(options, -0.6, -0.4)

    def _reset_state(self, uniforms: np.ndarray, bounds: tuple[float, float]) -> np.ndarray:
        return reset_state(uniforms, *bounds)

    def _after_reset(self, rows: np.ndarray) -> None:
        self._fresh[rows] = True

    def _step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rnd, lim = precision(ARRAY, self.params, self._fresh)
        pos, vel = self._cols  # views: written in place below
        new = step_state(ARRAY, self.params, pos, vel, actions, rnd, lim)
        pos[...], vel[...], terminated, reward = new
        self._fresh[:] = False
        return reward, terminated

    def _observe(self, rows: np.ndarray | None) -> None:
        if rows is None:
            np.copyto(self._obs, self._state)
        else:
            self._obs[rows] = self._state[rows]
