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

``step_state`` expresses this with ``rnd`` = "round like the stored state" (identity on the
first step after reset, float32 afterwards) and :class:`Limits`, the constants as that state
compares with them, computed once per params. Rounding a float64 result of one +, -, * of two
float32 values to float32 equals numpy's float32 operation (53 >= 2*24 + 2, so double rounding
is innocuous); rounding a value that is already a float32 is skipped, since it changes nothing.
Finite out-of-range actions are clipped as in Gymnasium; NaN/inf are refused.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.action_checks import check_box_action
from palaestra.envs.classic_control._common import (
    RENDER_MODES,
    ClassicControlEnv,
    expose_params,
    parse_reset_bounds,
    state_array,
)
from palaestra.envs.classic_control._ops import ARRAY, SCALAR
from palaestra.envs.classic_control.batched import BatchedEnv
from palaestra.envs.classic_control.mountain_car import RESET_DRAWS, reset_state
from palaestra.rendering.scenes import render_mountain_car
from palaestra.spaces import Box


@dataclass(frozen=True, slots=True)
class Limits:
    """Per-params constants of a step, as the state's precision sees them (see :func:`limits`).

    A slotted dataclass: its attributes read ~4x faster than a NamedTuple's, ~8 reads a step.
    """

    max_speed: Any
    min_speed: Any  # -max_speed
    max_position: Any
    min_position: Any
    goal_position: Any
    goal_velocity: Any  # compared with a velocity computed in the state's precision
    goal_velocity_py: Any  # the same comparison for a velocity Gymnasium set to a Python float
    same_goal_test: bool  # whether both thresholds give every velocity the same answer
    float32_state: Any  # whether rnd is float32 rounding (else the identity)
    power: Any  # float32 power: a float32 force times a Python float is float32 arithmetic


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


def limits(p: ContinuousMountainCarParams, rnd: Callable[[float], float]) -> Limits:
    """The constants a step with state rounding ``rnd`` compares with, computed once per params.

    ``rnd`` is float32 rounding (``SCALAR.f32``) or the identity on the first step after a
    reset. The values are Python floats, for the single env and the batch alike.
    Gymnasium replaces a too fast velocity (or one stopped by the wall) by a Python float ``c``
    and compares ``c >= goal_velocity`` in float64, while we carry ``rnd(c)``;
    ``goal_velocity_py`` is a threshold that gives ``rnd(c)`` the same answer for each such
    ``c``: ``rnd(goal_velocity)`` where that works (always for the identity, and for the default
    goal 0 -- then ``same_goal_test`` lets a step skip telling the two kinds of velocity apart),
    else the smallest ``rnd(c)`` with ``c >= goal_velocity`` (rounding is monotonic).
    """
    speed, goal_v = float(p.max_speed), float(p.goal_velocity)
    constants = (-speed, 0.0, speed)  # what Gymnasium may set the velocity to
    same = all((rnd(c) >= rnd(goal_v)) == (c >= goal_v) for c in constants)
    passing = [rnd(c) for c in constants if c >= goal_v]
    return Limits(
        max_speed=rnd(speed),
        min_speed=rnd(-speed),
        max_position=rnd(float(p.max_position)),
        min_position=rnd(float(p.min_position)),
        goal_position=rnd(float(p.goal_position)),
        goal_velocity=rnd(goal_v),
        goal_velocity_py=rnd(goal_v) if same else min(passing, default=math.inf),
        same_goal_test=same,
        float32_state=rnd is not _identity,
        power=SCALAR.f32(float(p.power)),
    )


def step_state(
    ops: Any,
    p: ContinuousMountainCarParams,
    position: Any,
    velocity: Any,
    action: Any,
    rnd: Callable[[Any], Any],
    lim: Limits,
) -> Any:
    """One step: ``(position, velocity, terminated, reward)``; the state still needs ``rnd``.

    ``action`` holds finite float32 values. ``rnd`` rounds like the stored state and ``lim``
    holds :func:`limits` for it: identity on the first step after a reset (float64 state),
    float32 rounding afterwards -- see :func:`precision`. The returned position and velocity
    are already float32 values after a float32 state; after a float64 one the caller rounds
    them (Gymnasium stores ``np.float32``).
    """
    cos = ops.cos(rnd(3 * position))
    gravity = p.gravity * cos
    force = ops.clip(action, p.min_action, p.max_action)
    in_range = force == action
    acc = ops.where(
        in_range,
        ops.f32(action * lim.power) - ops.f32(gravity),  # a float32 force: float32 arithmetic
        force * p.power - gravity,  # a clipped force is a Python float: float64 arithmetic
    )
    # A float32 result, or a float64 one that the state's precision rounds (one call for both).
    acc = ops.f32_where(in_range | lim.float32_state, acc)
    v1 = rnd(velocity + acc)
    # Gymnasium sets +-max_speed (Python floats); what is added to the position and stored is
    # their rnd, which clip gives directly.
    v2 = ops.clip(v1, lim.min_speed, lim.max_speed)
    p1 = rnd(position + v2)
    pos = ops.clip(p1, lim.min_position, lim.max_position)
    stop = (p1 <= lim.min_position) & (v2 < 0)  # the inelastic left wall
    vel = ops.where(stop, 0.0, v2)
    if lim.same_goal_test:  # the usual params: no need to know where the velocity came from
        vel_ok = vel >= lim.goal_velocity
    else:  # a velocity Gymnasium replaced by a Python float compares in float64
        python_vel = stop | (v1 > lim.max_speed) | (v1 < lim.min_speed)
        vel_ok = vel >= ops.where(python_vel, lim.goal_velocity_py, lim.goal_velocity)
    terminated = (p1 >= lim.goal_position) & vel_ok
    reward = terminated * 100.0 - action * action * 0.1  # 100.0 or 0.0 minus the square
    return pos, vel, terminated, reward


def all_limits(p: ContinuousMountainCarParams) -> tuple[Limits, Limits]:
    """``(exact, float32)`` :func:`limits` of ``p``: for a state fresh from a reset, and after."""
    return limits(p, _identity), limits(p, SCALAR.f32)


def precision(ops: Any, fresh: Any, lims: tuple[Limits, Limits]) -> tuple[Any, Limits]:
    """``(rnd, lim)`` for :func:`step_state` given which rows are fresh from a reset."""
    exact, lim32 = lims
    if isinstance(fresh, bool):
        return (_identity, exact) if fresh else (ops.f32, lim32)
    if not fresh.any():  # the usual batch step: no row was just reset
        return ops.f32, lim32

    def rnd(x: Any) -> Any:
        return ops.where(fresh, x, ops.f32(x))

    lim = Limits(*(ops.where(fresh, getattr(exact, f), getattr(lim32, f)) for f in _FIELDS))
    same = exact.same_goal_test and lim32.same_goal_test
    return rnd, dataclasses.replace(lim, same_goal_test=same)


def _identity(x: Any) -> Any:
    return x


_FIELDS = [f.name for f in dataclasses.fields(Limits)]
_F32 = np.dtype(np.float32)
_F32_RND = SCALAR.f32
_empty = np.empty


def spaces(p: ContinuousMountainCarParams) -> tuple[Box, Box]:
    """``(observation_space, action_space)`` as Gymnasium builds them."""
    low = np.array([p.min_position, -p.max_speed], dtype=np.float32)
    high = np.array([p.max_position, p.max_speed], dtype=np.float32)
    obs = Box(low, high, dtype=np.float32)
    return obs, Box(p.min_action, p.max_action, shape=(1,), dtype=np.float32)


class Continuous_MountainCarEnv(ClassicControlEnv):
    """Single continuous MountainCar: the Python-float path of :func:`step_state`."""

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 30}
    # Episodes end by termination only at the goal, so "terminated" means "succeeded".
    success_on_termination = True

    def __init__(self, render_mode: str | None = None, goal_velocity: float = 0) -> None:
        self.params = ContinuousMountainCarParams(goal_velocity=goal_velocity)
        self.observation_space, self.action_space = spaces(self.params)
        self._init_render(render_mode)
        self._s: tuple[float, float] | None = None
        self._fresh = True
        self._lims = (self.params, *all_limits(self.params))  # (params, exact, float32)

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
        # The usual action (a float32 array of shape (1,)) is read without check_box_action's
        # conversions: item() refuses any other size, and ``a - a`` is 0.0 iff ``a`` is finite.
        try:
            if type(action) is not np.ndarray or action.dtype is not _F32 or action.ndim != 1:
                raise ValueError
            a = action.item()
            if a - a != 0.0:
                raise ValueError
        except ValueError:
            a = check_box_action(action, self.action_space)  # converts, or raises InvalidAction
        s = self._s
        if s is None:
            raise error.ResetNeeded("Call reset before using step method.")
        p, lims = self.params, self._lims
        if lims[0] is not p:  # params replaced (env.unwrapped.power = ...)
            self._lims = lims = (p, *all_limits(p))
        if self._fresh:
            pos, vel, terminated, reward = step_state(SCALAR, p, s[0], s[1], a, _identity, lims[1])
            pos, vel = _F32_RND(pos), _F32_RND(vel)
            self._fresh = False
        else:  # a float32 state: step_state's position and velocity are float32 values
            pos, vel, terminated, reward = step_state(SCALAR, p, s[0], s[1], a, _F32_RND, lims[2])
        self._s = (pos, vel)
        if self.render_mode == "human":
            self.render()
        obs = _empty(2, _F32)  # ~2x cheaper than np.array((pos, vel), float32)
        obs[0], obs[1] = pos, vel
        return obs, reward, terminated, False, {}

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
    RUN_STATE = (*BatchedEnv.RUN_STATE, "_fresh")

    def __init__(self, num_envs: int, goal_velocity: float = 0) -> None:
        self.params = ContinuousMountainCarParams(goal_velocity=goal_velocity)
        self.single_observation_space, self.single_action_space = spaces(self.params)
        super().__init__(num_envs)
        self._fresh = np.ones(self.num_envs, dtype=bool)  # [N] no step since reset
        self._lims = (self.params, *all_limits(self.params))

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture (see :meth:`BatchedEnv.frame`)."""
        return render_mountain_car(self._state[row, 0], self.params.goal_position)

    def _parse_options(self, options: dict[str, Any] | None) -> tuple[float, float]:
        return parse_reset_bounds(options, -0.6, -0.4)

    def _reset_state(self, uniforms: np.ndarray, bounds: tuple[float, float]) -> np.ndarray:
        return reset_state(uniforms, *bounds)

    def _after_reset(self, rows: np.ndarray) -> None:
        self._fresh[rows] = True

    def _step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p = self.params
        if self._lims[0] is not p:
            self._lims = (p, *all_limits(p))
        rnd, lim = precision(ARRAY, self._fresh, self._lims[1:])
        pos, vel = self._cols  # views: written in place below
        new_pos, new_vel, terminated, reward = step_state(ARRAY, p, pos, vel, actions, rnd, lim)
        pos[...], vel[...] = ARRAY.f32(new_pos), ARRAY.f32(new_vel)
        self._fresh[:] = False
        return reward, terminated

    def _observe(self, rows: np.ndarray | None) -> None:
        if rows is None:
            np.copyto(self._obs, self._state)
        else:
            self._obs[rows] = self._state[rows]
