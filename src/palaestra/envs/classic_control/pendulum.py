"""Pendulum-v1: swing a pendulum up and keep it upright with a bounded torque.

Physics equal to Gymnasium 1.x's ``PendulumEnv``: float64 state ``[theta, theta_dot]``, the
torque clipped to [-2, 2] and kept float32, so ``3/(m l^2) * u`` and ``0.001 * u**2`` are
float32 products (numpy 2 / NEP 50 rounds a float32 scalar times a Python float to float32)
that then join the float64 sums. Reward is ``-(angle^2 + 0.1 theta_dot^2 + 0.001 u^2)``; the
episode never terminates (the 200-step limit truncates it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.action_checks import check_box_action
from palaestra.envs.classic_control._common import (
    RENDER_MODES,
    ClassicControlEnv,
    checked_options,
    expose_params,
    parse_number,
    state_array,
)
from palaestra.envs.classic_control._ops import ARRAY, SCALAR
from palaestra.envs.classic_control._trace import trace
from palaestra.envs.classic_control.batched import ReplayedBatch, copy_to_columns
from palaestra.rendering.scenes import render_pendulum
from palaestra.spaces import Box

DEFAULT_X = math.pi
DEFAULT_Y = 1.0


@dataclass(frozen=True)
class PendulumParams:
    """Gymnasium's Pendulum constants."""

    max_speed: float = 8
    max_torque: float = 2.0
    dt: float = 0.05
    g: float = 10.0
    m: float = 1.0
    l: float = 1.0  # noqa: E741 (Gymnasium's name)


def angle_normalize(ops: Any, x: Any) -> Any:
    """Wrap an angle into [-pi, pi) exactly as Gymnasium does."""
    return ops.mod(x + math.pi, 2 * math.pi) - math.pi


def step_state(ops: Any, p: PendulumParams, th: Any, thdot: Any, u: Any) -> Any:
    """One step: ``(theta, theta_dot, reward, clipped_u)``; ``u`` holds float32 values."""
    u = ops.clip(u, -p.max_torque, p.max_torque)
    f32_cost = ops.f32(ops.f32(0.001) * ops.powf2(u))  # 0.001 * u**2 in float32
    sq_angle, sq_thdot = ops.pow2s(angle_normalize(ops, th), thdot)  # x**2: libm pow
    costs = sq_angle + 0.1 * sq_thdot + f32_cost
    torque_term = ops.f32(ops.f32(3.0 / (p.m * p.l**2)) * u)  # float32 product, as in Gymnasium
    newthdot = thdot + (3 * p.g / (2 * p.l) * ops.sin(th) + torque_term) * p.dt
    newthdot = ops.clip(newthdot, -p.max_speed, p.max_speed)
    newth = th + newthdot * p.dt
    return newth, newthdot, -costs, u


def observation(ops: Any, th: Any) -> tuple[Any, Any]:
    """The observation's ``cos``/``sin`` of ``theta`` (float64: the caller casts them to
    float32 beside ``theta_dot``)."""
    return ops.cos(th), ops.sin(th)


def parse_options(options: dict[str, Any] | None) -> tuple[float, float]:
    """``x_init``/``y_init`` reset options (half-widths of the symmetric reset box)."""
    given = checked_options(options, ("x_init", "y_init"))
    x = parse_number("x_init", given["x_init"]) if "x_init" in given else DEFAULT_X
    y = parse_number("y_init", given["y_init"]) if "y_init" in given else DEFAULT_Y
    for name, value in (("x_init", x), ("y_init", y)):
        # Gymnasium draws U(-v, v) with numpy, which refuses v < 0 (high - low < 0) and a
        # 2 * v that overflows; we would draw from a flipped or infinite box instead.
        shown = f"Reset option {name}={given.get(name)!r}"
        if value < 0:
            raise ValueError(f"{shown} must be >= 0: the state is drawn from [-{name}, {name}].")
        if not math.isfinite(2 * value):
            raise ValueError(f"{shown} is too large: [-{name}, {name}] overflows a float.")
    return x, y


RESET_DRAWS = 2


def reset_state(uniforms: np.ndarray, x: float, y: float) -> np.ndarray:
    """Initial states ``[R, 2]`` from ``[R, 2]`` uniforms: ``U(-[x, y], [x, y])``.

    ``low + (high - low) * u`` is numpy's ``uniform`` bit for bit, so this is Gymnasium's draw.
    """
    high = np.array([x, y])
    low = -high
    return low + (high - low) * uniforms


def spaces(p: PendulumParams) -> tuple[Box, Box]:
    """``(observation_space, action_space)`` as Gymnasium builds them."""
    high = np.array([1.0, 1.0, p.max_speed], dtype=np.float32)
    obs = Box(-high, high, dtype=np.float32)
    return obs, Box(-p.max_torque, p.max_torque, shape=(1,), dtype=np.float32)


class PendulumEnv(ClassicControlEnv):
    """Single Pendulum: the Python-float path of :func:`step_state`."""

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 30}

    def __init__(self, render_mode: str | None = None, g: float = 10.0) -> None:
        self.params = PendulumParams(g=g)
        self.observation_space, self.action_space = spaces(self.params)
        self._init_render(render_mode)
        self._s: tuple[float, float] | None = None
        self.last_u: float | None = None  # for rendering

    @property
    def state(self) -> np.ndarray | None:
        """``[theta, theta_dot]`` as float64 (None before the first reset)."""
        return None if self._s is None else state_array(self._s)

    @state.setter
    def state(self, value: Any) -> None:
        self._s = None if value is None else (float(value[0]), float(value[1]))

    def _get_obs(self) -> np.ndarray:
        assert self._s is not None
        th, thdot = self._s
        return np.array((*observation(SCALAR, th), thdot), dtype=np.float32)

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Advance one step; a wrongly shaped or non-finite action raises InvalidAction."""
        u = check_box_action(action, self.action_space)
        if self._s is None:
            raise error.ResetNeeded("Call reset before using step method.")
        th, thdot, reward, self.last_u = step_state(SCALAR, self.params, *self._s, u)
        self._s = (th, thdot)
        if self.render_mode == "human":
            self.render()
        return self._get_obs(), reward, False, False, {}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start at ``U(-[pi, 1], [pi, 1])`` (options ``x_init``/``y_init`` override)."""
        super().reset(seed=seed)
        x, y = parse_options(options)
        state = reset_state(self.np_random.random((1, RESET_DRAWS)), x, y)
        self._s = tuple(state[0].tolist())
        self.last_u = None
        if self.render_mode == "human":
            self.render()
        return self._get_obs(), {}

    def _frame(self) -> np.ndarray:
        if self._s is None:
            raise error.ResetNeeded("Call reset before render.")
        return render_pendulum(self._s[0], self.last_u)


expose_params(PendulumEnv, ["max_speed", "max_torque", "dt", "g", "m", "l"])


class PendulumBatch(ReplayedBatch):
    """N Pendulums stepped by :func:`step_state`, recorded once and replayed on buffers.

    As :class:`~.acrobot.AcrobotBatch`: :func:`step_state` and the observation's cos/sin run on
    :class:`~._trace.TraceOps` and are replayed (:class:`~.batched.ReplayedBatch`), the same
    float operations per row as the single env. The new observation's ``sin(theta)`` is the
    next step's ``sin(theta)`` for the rows whose ``theta`` still has the same bits (others
    are recomputed).
    """

    state_dim = 2
    reset_draws = RESET_DRAWS

    def __init__(self, num_envs: int, g: float = 10.0) -> None:
        self.params = PendulumParams(g=g)
        self.single_observation_space, self.single_action_space = spaces(self.params)
        super().__init__(num_envs)
        # sin of the theta whose bits _sin_of holds: of 0.0 at first, exactly.
        self._sin_of = np.zeros(self.num_envs)
        self._sin = np.zeros(self.num_envs)
        self._reward = np.zeros(self.num_envs)

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture (see :meth:`BatchedEnv.frame`)."""
        # The single env draws its last clipped torque (last_u), None right after a reset.
        last_u = None
        if action is not None:
            torque = float(np.asarray(action, dtype=np.float32).reshape(-1)[0])
            last_u = min(max(torque, -self.params.max_torque), self.params.max_torque)
        return render_pendulum(self._state[row, 0], last_u)

    def _parse_options(self, options: dict[str, Any] | None) -> tuple[float, float]:
        return parse_options(options)

    def _reset_state(self, uniforms: np.ndarray, bounds: tuple[float, float]) -> np.ndarray:
        return reset_state(uniforms, *bounds)

    def _record(self) -> Any:
        def batch_step(ops: Any, th: Any, thdot: Any, u: Any) -> Any:
            known = ops.known("sin", th)  # the last observation's
            newth, newthdot, reward, _ = step_state(ops, self.params, th, thdot, u)
            return (th, thdot), (u, known), (newth, newthdot), reward, observation(ops, newth)

        ops, _, (state, given, new, reward, trig) = trace(batch_step, 3)
        return ops, {"state": state, "given": given, "new": new, "trig": trig, "reward": [reward]}

    def _swaps(self, rows: slice) -> dict[str, np.ndarray]:
        return {"given.1": self._sin[rows], "reward.0": self._reward[rows]}

    def _step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        replays = self._replays()
        self.refresh_kept(self._state[:, 0], self._sin_of, (self._sin,), (np.sin,))
        torques = actions.reshape(self.num_envs)  # float32 values, exact in float64
        state, obs, pos = self._state, self._obs, np.positive
        for rows, prog, steps in replays:
            copy_to_columns(state[rows].T, prog.block("state").T)
            pos(torques[rows], out=prog.block("given")[0])
            prog.run(steps)
            new, cs = prog.block("new"), prog.block("trig")
            copy_to_columns(new, state[rows])
            copy_to_columns(cs, obs[rows, :2])
            pos(new[1], out=obs[rows, 2])
            pos(cs[1], out=self._sin[rows])
            pos(new[0], out=self._sin_of[rows])
        return self._reward.copy(), np.zeros(self.num_envs, dtype=bool)

    def _observe(self, rows: np.ndarray | None) -> None:
        # Rows just reset (step_writes_obs): one formula with the single env's.
        sel = slice(None) if rows is None else rows
        self._obs[sel, 0], self._obs[sel, 1] = observation(ARRAY, self._state[sel, 0])
        self._obs[sel, 2] = self._state[sel, 1]
