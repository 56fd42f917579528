"""Acrobot-v1: swing the tip of a two-link pendulum above the bar by torquing the middle joint.

Dynamics equal to Gymnasium 1.x's ``AcrobotEnv`` ("book" equations of Sutton & Barto, one RK4
step of dt = 0.2 per action, angles wrapped to [-pi, pi], velocities bounded), evaluated in the
same order. Gymnasium's quirks kept: the reset state is float32 (so the first observation's
cos/sin are float32 numpy math) while every later state is float64; ``x**2`` is libm ``pow``
(see ``_ops``). Torque noise (``torque_noise_max``, 0 in Gymnasium) is not modelled.
"""

from __future__ import annotations

import math
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
from palaestra.envs.classic_control._ops import SCALAR
from palaestra.envs.classic_control._trace import trace
from palaestra.envs.classic_control.batched import ReplayedBatch, copy_to_columns
from palaestra.rendering.scenes import render_acrobot
from palaestra.spaces import Box, Discrete

AVAIL_TORQUE = (-1.0, 0.0, 1.0)


@dataclass(frozen=True)
class AcrobotParams:
    """Gymnasium's Acrobot constants (SI units)."""

    dt: float = 0.2
    LINK_LENGTH_1: float = 1.0
    LINK_LENGTH_2: float = 1.0
    LINK_MASS_1: float = 1.0
    LINK_MASS_2: float = 1.0
    LINK_COM_POS_1: float = 0.5
    LINK_COM_POS_2: float = 0.5
    LINK_MOI: float = 1.0
    MAX_VEL_1: float = 4 * math.pi
    MAX_VEL_2: float = 9 * math.pi
    g: float = 9.8


def dsdt(
    ops: Any, p: AcrobotParams, a: Any, theta1: Any, theta2: Any, dtheta1: Any, dtheta2: Any
) -> tuple[Any, Any, Any, Any]:
    """Time derivative of the state under torque ``a`` (the "book" equations)."""
    m1, m2, l1 = p.LINK_MASS_1, p.LINK_MASS_2, p.LINK_LENGTH_1
    lc1, lc2, i1, i2, g = p.LINK_COM_POS_1, p.LINK_COM_POS_2, p.LINK_MOI, p.LINK_MOI, p.g
    cos2, sin2 = ops.cos(theta2), ops.sin(theta2)
    # Written as Gymnasium writes it: the same association gives the same roundings.
    d1 = m1 * lc1**2 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * cos2) + i1 + i2
    d2 = m2 * (lc2**2 + l1 * lc2 * cos2) + i2
    phi2 = m2 * lc2 * g * ops.cos(theta1 + theta2 - math.pi / 2.0)
    sq_dtheta2, sq_dtheta1, sq_d2 = ops.pow2s(dtheta2, dtheta1, d2)  # x**2: libm pow
    phi1 = (
        -m2 * l1 * lc2 * sq_dtheta2 * sin2
        - 2 * m2 * l1 * lc2 * dtheta2 * dtheta1 * sin2
        + (m1 * lc1 + m2 * l1) * g * ops.cos(theta1 - math.pi / 2)
        + phi2
    )
    ddtheta2 = (a + d2 / d1 * phi1 - m2 * l1 * lc2 * sq_dtheta1 * sin2 - phi2) / (
        m2 * lc2**2 + i2 - sq_d2 / d1
    )
    ddtheta1 = -(d2 * ddtheta2 + phi1) / d1
    return dtheta1, dtheta2, ddtheta1, ddtheta2


def step_state(ops: Any, p: AcrobotParams, s0: Any, s1: Any, s2: Any, s3: Any, torque: Any) -> Any:
    """One RK4 step of ``dt``: ``(theta1, theta2, dtheta1, dtheta2, terminated)``."""
    h, h2, h6 = p.dt, p.dt / 2.0, p.dt / 6.0
    k1 = dsdt(ops, p, torque, s0, s1, s2, s3)
    k2 = dsdt(ops, p, torque, *(y + h2 * k for y, k in zip((s0, s1, s2, s3), k1)))
    k3 = dsdt(ops, p, torque, *(y + h2 * k for y, k in zip((s0, s1, s2, s3), k2)))
    k4 = dsdt(ops, p, torque, *(y + h * k for y, k in zip((s0, s1, s2, s3), k3)))
    n0, n1, n2, n3 = (
        y + h6 * (a + 2 * b + 2 * c + d) for y, a, b, c, d in zip((s0, s1, s2, s3), k1, k2, k3, k4)
    )
    n0 = ops.wrap(n0, -math.pi, math.pi)  # Gymnasium's wrap: one period at a time
    n1 = ops.wrap(n1, -math.pi, math.pi)
    n2 = ops.clip(n2, -p.MAX_VEL_1, p.MAX_VEL_1)
    n3 = ops.clip(n3, -p.MAX_VEL_2, p.MAX_VEL_2)
    terminated = -ops.cos(n0) - ops.cos(n1 + n0) > 1.0
    return n0, n1, n2, n3, terminated


def observation(ops: Any, s0: Any, s1: Any, s2: Any, s3: Any) -> tuple[Any, ...]:
    """The observation's six components of a float64 state (cast to float32 by the caller)."""
    return ops.cos(s0), ops.sin(s0), ops.cos(s1), ops.sin(s1), s2, s3


RESET_DRAWS = 4


def reset_state(uniforms: np.ndarray, low: float, high: float) -> np.ndarray:
    """Initial float32 states ``[R, 4]`` from ``[R, 4]`` uniforms: U(low, high), then float32.

    ``low + (high - low) * u`` is numpy's ``uniform`` bit for bit, so this is Gymnasium's draw.
    """
    return (low + (high - low) * uniforms).astype(np.float32)


def reset_observation(state32: np.ndarray) -> np.ndarray:
    """Observations ``[R, 6]`` of float32 reset states ``[R, 4]``, with float32 cos/sin."""
    th1, th2 = state32[:, 0], state32[:, 1]
    cols = (np.cos(th1), np.sin(th1), np.cos(th2), np.sin(th2), state32[:, 2], state32[:, 3])
    return np.stack(cols, axis=1).astype(np.float32)


def observation_space(p: AcrobotParams) -> Box:
    """cos/sin of both angles in [-1, 1], velocities within their bounds."""
    high = np.array([1.0, 1.0, 1.0, 1.0, p.MAX_VEL_1, p.MAX_VEL_2], dtype=np.float32)
    return Box(-high, high, dtype=np.float32)


class AcrobotEnv(ClassicControlEnv):
    """Single Acrobot: the Python-float path of :func:`step_state`."""

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 15}
    # Episodes end by termination only at the goal, so "terminated" means "succeeded".
    success_on_termination = True
    AVAIL_TORQUE = list(AVAIL_TORQUE)

    def __init__(self, render_mode: str | None = None) -> None:
        self.params = AcrobotParams()
        self.observation_space = observation_space(self.params)
        self.action_space = Discrete(3)
        self._init_render(render_mode)
        self._s: tuple[float, float, float, float] | None = None
        self._fresh = True

    @property
    def state(self) -> np.ndarray | None:
        """``[theta1, theta2, dtheta1, dtheta2]``: float32 after reset, float64 after a step."""
        if self._s is None:
            return None
        return state_array(self._s, np.float32 if self._fresh else np.float64)

    @state.setter
    def state(self, value: Any) -> None:
        arr = None if value is None else np.asarray(value)
        self._fresh = arr is not None and arr.dtype == np.float32
        self._s = None if arr is None else tuple(float(v) for v in arr)  # type: ignore[assignment]

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Advance one RK4 step; an action outside ``Discrete(3)`` raises InvalidAction."""
        if type(action) is not int or not 0 <= action < 3:
            action = check_discrete_action(action, self.action_space, 3)
        if self._s is None:
            raise error.ResetNeeded("Call reset before using step method.")
        *s, terminated = step_state(SCALAR, self.params, *self._s, AVAIL_TORQUE[action])
        self._s, self._fresh = tuple(s), False
        if self.render_mode == "human":
            self.render()
        obs = np.array(observation(SCALAR, *s), dtype=np.float32)
        return obs, 0.0 if terminated else -1.0, terminated, False, {}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start with all four components ~ U(-0.1, 0.1) (``options`` low/high override)."""
        super().reset(seed=seed)
        low, high = parse_reset_bounds(options, -0.1, 0.1)
        state32 = reset_state(self.np_random.random((1, RESET_DRAWS)), low, high)
        self._s, self._fresh = tuple(state32[0].tolist()), True
        if self.render_mode == "human":
            self.render()
        return reset_observation(state32)[0], {}

    def _frame(self) -> np.ndarray:
        if self._s is None:
            raise error.ResetNeeded("Call reset before render.")
        return render_acrobot(self._s[0], self._s[1])


expose_params(
    AcrobotEnv,
    [
        "dt",
        "LINK_LENGTH_1",
        "LINK_LENGTH_2",
        "LINK_MASS_1",
        "LINK_MASS_2",
        "LINK_COM_POS_1",
        "LINK_COM_POS_2",
        "LINK_MOI",
        "MAX_VEL_1",
        "MAX_VEL_2",
    ],
)


class AcrobotBatch(ReplayedBatch):
    """N Acrobots stepped by :func:`step_state`, recorded once and replayed on buffers.

    The step is :func:`step_state` and :func:`observation` run on :class:`~._trace.TraceOps`
    and replayed (:class:`~.batched.ReplayedBatch`): the same float operations per row as the
    single env, without per-step temporaries. The new state's ``cos/sin(theta2)`` (the
    observation's) are kept for the next step's first RK4 stage, for the rows whose ``theta2``
    still has the same bits (others are recomputed).
    """

    state_dim = 4
    reset_draws = RESET_DRAWS

    def __init__(self, num_envs: int) -> None:
        self.params = AcrobotParams()
        self.single_observation_space = observation_space(self.params)
        self.single_action_space = Discrete(3)
        super().__init__(num_envs)
        n = self.num_envs
        # cos/sin of the theta2 whose bits _trig_of holds: of 0.0 at first, exactly.
        self._trig_of = np.zeros(n)
        self._trig = np.stack([np.ones(n), np.zeros(n)])  # [2, N]: cos, sin
        self._torque = np.zeros(n)
        self._terminated = np.zeros(n, dtype=bool)

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture (see :meth:`BatchedEnv.frame`)."""
        return render_acrobot(self._state[row, 0], self._state[row, 1])

    def _parse_options(self, options: dict[str, Any] | None) -> tuple[float, float]:
        return parse_reset_bounds(options, -0.1, 0.1)

    def _reset_state(self, uniforms: np.ndarray, bounds: tuple[float, float]) -> np.ndarray:
        return reset_state(uniforms, *bounds)

    def _record(self) -> Any:
        def batch_step(ops: Any, s0: Any, s1: Any, s2: Any, s3: Any, torque: Any) -> Any:
            known = ops.known("cos", s1), ops.known("sin", s1)  # the last observation's
            *new, terminated = step_state(ops, self.params, s0, s1, s2, s3, torque)
            return (s0, s1, s2, s3), torque, known, new, terminated, observation(ops, *new)[:4]

        ops, _, (state, torque, known, new, terminated, trig) = trace(batch_step, 5)
        blocks = {"state": state, "new": new, "trig": trig, "known": [*known, torque]}
        return ops, {**blocks, "terminated": [terminated]}

    def _swaps(self, rows: slice) -> dict[str, np.ndarray]:
        return {
            "known.0": self._trig[0, rows],
            "known.1": self._trig[1, rows],
            "known.2": self._torque[rows],
            "terminated.0": self._terminated[rows],
        }

    def _step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        replays = self._replays()
        trig = self._trig
        self.refresh_kept(self._state[:, 1], self._trig_of, (trig[0], trig[1]), (np.cos, np.sin))
        np.subtract(actions, 1.0, out=self._torque)  # AVAIL_TORQUE[a] for a in {0, 1, 2}
        state, obs, pos = self._state, self._obs, np.positive
        for rows, prog, steps in replays:
            copy_to_columns(state[rows].T, prog.block("state").T)
            prog.run(steps)
            new, cs = prog.block("new"), prog.block("trig")
            copy_to_columns(new, state[rows])
            copy_to_columns(cs, obs[rows, :4])
            copy_to_columns(new[2:], obs[rows, 4:])
            pos(cs[2:], out=trig[:, rows])
            pos(new[1], out=self._trig_of[rows])
        terminated = self._terminated.copy()
        return np.where(terminated, 0.0, -1.0), terminated

    def _observe(self, rows: np.ndarray | None) -> None:
        # Only fresh rows come here (step_writes_obs): their float32 states get float32 cos/sin.
        sel = slice(None) if rows is None else rows
        self._obs[sel] = reset_observation(self._state[sel].astype(np.float32))
