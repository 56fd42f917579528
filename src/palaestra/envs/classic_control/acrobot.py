"""Acrobot-v1: swing the tip of a two-link pendulum above the bar by torquing the middle joint.

Dynamics equal to Gymnasium 1.x's ``AcrobotEnv`` ("book" equations of Sutton & Barto, one RK4
step of dt = 0.2 per action, angles wrapped to [-pi, pi], velocities bounded), evaluated in the
same order. Gymnasium's quirks kept: the reset state is float32 (so the first observation's
cos/sin are float32 numpy math) while every later state is float64; ``x**2`` is libm ``pow``
(see ``_ops``). Torque noise (``torque_noise_max``, 0 in Gymnasium) is not modelled.
"""

from __future__ import annotations

import functools
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
from palaestra.envs.classic_control._ops import SCALAR, SquareKernel
from palaestra.envs.classic_control.batched import BatchedEnv
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


def wrap(ops: Any, x: Any, lo: float, hi: float) -> Any:
    """Shift ``x`` by whole periods into [lo, hi], one period at a time (as Gymnasium)."""
    diff = hi - lo
    while ops.any(x > hi):
        x = ops.where(x > hi, x - diff, x)
    while ops.any(x < lo):
        x = ops.where(x < lo, x + diff, x)
    return x


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
    n0 = wrap(ops, n0, -math.pi, math.pi)
    n1 = wrap(ops, n1, -math.pi, math.pi)
    n2 = ops.clip(n2, -p.MAX_VEL_1, p.MAX_VEL_1)
    n3 = ops.clip(n3, -p.MAX_VEL_2, p.MAX_VEL_2)
    terminated = -ops.cos(n0) - ops.cos(n1 + n0) > 1.0
    return n0, n1, n2, n3, terminated


class BatchStep:
    """:func:`step_state` for ``[N]`` arrays, as a fixed sequence of numpy calls on buffers.

    The same float operations per element, in the same order, as Gymnasium's scalar code
    (and :func:`step_state`), so rows stay bit-exact; only the bookkeeping differs, for
    speed. Written out with ``ARRAY`` ops a step is ~350 numpy calls, each with a fixed cost
    (~1 us) and, at 16,384 rows, a fresh 128 KiB temporary (past glibc malloc's mmap
    threshold: page-faulted anew). Here each RK4 stage's input, derivative and the terms
    that share an operation sit as rows of stacked buffers, so one call covers several
    terms (``[c1, c2] * cos2`` is one broadcast product; the four components' ``y + h*k``
    one add), and every call writes into preallocated arrays (``out=``): ~210 calls and no
    temporaries besides the torque, reward and terminated arrays. The final state's
    ``cos/sin(theta2)`` (the observation's) are kept and reused by the next step's first
    stage for the rows whose ``theta2`` is bit for bit unchanged, and the terminal test
    reuses the observation's ``cos(theta1)``: 19 trig evaluations per row and step, not 22.
    """

    def __init__(self, p: AcrobotParams, n: int) -> None:
        self.params = p
        m1, m2, l1 = p.LINK_MASS_1, p.LINK_MASS_2, p.LINK_LENGTH_1
        lc1, lc2, i1, i2, g = p.LINK_COM_POS_1, p.LINK_COM_POS_2, p.LINK_MOI, p.LINK_MOI, p.g
        # Python-float subexpressions of Gymnasium's formulas, grouped as Python parses them
        # (left to right); each is then one product or sum with an array, as in Gymnasium.
        # Constants as 0-d arrays (numpy converts a Python float on every call), and the
        # per-row columns as full [k, N] arrays up to 4096 rows, where a broadcast's set-up
        # (~1.3 us a call) costs more than reading one more array.
        zero_d = functools.partial(np.array, dtype=np.float64)

        def col(values: list[list[float]]) -> np.ndarray:
            c = np.array(values, dtype=np.float64)
            return np.repeat(c, n, axis=1) if n <= 4096 else c

        self._m2 = m2
        self._i1, self._i2 = zero_d(i1), zero_d(i2)
        self._cos2_coef = col([[2 * l1 * lc2], [l1 * lc2]])  # d1's and d2's cos(theta2) terms
        self._cos2_add = col([[l1**2 + lc2**2], [lc2**2]])
        self._d_add = col([[m1 * lc1**2], [i2]])  # d1's first term; d2's last
        self._phi_coef = col([[m2 * lc2 * g], [(m1 * lc1 + m2 * l1) * g]])  # phi2, phi1's cos
        self._sq_coef = col([[m2 * l1 * lc2], [-m2 * l1 * lc2]])  # of dtheta1**2, dtheta2**2
        self._cross_coef = 2 * m2 * l1 * lc2  # of dtheta2 * dtheta1
        self._den = zero_d(m2 * lc2**2 + i2)
        self._half_pi = zero_d(math.pi / 2.0)
        self._h = tuple(zero_d(h) for h in (p.dt / 2.0, p.dt / 2.0, p.dt))  # k1 -> stage 2, ...
        self._h6 = zero_d(p.dt / 6.0)
        self._two = zero_d(2.0)
        self._pi, self._two_pi, self._minus_pi = (
            zero_d(math.pi),
            zero_d(2 * math.pi),
            zero_d(-math.pi),
        )
        self._minus_one = zero_d(-1.0)
        self._vel_lo = col([[-p.MAX_VEL_1], [-p.MAX_VEL_2]])
        self._vel_hi = col([[p.MAX_VEL_1], [p.MAX_VEL_2]])
        self.n = n
        # Stage j's rows: theta1 + theta2, then its input y = (theta1, theta2, dtheta1,
        # dtheta2) at rows 1:5 and its derivative k = (dtheta1, dtheta2, ddtheta1, ddtheta2)
        # at rows 3:7 (a stage's derivative starts with its own input velocities).
        self._stages = np.empty((4, 7, n))
        self._uv = np.empty((2, n))  # the two cos arguments, then phi2 and phi1's cos term
        self._cs = np.empty((2, n))  # cos/sin(theta2) of stages 2-4
        self._d = np.empty((4, n))  # d1, d2, dtheta1, dtheta2 (the last three squared)
        self._sq = np.empty((3, n))  # d2**2, dtheta1**2, dtheta2**2 (libm pow)
        self._square = SquareKernel((3, n))
        self._terms = np.empty((3, n))
        self._phi1 = np.empty(n)
        self._num = np.empty(n)
        self._den_arr = np.empty(n)
        self._k = np.empty((4, n))  # h * k, then the RK4 sum
        self._k23 = np.empty((2, 4, n))  # 2 * k2, 2 * k3
        self._new = np.full((4, n), np.nan)  # the new state (theta2 row: the trig cache key)
        self._trig = np.empty((2, 2, n))  # [cos, sin] of the new [theta1, theta2]
        self._trig[0], self._trig[1] = np.cos(self._new[:2]), np.sin(self._new[:2])
        self._sum = np.empty(n)
        self._mask = np.empty((2, n), dtype=bool)

    def __call__(self, state: np.ndarray, torque: np.ndarray, obs: np.ndarray) -> np.ndarray:
        """Step ``state`` (``[N, 4]`` float64) in place under ``torque`` ``[N]``; write the
        observations into ``obs`` (``[N, 6]`` float32); return ``terminated`` (new ``[N]``)."""
        st, new, trig = self._stages, self._new, self._trig
        s = st[0, 1:5]
        np.copyto(s, state.T)
        # Rows whose theta2 changed since the last step (resets, writes to ``state``).
        stale = (s[1].view(np.uint64) != new[1].view(np.uint64)).nonzero()[0]
        if stale.size:
            th2 = s[1][stale]
            trig[0, 1][stale], trig[1, 1][stale] = np.cos(th2), np.sin(th2)
        for j in range(4):
            self._derivative(st[j], trig[:, 1] if j == 0 else None, torque)
            if j < 3:
                np.multiply(st[j, 3:7], self._h[j], out=self._k)
                np.add(s, self._k, out=st[j + 1, 1:5])  # y + h * k
        # y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        acc = self._k
        np.multiply(st[1:3, 3:7], self._two, out=self._k23)
        np.add(st[0, 3:7], self._k23[0], out=acc)
        acc += self._k23[1]
        acc += st[3, 3:7]
        acc *= self._h6
        np.add(s, acc, out=new)
        self._wrap(new[:2])
        np.clip(new[2:], self._vel_lo, self._vel_hi, out=new[2:])
        np.copyto(state, new.T)
        np.cos(new[:2], out=trig[0])
        np.sin(new[:2], out=trig[1])
        # -cos(theta1) - cos(theta2 + theta1) > 1, as -(a + b) > 1 (negation is exact)
        np.add(new[1], new[0], out=self._sum)
        np.cos(self._sum, out=self._sum)
        self._sum += trig[0, 0]
        terminated = np.less(self._sum, self._minus_one)
        # obs columns: cos/sin of theta1, cos/sin of theta2, the two velocities
        o = obs.reshape(self.n, 3, 2)
        np.copyto(o[:, :2], trig.transpose(2, 1, 0), casting="same_kind")
        np.copyto(o[:, 2], new[2:].T, casting="same_kind")
        return terminated

    def _derivative(self, y: np.ndarray, cs: np.ndarray | None, torque: np.ndarray) -> None:
        """Fill ``y[5:7]`` (ddtheta1, ddtheta2) of stage rows ``y`` (see :class:`BatchStep`):
        Gymnasium's ``_dsdt``, the "book" equations. ``cs``: cos/sin(theta2) if known."""
        th1, th2, dth1, dth2 = y[1], y[2], y[3], y[4]
        if cs is None:
            cs = self._cs
            np.cos(th2, out=cs[0])
            np.sin(th2, out=cs[1])
        cos2, sin2 = cs[0], cs[1]
        uv, d, sq, terms = self._uv, self._d, self._sq, self._terms
        np.add(th1, th2, out=y[0])
        np.subtract(y[0:2], self._half_pi, out=uv)  # theta1 + theta2 - pi/2, theta1 - pi/2
        np.cos(uv, out=uv)
        uv *= self._phi_coef  # phi2; (m1 lc1 + m2 l1) g cos(theta1 - pi/2)
        # d1 = m1 lc1**2 + m2 (l1**2 + lc2**2 + 2 l1 lc2 cos2) + I1 + I2
        # d2 = m2 (lc2**2 + l1 lc2 cos2) + I2
        dd = d[:2]
        np.multiply(self._cos2_coef, cos2, out=dd)
        dd += self._cos2_add
        if self._m2 != 1.0:  # x * 1.0 is x
            dd *= self._m2
        dd += self._d_add
        d1, d2 = d[0], d[1]
        d1 += self._i1
        d1 += self._i2
        np.copyto(d[2:], y[3:5])
        self._square(d[1:], sq)  # d2**2, dtheta1**2, dtheta2**2 (libm pow)
        # m2 l1 lc2 dtheta1**2 sin2, -m2 l1 lc2 dtheta2**2 sin2, 2 m2 l1 lc2 dtheta2 dtheta1 sin2
        np.multiply(sq[1:], self._sq_coef, out=terms[:2])
        if self._cross_coef == 1.0:  # x * 1.0 is x
            np.multiply(dth2, dth1, out=terms[2])
        else:
            np.multiply(dth2, self._cross_coef, out=terms[2])
            terms[2] *= dth1
        terms *= sin2
        phi1 = self._phi1
        np.subtract(terms[1], terms[2], out=phi1)
        phi1 += uv[1]
        phi1 += uv[0]
        # ddtheta2 = (a + d2 / d1 phi1 - m2 l1 lc2 dtheta1**2 sin2 - phi2)
        #            / (m2 lc2**2 + I2 - d2**2 / d1)
        num, den = self._num, self._den_arr
        np.divide(d2, d1, out=num)
        num *= phi1
        np.add(torque, num, out=num)
        num -= terms[0]
        num -= uv[0]
        np.divide(sq[0], d1, out=den)
        np.subtract(self._den, den, out=den)
        np.divide(num, den, out=y[6])
        # ddtheta1 = -(d2 ddtheta2 + phi1) / d1
        np.multiply(d2, y[6], out=num)
        num += phi1
        np.negative(num, out=num)
        np.divide(num, d1, out=y[5])

    def _wrap(self, x: np.ndarray) -> None:
        """:func:`wrap` of both angle rows of ``x`` into [-pi, pi], in place."""
        diff, mask = self._two_pi, self._mask
        while np.greater(x, self._pi, out=mask).any():
            np.subtract(x, diff, out=x, where=mask)
        while np.less(x, self._minus_pi, out=mask).any():
            np.add(x, diff, out=x, where=mask)


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
        s0, s1, s2, s3 = s
        obs = np.array(
            (math.cos(s0), math.sin(s0), math.cos(s1), math.sin(s1), s2, s3), dtype=np.float32
        )
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


class AcrobotBatch(BatchedEnv):
    """N Acrobots stepped by :func:`step_state` on ``[N]`` arrays."""

    state_dim = 4
    reset_draws = RESET_DRAWS
    obs_of_state = False  # fresh rows hold float32 states and get float32 cos/sin

    def __init__(self, num_envs: int) -> None:
        self.params = AcrobotParams()
        self.single_observation_space = observation_space(self.params)
        self.single_action_space = Discrete(3)
        super().__init__(num_envs)
        self._kernel: BatchStep | None = None  # made at the first step (and for new params)
        self._observed = False  # whether _step already wrote every row's observation

    def __getstate__(self) -> dict[str, Any]:
        state = super().__getstate__()
        state["_kernel"] = None  # scratch buffers; its trig cache checks itself against state
        return state

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture (see :meth:`BatchedEnv.frame`)."""
        return render_acrobot(self._state[row, 0], self._state[row, 1])

    def _parse_options(self, options: dict[str, Any] | None) -> tuple[float, float]:
        return parse_reset_bounds(options, -0.1, 0.1)

    def _reset_state(self, uniforms: np.ndarray, bounds: tuple[float, float]) -> np.ndarray:
        return reset_state(uniforms, *bounds)

    def _step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        kernel = self._kernel
        if kernel is None or kernel.params is not self.params:
            kernel = self._kernel = BatchStep(self.params, self.num_envs)
        torque = actions - 1.0  # AVAIL_TORQUE[a] for a in {0, 1, 2}
        terminated = kernel(self._state, torque, self._obs)
        self._observed = True  # the kernel wrote every row's observation
        return terminated - 1.0, terminated  # reward 0 where terminated, else -1

    def _observe(self, rows: np.ndarray | None) -> None:
        if rows is not None:  # fresh rows hold float32 states: float32 cos/sin
            self._obs[rows] = reset_observation(self._state[rows].astype(np.float32))
            return
        if self._observed:  # by the step just taken
            self._observed = False
            return
        th1, th2, dth1, dth2 = self._cols
        self._obs[:, 0], self._obs[:, 1] = np.cos(th1), np.sin(th1)
        self._obs[:, 2], self._obs[:, 3] = np.cos(th2), np.sin(th2)
        self._obs[:, 4], self._obs[:, 5] = dth1, dth2
