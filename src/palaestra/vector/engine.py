"""Engines: the one layer that steps N sub-envs, whatever runs them.

An engine owns a batched observation buffer ``obs`` and steps or resets chosen rows in place.
It knows nothing of autoreset modes or of how infos are presented: :mod:`.autoreset` drives it
and the two faces (:mod:`palaestra.vector`, :mod:`palaestra.vec_env`) present the results.

Three engines implement :class:`Engine`: :class:`LoopEngine` (here: a Python loop over env
objects in this process), :class:`~.process_engine.ProcessEngine` (one worker process per env,
observations in shared memory) and :class:`~.native_engine.NativeEngine` (a native
``BatchedEnv``: one array step for all rows, time limits as a step-counter array).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol

import numpy as np

from palaestra import error
from palaestra.core import Env
from palaestra.spaces import Box, Discrete, MultiBinary, MultiDiscrete, Space
from palaestra.spaces.batched_samples import (
    concatenate,
    concatenate_array,
    create_empty_array,
    iterate,
)
from palaestra.spaces.batching import batch_differing_spaces, batch_space
from palaestra.spaces.utils import is_space_dtype_shape_equiv

# One raw info dict per row (a list, or a StackedInfos holding them as arrays); None: every
# dict is empty.
Infos = Sequence[dict[str, Any]] | None
Rows = Sequence[int] | None  # sub-env indices; None: all
StepResult = tuple[np.ndarray, np.ndarray, np.ndarray, Infos]
_REAL_KINDS = "biuf"  # bool, int, uint, float: the dtype kinds of numeric actions
# Spaces whose batch is one array indexed by row: ``iterate`` walks it with ``iter`` and
# ``concatenate`` stacks into it (``concatenate_array``). Exact types: a subclass may register
# its own functions.
_ARRAY_SPACES = (Box, Discrete, MultiBinary, MultiDiscrete)


class Engine(Protocol):
    """What the autoreset layer needs from an engine."""

    num_envs: int
    single_observation_space: Space[Any]
    single_action_space: Space[Any]
    observation_space: Space[Any]
    action_space: Space[Any]
    metadata: dict[str, Any]
    render_mode: str | None
    obs: Any  # batched observations, rewritten in place by reset/step

    def reset(self, mask: np.ndarray | None, seeds: list[int | None], options: Any) -> Infos:
        """Reset the rows in ``mask`` (all if None) with per-row seeds; write ``obs``."""
        ...

    def step_send(self, actions: Any, reset_mask: np.ndarray | None) -> None:
        """Start stepping every row, except rows in ``reset_mask``: those are reset (no seed)."""
        ...

    def step_recv(self, timeout: float | None = None) -> StepResult:
        """Finish the step: ``(rewards [N] f64, terminated [N], truncated [N], infos)``.

        Entries of reset rows are left for the caller to overwrite. The arrays are reused.
        """
        ...

    def call(
        self, name: str, args: tuple[Any, ...], kwargs: dict[str, Any], rows: Rows = None
    ) -> tuple[Any, ...]:
        """Call method ``name`` (or read attribute ``name``) on each sub-env in ``rows``."""
        ...

    def set_attr(self, name: str, values: Sequence[Any], rows: Rows = None) -> None:
        """Set attribute ``name`` on each sub-env in ``rows`` to its value."""
        ...

    def is_wrapped(self, wrapper_class: type, rows: Rows = None) -> list[bool]:
        """Whether each sub-env in ``rows`` has a ``wrapper_class`` layer."""
        ...

    def render(self) -> tuple[Any, ...]:
        """Every sub-env's frame."""
        ...

    def close(self) -> None:
        """Release sub-envs and workers; idempotent."""
        ...


def check_actions_batch(space: Space[Any], actions: Any, num_envs: int) -> None:
    """A clear error for a batch of array actions of the wrong shape or kind.

    Per-element validity (range, NaN) is the sub-env's business; this catches the batch-level
    mistakes that would otherwise surface as a confusing error deep inside ``iterate`` or reach
    a user's env unnoticed (complex values, strings, ``None``: Gymnasium passes them on).
    """
    shape = getattr(space, "shape", None)
    if shape is None or not isinstance(actions, (np.ndarray, list, tuple)):
        return
    dtype = getattr(space, "dtype", None)
    numeric = dtype is not None and dtype.kind in _REAL_KINDS
    try:
        arr = np.asarray(actions) if not isinstance(actions, np.ndarray) else actions
    except ValueError:  # ragged nesting
        if not numeric:
            return
        raise error.InvalidAction(
            f"Invalid actions {actions!r} for action space {space} ({num_envs} envs): not a "
            f"rectangular array of shape {shape}"
        ) from None
    if arr.dtype.kind == "O" and not numeric:  # object arrays (kind "O": ~0.2 µs cheaper)
        return
    if arr.shape != shape:
        raise error.InvalidAction(
            f"Expected a batch of actions of shape {shape} for action space {space} "
            f"({num_envs} envs), got shape {arr.shape}"
        )
    if dtype is not None and numeric:
        integer = dtype.kind in "iu"
        if arr.dtype.kind not in ("iub" if integer else _REAL_KINDS):
            raise error.InvalidAction(
                f"Invalid actions {actions!r} for action space {space}: expected "
                f"{'integer' if integer else 'real'} values, got dtype {arr.dtype}"
            )


def batch_spaces(
    env_spaces: Sequence[Space[Any]], observation_mode: Any, who: str
) -> tuple[Space[Any], Space[Any]]:
    """``(single, batched)`` observation space from the sub-envs' spaces, checked.

    ``observation_mode`` is Gymnasium's: "same" (all equal), "different" (same shape and
    dtype, bounds may differ) or a ``(batched, single)`` pair of spaces.
    """
    first = env_spaces[0]
    if isinstance(observation_mode, tuple) and len(observation_mode) == 2:
        batched, single = observation_mode
        if not isinstance(batched, Space) or not isinstance(single, Space):
            raise TypeError(
                "Expected both elements of observation_mode to be Spaces, "
                f"got {type(batched)} and {type(single)}"
            )
    elif observation_mode == "same":
        single, batched = first, batch_space(first, len(env_spaces))
    elif observation_mode == "different":
        single, batched = first, batch_differing_spaces(list(env_spaces))
    else:
        raise ValueError(
            "Invalid `observation_mode`, expected: 'same' or 'different' or tuple of single and "
            f"batch observation space, actual got {observation_mode}"
        )
    for i, space in enumerate(env_spaces):
        if observation_mode == "same":
            if space != single:
                raise RuntimeError(
                    f"{who}(..., observation_mode='same') however the sub-environments "
                    f"observation spaces are not equivalent: sub-environment 0 has {single}, "
                    f"sub-environment {i} has {space}. If this is intentional, use "
                    "`observation_mode='different'` instead."
                )
        elif not is_space_dtype_shape_equiv(space, single):
            raise RuntimeError(
                f"{who}(..., observation_mode='different' or custom space) however the "
                "sub-environments observation spaces do not share a common shape and dtype: "
                f"single_observation_space={single}, sub-environment {i} has {space}"
            )
    return single, batched


def check_action_spaces(env_spaces: Sequence[Space[Any]], who: str) -> Space[Any]:
    """The common action space; every sub-env must have exactly it."""
    for i, space in enumerate(env_spaces):
        if space != env_spaces[0]:
            raise RuntimeError(
                f"{who}: sub-environment {i} has action space {space}, which is not the "
                f"`single_action_space` {env_spaces[0]} of sub-environment 0"
            )
    return env_spaces[0]


def call_env(env: Env[Any, Any], name: str, args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any:
    """``env.name(*args, **kwargs)``, or the attribute's value when it is not callable."""
    attr = env.get_wrapper_attr(name)
    return attr(*args, **kwargs) if callable(attr) else attr


def unwrap_wrapper(env: Any, wrapper_class: type) -> Any:
    """The outermost layer of ``env``'s wrapper stack that is a ``wrapper_class``, or None."""
    while env is not None:
        if isinstance(env, wrapper_class):
            return env
        env = getattr(env, "env", None)
    return None


def is_wrapped(env: Any, wrapper_class: type) -> bool:
    """Whether any layer of ``env``'s wrapper stack is a ``wrapper_class``."""
    return unwrap_wrapper(env, wrapper_class) is not None


def check_env_fns(env_fns: Sequence[Callable[[], Env[Any, Any]]], who: str) -> None:
    """At least one env function, each callable (``InvalidEnvFunction`` names the first that
    is not: usually an env passed where a function making one belongs)."""
    if len(env_fns) == 0:
        raise ValueError(f"{who} needs at least one environment function")
    for i, fn in enumerate(env_fns):
        if not callable(fn):
            raise error.InvalidEnvFunction(
                f"{who}: env_fns[{i}] is {fn!r:.200}, not a function that makes an env: pass "
                "e.g. `lambda: palaestra.make(...)`, which makes a new env at each call"
            )


class LoopEngine:
    """Sub-env objects in this process, stepped one after the other."""

    def __init__(
        self, env_fns: Sequence[Callable[[], Env[Any, Any]]], observation_mode: Any, who: str
    ) -> None:
        check_env_fns(env_fns, who)
        self.envs = [fn() for fn in env_fns]
        for i, env in enumerate(self.envs):
            if not isinstance(env, Env):
                raise TypeError(
                    f"{who}: env_fns[{i}] returned {type(env)}, not a palaestra.Env (wrap a "
                    "Gymnasium env with palaestra's adapter first: "
                    "`palaestra.compat.from_gymnasium(env)`)"
                )
        self.num_envs = len(self.envs)
        first = self.envs[0]
        self.metadata = dict(first.metadata)
        self.render_mode = first.render_mode
        self.single_observation_space, self.observation_space = batch_spaces(
            [env.observation_space for env in self.envs], observation_mode, who
        )
        self.single_action_space = check_action_spaces([env.action_space for env in self.envs], who)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.obs = create_empty_array(self.single_observation_space, n=self.num_envs)
        self._env_obs: list[Any] = [None] * self.num_envs
        self._rewards = np.zeros(self.num_envs)  # [N] float64
        self._terminated = np.zeros(self.num_envs, dtype=bool)  # [N]
        self._truncated = np.zeros(self.num_envs, dtype=bool)  # [N]
        self._sent: tuple[Any, np.ndarray | None] = (None, None)
        # The single-dispatch calls cost ~1 us each per step (DQN's one env): array spaces
        # call what they would dispatch to directly.
        # (A batched Discrete is a MultiDiscrete: iterate refuses a Discrete batch.)
        self._array_actions = type(self.action_space) in (Box, MultiBinary, MultiDiscrete)
        self._array_obs = type(self.single_observation_space) in _ARRAY_SPACES

    def _stack_obs(self) -> None:
        """The sub-envs' latest observations into ``self.obs``."""
        if self._array_obs:
            self.obs = concatenate_array(self.single_observation_space, self._env_obs, self.obs)
        else:
            self.obs = concatenate(self.single_observation_space, self._env_obs, self.obs)

    def reset(self, mask: np.ndarray | None, seeds: list[int | None], options: Any) -> Infos:
        """Reset the masked rows (all if None), each with its seed."""
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for i, env in enumerate(self.envs):
            if mask is None or mask[i]:
                # `options` only when there are some: SB3 calls reset(seed=...) alone, and
                # envs written for it may take no `options`.
                extra = {} if options is None else {"options": options}
                self._env_obs[i], infos[i] = env.reset(seed=seeds[i], **extra)
        self._stack_obs()
        return infos

    def step_send(self, actions: Any, reset_mask: np.ndarray | None) -> None:
        """Check the actions; the loop runs in :meth:`step_recv`."""
        check_actions_batch(self.action_space, actions, self.num_envs)
        self._sent = (actions, reset_mask)

    def step_recv(self, timeout: float | None = None) -> StepResult:
        """Step each row (or reset it, where the mask says)."""
        actions, reset_mask = self._sent
        if (
            self.num_envs == 1
            and reset_mask is None
            and self._array_actions
            and type(actions) is np.ndarray
            and actions.ndim
            and len(actions) == 1
        ):  # one env stepped (DQN, SAC): the loop below for its one row, without the loop
            info = self._step_row(0, actions[0])
            self._stack_obs()
            return self._rewards, self._terminated, self._truncated, [info]
        infos: list[dict[str, Any]] = [{}] * self.num_envs
        rows = (
            iter(actions)  # what iterate does for these spaces (a 0-d array raises TypeError)
            if self._array_actions and type(actions) is np.ndarray and actions.ndim
            else iterate(self.action_space, actions)
        )
        for i, action in enumerate(rows):
            if i >= self.num_envs:
                raise error.InvalidAction(f"Got more than {self.num_envs} actions: {actions!r}")
            if reset_mask is not None and reset_mask[i]:
                self._env_obs[i], infos[i] = self.envs[i].reset()
                continue
            infos[i] = self._step_row(i, action)
        self._stack_obs()
        return self._rewards, self._terminated, self._truncated, infos

    def _step_row(self, i: int, action: Any) -> dict[str, Any]:
        """Step sub-env ``i``; its results go into row ``i`` of the arrays, its info is returned."""
        (
            self._env_obs[i],
            self._rewards[i],
            self._terminated[i],
            self._truncated[i],
            info,
        ) = self.envs[i].step(action)
        return info

    def final_observations(self, rows: np.ndarray) -> list[Any]:
        """Copies of the observations the sub-envs in ``rows`` returned from their last step
        (read before autoreset replaces them)."""
        return [copy_obs(self._env_obs[i]) for i in rows.tolist()]

    def _targets(self, rows: Rows) -> list[Env[Any, Any]]:
        return self.envs if rows is None else [self.envs[i] for i in rows]

    def call(
        self, name: str, args: tuple[Any, ...], kwargs: dict[str, Any], rows: Rows = None
    ) -> tuple[Any, ...]:
        """Call ``name`` on each sub-env, or read it when it is not callable."""
        return tuple(call_env(env, name, args, kwargs) for env in self._targets(rows))

    def set_attr(self, name: str, values: Sequence[Any], rows: Rows = None) -> None:
        """Set ``name`` on each sub-env (on the outermost layer that has it)."""
        for env, value in zip(self._targets(rows), values):
            env.set_wrapper_attr(name, value)

    def is_wrapped(self, wrapper_class: type, rows: Rows = None) -> list[bool]:
        """Whether each sub-env has a ``wrapper_class`` layer."""
        return [is_wrapped(env, wrapper_class) for env in self._targets(rows)]

    def render(self) -> tuple[Any, ...]:
        """Each sub-env's frame."""
        return tuple(env.render() for env in self.envs)

    def close(self) -> None:
        """Close each sub-env."""
        for env in self.envs:
            env.close()


def copy_obs(item: Any) -> Any:
    """A copy of one observation that keeps its types (arrays, dicts, tuples, NamedTuples)."""
    if isinstance(item, np.ndarray):
        return item.copy()
    if isinstance(item, dict):
        return {k: copy_obs(v) for k, v in item.items()}
    if isinstance(item, tuple):
        if hasattr(item, "_fields"):  # a NamedTuple such as GraphInstance keeps its type
            return type(item)(*(copy_obs(v) for v in item))
        return tuple(copy_obs(v) for v in item)
    return item
