"""CartPole-v0/v1: balance a pole on a cart by pushing it left or right.

Physics equal to Gymnasium 1.x's ``CartPoleEnv`` (Barto, Sutton & Anderson 1983): explicit
Euler with tau = 0.02, float64 state, the same operation order (Gymnasium's ``np.cos`` on a
numpy scalar is the same libm call as ``math.cos``, see ``_ops``), reward 1 per step including
the terminating one, 0 after it (with Gymnasium's warning), or the Sutton-Barto 0/-1 variant.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from palaestra import error, logger
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
from palaestra.rendering.scenes import render_cartpole
from palaestra.spaces import Box, Discrete


@dataclass(frozen=True)
class CartPoleParams:
    """Gymnasium's CartPole constants (derived ones computed in the same order)."""

    gravity: float = 9.8
    masscart: float = 1.0
    masspole: float = 0.1
    total_mass: float = 0.1 + 1.0  # masspole + masscart
    length: float = 0.5  # half the pole's length
    polemass_length: float = 0.1 * 0.5  # masspole * length
    force_mag: float = 10.0
    tau: float = 0.02
    theta_threshold_radians: float = 12 * 2 * math.pi / 360
    x_threshold: float = 2.4
    kinematics_integrator: str = "euler"  # anything else: semi-implicit Euler, as Gymnasium


def step_state(
    ops: Any, p: CartPoleParams, x: Any, x_dot: Any, theta: Any, theta_dot: Any, action: Any
) -> Any:
    """One Euler step (scalars or ``[N]`` arrays): ``(x, x_dot, theta, theta_dot, terminated)``."""
    force = ops.pick(action, -p.force_mag, p.force_mag)  # action 1 pushes right
    costheta = ops.cos(theta)
    sintheta = ops.sin(theta)
    # Association exactly as Gymnasium writes it; float addition is not associative.
    temp = (force + p.polemass_length * (theta_dot * theta_dot) * sintheta) / p.total_mass
    thetaacc = (p.gravity * sintheta - costheta * temp) / (
        p.length * (4.0 / 3.0 - p.masspole * (costheta * costheta) / p.total_mass)
    )
    xacc = temp - p.polemass_length * thetaacc * costheta / p.total_mass
    if p.kinematics_integrator == "euler":
        x = x + p.tau * x_dot
        x_dot = x_dot + p.tau * xacc
        theta = theta + p.tau * theta_dot
        theta_dot = theta_dot + p.tau * thetaacc
    else:
        x_dot = x_dot + p.tau * xacc
        x = x + p.tau * x_dot
        theta_dot = theta_dot + p.tau * thetaacc
        theta = theta + p.tau * theta_dot
    # Gymnasium's x < -t or x > t, as one comparison: equal for every value, NaN included
    # (both False), since -t is exact. Builtin abs works on floats and arrays alike.
    terminated = (abs(x) > p.x_threshold) | (abs(theta) > p.theta_threshold_radians)
    return x, x_dot, theta, theta_dot, terminated


RESET_DRAWS = 4
# Batches of at most this many rows step row by row on Python floats (CartPoleBatch._step_rows).
SCALAR_ROWS = 16


def reset_state(uniforms: np.ndarray, low: float, high: float) -> np.ndarray:
    """Initial states ``[R, 4]`` from ``[R, 4]`` uniforms: every component ~ U(low, high).

    ``low + (high - low) * u`` is numpy's ``uniform`` bit for bit, so this is Gymnasium's draw.
    """
    return low + (high - low) * uniforms


def observation_space(p: CartPoleParams) -> Box:
    """Gymnasium's box: ±2·x_threshold, ±inf, ±2·theta_threshold, ±inf."""
    high = np.array(
        [p.x_threshold * 2, np.inf, p.theta_threshold_radians * 2, np.inf], dtype=np.float32
    )
    return Box(-high, high, dtype=np.float32)


class CartPoleEnv(ClassicControlEnv):
    """Single CartPole: the Python-float fast path of :func:`step_state`."""

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 50}

    def __init__(self, sutton_barto_reward: bool = False, render_mode: str | None = None) -> None:
        self._sutton_barto_reward = sutton_barto_reward
        self.params = CartPoleParams()
        self.action_space = Discrete(2)
        self.observation_space = observation_space(self.params)
        self._init_render(render_mode)
        self._s: tuple[float, float, float, float] | None = None
        self.steps_beyond_terminated: int | None = None

    @property
    def state(self) -> np.ndarray | None:
        """``[x, x_dot, theta, theta_dot]`` as float64 (None before the first reset)."""
        return None if self._s is None else state_array(self._s)

    @state.setter
    def state(self, value: Any) -> None:
        self._s = None if value is None else tuple(float(v) for v in value)  # type: ignore[assignment]

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Advance one step; an action outside ``Discrete(2)`` raises InvalidAction."""
        if type(action) is not int or not 0 <= action < 2:
            action = check_discrete_action(action, self.action_space, 2)
        if self._s is None:
            raise error.ResetNeeded("Call reset before using step method.")
        x, x_dot, theta, theta_dot, terminated = step_state(SCALAR, self.params, *self._s, action)
        self._s = s = (x, x_dot, theta, theta_dot)
        if not terminated:
            reward = 0.0 if self._sutton_barto_reward else 1.0
        elif self.steps_beyond_terminated is None:
            self.steps_beyond_terminated = 0
            reward = -1.0 if self._sutton_barto_reward else 1.0
        else:
            if self.steps_beyond_terminated == 0:
                logger.warn(
                    "You are calling 'step()' even though this environment has already returned "
                    "terminated = True. You should always call 'reset()' once you receive "
                    "'terminated = True' -- any further steps are undefined behavior."
                )
            self.steps_beyond_terminated += 1
            reward = -1.0 if self._sutton_barto_reward else 0.0
        if self.render_mode == "human":
            self.render()
        return np.array(s, dtype=np.float32), reward, terminated, False, {}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start with every component ~ U(-0.05, 0.05) (``options`` low/high override)."""
        super().reset(seed=seed)
        low, high = parse_reset_bounds(options, -0.05, 0.05)
        state = reset_state(self.np_random.random((1, RESET_DRAWS)), low, high)
        self._s = tuple(state[0].tolist())
        self.steps_beyond_terminated = None
        if self.render_mode == "human":
            self.render()
        return np.array(self._s, dtype=np.float32), {}

    def _frame(self) -> np.ndarray:
        if self._s is None:
            raise error.ResetNeeded("Call reset before render.")
        return render_cartpole(np.array(self._s))


expose_params(
    CartPoleEnv,
    [
        "gravity",
        "masscart",
        "masspole",
        "total_mass",
        "length",
        "polemass_length",
        "force_mag",
        "tau",
        "theta_threshold_radians",
        "x_threshold",
        "kinematics_integrator",
    ],
)


class CartPoleBatch(BatchedEnv):
    """N CartPoles stepped by :func:`step_state` on ``[N]`` arrays.

    Rewards follow the single env, including 0 (or -1) for steps after termination.
    """

    state_dim = 4
    reset_draws = RESET_DRAWS
    RUN_STATE = (*BatchedEnv.RUN_STATE, "_live")

    def __init__(self, num_envs: int, sutton_barto_reward: bool = False) -> None:
        self.params = CartPoleParams()
        self.sutton_barto_reward = sutton_barto_reward
        self.single_action_space = Discrete(2)
        self.single_observation_space = observation_space(self.params)
        super().__init__(num_envs)
        n = self.num_envs
        self._live = np.ones(n, dtype=bool)  # [N] not terminated since the last reset
        self._reward = np.zeros(n)  # [N] float64, rewritten every step

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture (see :meth:`BatchedEnv.frame`)."""
        return render_cartpole(self._state[row])

    def _parse_options(self, options: dict[str, Any] | None) -> tuple[float, float]:
        return parse_reset_bounds(options, -0.05, 0.05)

    def _reset_state(self, uniforms: np.ndarray, bounds: tuple[float, float]) -> np.ndarray:
        return reset_state(uniforms, *bounds)

    def _after_reset(self, rows: np.ndarray) -> None:
        self._live[rows] = True

    def _step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        terminated = self._step_rows(actions) if self.num_envs <= SCALAR_ROWS else None
        if terminated is None:
            # The one step_state on [N] arrays: an in-place copy of it ran ~25 µs faster per
            # 1024 rows but was a second CartPole physics; see BENCHMARKS.md (vector section).
            x, x_dot, theta, theta_dot = self._cols  # views: written in place below
            new = step_state(ARRAY, self._array_params(), x, x_dot, theta, theta_dot, actions)
            x[...], x_dot[...], theta[...], theta_dot[...], terminated = new
        # The single env's rule: a terminating step pays -1 (Sutton-Barto) or, the first time
        # only, 1; a non-terminating step pays 0 or 1, even after an earlier termination.
        if self.sutton_barto_reward:
            self._reward[:] = np.where(terminated, -1.0, 0.0)
        else:
            np.less_equal(terminated, self._live, out=self._reward)  # not (terminated and done)
        np.greater(self._live, terminated, out=self._live)  # live and not terminated
        return self._reward, terminated

    def _step_rows(self, actions: np.ndarray) -> np.ndarray | None:
        """A few rows: the single env's float path of :func:`step_state`, row by row.

        On [N] arrays each of its ~25 numpy calls costs ~1 µs whatever N is, so below
        ``SCALAR_ROWS`` rows the Python floats are cheaper (an 8-env PPO or A2C steps 8 rows).
        The same function and the same IEEE operations: bit for bit the array step, as the
        single env is (``tests/envs/test_batched_fast_paths.py`` compares the two). None,
        with the state untouched, where an angle is infinite: ``math.cos`` raises there,
        ``np.cos`` gives NaN, and the array step decides.
        """
        p = self.params
        try:
            rows = [
                step_state(SCALAR, p, x, x_dot, theta, theta_dot, a)
                for (x, x_dot, theta, theta_dot), a in zip(self._state.tolist(), actions.tolist())
            ]
        except ValueError:  # math domain error
            return None
        self._state[...] = [row[:4] for row in rows]
        return np.array([row[4] for row in rows])

    def _observe(self, rows: np.ndarray | None) -> None:
        if rows is None:
            np.copyto(self._obs, self._state)  # float64 -> float32, as np.array(s, float32)
        else:
            self._obs[rows] = self._state[rows]


def __getattr__(name: str) -> Any:  # PEP 562 module attribute: built on first use
    if name == "CartPoleVectorEnv":
        return _vector_env_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@functools.cache
def _vector_env_class() -> type:
    """Gymnasium's ``CartPoleVectorEnv``, built on first use: its base lives in
    ``palaestra.vector``, which loads multiprocessing, and making a single CartPole must not."""
    from palaestra.vector.native import BatchedVectorEnv  # lazy: import-time — palaestra.vector

    class CartPoleVectorEnv(BatchedVectorEnv):
        """Gymnasium's ``CartPoleVectorEnv(num_envs, max_episode_steps, render_mode,
        sutton_barto_reward)``: :class:`CartPoleBatch` behind the vector API, as
        ``make_vec("CartPole-v1", num_envs)`` builds it, with time limits and next-step
        autoreset. Row i of ``reset(seed=s)`` is a single CartPole seeded ``s + i``
        (Gymnasium's draws all rows from one generator); ``render()`` draws each row.
        """

        def __init__(
            self,
            num_envs: int = 1,
            max_episode_steps: int = 500,
            render_mode: str | None = None,
            sutton_barto_reward: bool = False,
        ) -> None:
            modes = ["rgb_array"]  # Gymnasium's: the frames of all rows, no window
            if render_mode is not None and render_mode not in modes:
                raise error.UnsupportedMode(f"render_mode={render_mode!r} is not one of {modes}")
            batch = CartPoleBatch(num_envs, sutton_barto_reward=sutton_barto_reward)
            metadata = {"render_modes": modes, "render_fps": CartPoleEnv.metadata["render_fps"]}
            super().__init__(batch, max_episode_steps, metadata=metadata)
            self.render_mode = render_mode

        def render(self) -> tuple[np.ndarray, ...] | None:  # type: ignore[override]
            """One ``[400, 600, 3]`` frame per row (``rgb_array``); None, with Gymnasium's
            warning, without a render mode."""
            if self.render_mode is None:
                logger.warn(
                    "You are calling render method without specifying any render mode. You can "
                    'specify the render_mode at initialization, e.g. gym.make_vec("CartPole-v1", '
                    'render_mode="rgb_array")'
                )
                return None
            batch = self.batch  # a CartPoleBatch: it draws its rows
            return tuple(batch.frame(i) for i in range(self.num_envs))  # type: ignore[attr-defined]

    CartPoleVectorEnv.__qualname__ = "CartPoleVectorEnv"  # pickled by this module's name
    return CartPoleVectorEnv
