"""The native engine: a ``BatchedEnv`` (one array step for all rows) plus time limits.

The batched envs of :mod:`palaestra.envs.classic_control` step physics only; this adds what
``make()``'s wrappers add to a single env: a ``TimeLimit`` as a step-counter array, and resets
of the rows that need one. A step is a fixed number of array ops whatever N is; only rows being
reset are looped over, because each row draws from its own generator (row i seeded ``s`` draws
what a single env seeded ``s + i`` draws).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from palaestra.spaces import Space
from palaestra.spaces.batching import batch_space
from palaestra.vector.engine import Infos, Rows, StepResult


class NativeBatch(Protocol):
    """What the engine needs of a batch (classic control's ``BatchedEnv``, toy text's).

    A batch may also have ``last_infos() -> Infos``: the infos of its last reset or step
    (toy text's ``prob``); without it every info is empty. ``frame(row, action)`` draws a row
    (``render_mode="rgb_array"``).
    """

    num_envs: int
    single_observation_space: Space[Any]
    single_action_space: Space[Any]
    seeds: list[int | None]
    _rngs: list[np.random.Generator | None]
    _obs: Any

    def reset(self, *, seed: Any = None, options: Any = None, mask: Any = None) -> Any:
        """Re-sample the masked rows (all if None)."""
        ...

    def step(self, actions: Any, reset_mask: np.ndarray | None = None) -> tuple[Any, Any, Any]:
        """Step every row (reset those in ``reset_mask``): ``(obs, reward, terminated)``."""
        ...


class NativeEngine:
    """Engine over a ``BatchedEnv``; ``max_episode_steps`` None means no time limit.

    With ``render_mode="rgb_array"`` (SB3's ``make_vec_env`` asks for it), ``render()`` draws
    each row with the batch's ``frame``, from its state and the action it last took.
    """

    # For exact resume (utils.run_state): the batch, the time-limit counters, and the last
    # step's outputs (``_truncated`` is only cleared when a comparison ran).
    RUN_STATE = (
        "batch",
        "_steps",
        "_reset_at",
        "_oldest",
        "_compared",
        "_rewards",
        "_terminated",
        "_truncated",
    )

    def __init__(
        self,
        batch: NativeBatch,
        max_episode_steps: int | None,
        metadata: dict[str, Any] | None = None,
        render_mode: str | None = None,
    ) -> None:
        if render_mode not in (None, "rgb_array"):
            raise ValueError(
                f"a native batch draws rgb_array frames only, got render_mode={render_mode!r}"
            )
        if max_episode_steps is not None and (
            not isinstance(max_episode_steps, (int, np.integer)) or max_episode_steps < 1
        ):
            raise ValueError(f"max_episode_steps must be a positive int, got {max_episode_steps}")
        self.batch = batch
        self.num_envs = batch.num_envs
        self.max_episode_steps = max_episode_steps
        self.single_observation_space = batch.single_observation_space
        self.single_action_space = batch.single_action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.metadata = dict(metadata or {})
        self.render_mode = render_mode
        n = self.num_envs
        self.obs = batch._obs  # [N, obs_dim] float32, rewritten in place by the batch
        # Steps since a row's reset = the engine's step count minus the count at that reset:
        # one integer per step instead of an [N] `elapsed += 1` (~0.6 us at 1024 rows).
        self._steps = 0
        self._reset_at = np.zeros(n, dtype=np.int64)  # [N] self._steps at each row's reset
        # A lower bound of _reset_at (resets only raise entries): while steps - limit is below
        # it no row can be truncated, and the [N] comparison is skipped.
        self._oldest = 0
        self._compared = False  # the last step compared (so _truncated may hold True)
        self._rewards = np.zeros(n)  # [N] float64
        self._terminated = np.zeros(n, dtype=bool)  # [N]
        self._truncated = np.zeros(n, dtype=bool)  # [N]
        # No time limit: truncation never happens, so the array stays all False.
        self._sent: tuple[Any, np.ndarray | None] = (None, None)
        self._limit = max_episode_steps
        self._infos = getattr(batch, "last_infos", None)  # None: the batch's infos are empty
        # The actions of the last step, for frames (Pendulum's torque, the taxi's heading): a
        # reference, not a copy, to keep the step free of work only pictures need.
        self._last_actions: Any = None

    def reset(self, mask: np.ndarray | None, seeds: list[int | None], options: Any) -> Infos:
        """Re-sample the masked rows (all if None); infos from the batch (toy text's ``prob``),
        or None (classic control's are empty)."""
        self.batch.reset(seed=seeds, options=options, mask=mask)
        if mask is None:
            self._reset_at[:] = self._steps
        else:
            self._reset_at[mask] = self._steps
        return None if self._infos is None else self._infos()

    def step_send(self, actions: Any, reset_mask: np.ndarray | None) -> None:
        """Remember the actions; the array step runs in :meth:`step_recv`."""
        self._sent = (actions, reset_mask)

    def step_recv(self, timeout: float | None = None) -> StepResult:
        """One array step for every row; rows in the reset mask are then re-sampled."""
        actions, reset_mask = self._sent
        self._sent = (None, None)
        self._last_actions = actions
        # Classic control: the masked rows also step, harmless since a step draws no random
        # numbers and the reset overwrites the whole row state; toy text skips them (its
        # steps draw). The batch does both and writes obs once.
        _, reward, terminated = self.batch.step(actions, reset_mask)
        # The batch reuses its reward/terminated arrays (MountainCar's reward is a constant):
        # copy into ours so callers may overwrite entries.
        np.copyto(self._rewards, reward)
        np.copyto(self._terminated, terminated)
        self._steps += 1
        compared = False
        if self._limit is not None:
            horizon = self._steps - self._limit  # rows reset at or before it are out of time
            if horizon >= self._oldest:
                np.less_equal(self._reset_at, horizon, out=self._truncated)
                compared = True
            elif self._compared:  # no row can be out of time: clear what the last one set
                self._truncated[:] = False
            self._compared = compared
        if reset_mask is not None:
            self._reset_at[reset_mask] = self._steps
        if compared:
            self._oldest = int(np.minimum.reduce(self._reset_at))
        infos = None if self._infos is None else self._infos()
        return self._rewards, self._terminated, self._truncated, infos

    def call(
        self, name: str, args: tuple[Any, ...], kwargs: dict[str, Any], rows: Rows = None
    ) -> tuple[Any, ...]:
        """Call ``name`` on the batch (one result per row, as a loop over envs would give)."""
        rows = range(self.num_envs) if rows is None else rows
        if name == "np_random_seed":
            return tuple(-1 if self.batch.seeds[i] is None else self.batch.seeds[i] for i in rows)
        if name == "np_random":
            return tuple(self.batch._rngs[i] for i in rows)
        if name == "render_mode":
            return tuple(self.render_mode for _ in rows)
        if name == "metadata":  # each row's env's (SB3's VecVideoRecorder reads render_fps)
            return tuple(self.metadata for _ in rows)
        if _is_param(self.batch, name):
            # What a single env exposes as `env.unwrapped.goal_velocity` lives in the batch's
            # params (made from make_vec_env's env_kwargs): SB3's get_attr reads it there.
            value = getattr(getattr(self.batch, "params"), name)  # noqa: B009 (not in the protocol)
            return tuple(value for _ in rows)
        attr = getattr(self.batch, name)
        result = attr(*args, **kwargs) if callable(attr) else attr
        return tuple(result for _ in rows)

    def is_wrapped(self, wrapper_class: type, rows: Rows = None) -> list[bool]:
        """A native batch has no wrappers."""
        return [False for _ in (range(self.num_envs) if rows is None else rows)]

    def set_attr(self, name: str, values: Sequence[Any], rows: Rows = None) -> None:
        """Set ``name`` on the batch: all rows share one value, so the values must agree."""
        first = values[0]
        if any(v is not first and v != first for v in values[1:]):
            raise ValueError(
                f"The rows of a native batch share their attributes; got different values "
                f"for {name!r}. Use vectorization_mode='sync' for per-env attributes."
            )
        if _is_param(self.batch, name):  # as the single env's setter: a new params object
            batch: Any = self.batch  # a classic-control batch: its physics lives in params
            batch.params = dataclasses.replace(batch.params, **{name: first})
        else:
            setattr(self.batch, name, first)

    def render(self, rows: Rows = None) -> tuple[Any, ...]:
        """Each row's frame (``rgb_array``), or one None per row without a render mode."""
        rows = range(self.num_envs) if rows is None else rows
        if self.render_mode is None:
            return tuple(None for _ in rows)
        frame = getattr(self.batch, "frame")  # noqa: B009 (not in the protocol: rendering only)
        actions = self._last_actions
        # A row reset since the last step (its reset count is this step's) has no last action.
        return tuple(
            frame(i, None if actions is None or self._reset_at[i] == self._steps else actions[i])
            for i in rows
        )

    def close(self) -> None:
        """Nothing to release."""


def _is_param(batch: Any, name: str) -> bool:
    """Whether ``name`` is a field of the batch's physics params (and not a batch attribute)."""
    params = getattr(batch, "params", None)
    if not dataclasses.is_dataclass(params) or name in vars(batch):
        return False
    return name in {field.name for field in dataclasses.fields(params)}
