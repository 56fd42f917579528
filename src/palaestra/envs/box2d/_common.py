"""What the Box2D envs share: the lazy ``Box2D`` import, action checks and kwarg checks."""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from copy import deepcopy
from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.action_checks import invalid_action

_REAL_KINDS = "biuf"


def import_box2d() -> Any:
    """The ``Box2D`` module, or ``DependencyNotInstalled`` naming the extra to install."""
    try:
        import Box2D
    except ImportError as e:
        raise error.dependency_not_installed(
            "box2d", "box2d", "the Box2D environments: LunarLander, BipedalWalker, CarRacing"
        ) from e
    return Box2D


def check_bool(name: str, value: Any) -> bool:
    """A ``bool`` (or numpy bool) kwarg, else ``TypeError`` naming it: ``"False"`` is truthy."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise TypeError(f"{name} must be a bool, got {value!r} ({type(value).__name__})")


def check_real(name: str, value: Any) -> float:
    """A finite real kwarg as a float, else ``TypeError``/``ValueError`` naming it."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
        raise TypeError(f"{name} must be a real number, got {value!r} ({type(value).__name__})")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return number


def box_action(action: Any, space: Any, keep_float_dtype: bool = False) -> np.ndarray:
    """A continuous action as a float64 ``space.shape`` array, else InvalidAction.

    Values keep their own precision (a float64 action is not rounded to float32), because
    Gymnasium clips and computes with ``astype(np.float64)``; with ``keep_float_dtype`` a float
    array keeps its dtype (for envs whose Gymnasium arithmetic runs in the action's own type)
    and integers still become float64. Out-of-bound finite values are
    accepted and clipped by the env, as in Gymnasium; NaN, inf, strings, complex numbers and
    wrong shapes are refused with the action and the space in the message.
    """
    try:
        raw = np.asarray(action)
    except (TypeError, ValueError) as e:
        raise invalid_action(action, space, "not a numeric array") from e
    if raw.dtype.kind not in _REAL_KINDS:
        why = f"expected real numeric values, got dtype {raw.dtype}"
        raise invalid_action(action, space, why)
    if raw.shape != space.shape:
        why = f"expected shape {space.shape}, got {raw.shape}"
        if raw.ndim == 0:
            why += " (a discrete action given to a continuous env?)"
        raise invalid_action(action, space, why)
    arr = raw if keep_float_dtype and raw.dtype.kind == "f" else raw.astype(np.float64)
    if not np.isfinite(arr).all():
        raise invalid_action(action, space, "actions must be finite (no NaN or inf)")
    return arr


def discrete_action(action: Any, space: Any) -> int:
    """A discrete action as an ``int`` in ``[0, n)``, else InvalidAction naming it."""
    n = int(space.n)
    if type(action) is int or type(action) is np.int64:
        if 0 <= action < n:
            return int(action)
    elif space.contains(action):
        return int(action)
    why = ""
    if np.ndim(action) > 0:
        why = "expected one integer (an array given to a discrete env? use continuous=True)"
    raise invalid_action(action, space, why)


def _generator_at(state: Mapping[str, Any]) -> np.random.Generator:
    """A fresh generator whose bit generator (of the recorded kind) is at ``state``."""
    bit_generator = getattr(np.random, state["bit_generator"])()
    bit_generator.state = state
    return np.random.Generator(bit_generator)


# At most this many recorded calls (resets and steps) per copyable history: a copy replays
# them (measured: ~0.25 ms a BipedalWalker step, so at most ~2.5 s) and each keeps ~0.7 kB.
MAX_REPLAYED_CALLS = 10_000


class ReplayCopies:
    """``pickle`` and ``copy.deepcopy`` for the Box2D envs, by replaying the calls so far.

    A Box2D world (SWIG objects) cannot be pickled, and what decides its next step (contacts,
    warm-start impulses, sleep timers, the broad-phase tree) cannot be written back. What built
    it can be kept: the constructor's arguments and, since the env last had a fresh world, each
    ``reset``'s options and each ``step``'s action, with the state ``np_random`` had when each
    began (so draws that wrappers such as ``StickyAction`` make between steps replay too). A
    copy is constructed from them and replays the calls; Box2D is deterministic, so the copy's
    world is the same bits and it continues the same trajectory. Attributes changed by hand
    after construction are not carried over.

    LunarLander builds a fresh world at every ``reset``, so it keeps only the current episode.
    BipedalWalker and CarRacing keep one world across episodes as Gymnasium does (its freed
    broad-phase ids decide the next episode's contact order), so an exact copy needs every call
    since construction. So that neither memory nor the time a copy takes grows without bound,
    the history is cut at the first ``reset`` after :data:`MAX_REPLAYED_CALLS` calls: the env
    itself keeps its world (its physics stay Gymnasium's, bit for bit), and a later copy
    replays the calls since the cut in a fresh world, which follows the original only
    approximately (contact order may differ); copying such an env warns.

    Subclasses call :meth:`_record_init` in ``__init__``, :meth:`_start_reset` right after
    seeding in ``reset`` (True: build a fresh world now), :meth:`_record_reset` when ``reset``
    ends, :meth:`_start_step` and :meth:`_record_step` around ``step``.
    """

    _FRESH_WORLD_EACH_RESET = False
    _init_kwargs: dict[str, Any]
    _calls: list[tuple[str, Mapping[str, Any], Any]]  # ("reset" | "step", rng state, argument)
    _replaying = False
    _history_cut = False  # the recorded calls no longer start from a fresh world
    _np_random: np.random.Generator | None
    _np_random_seed: int | None
    render_mode: str | None
    spec: Any
    np_random: np.random.Generator

    def _record_init(self, **kwargs: Any) -> None:
        self._init_kwargs = kwargs
        self._calls = []
        self._reset_start: tuple[Mapping[str, Any], int] | None = None
        self._step_start: Mapping[str, Any] | None = None

    def _start_reset(self) -> bool:
        """Note the generator's state as ``reset`` begins; True if the history restarts here
        with a fresh world (which the env must then build)."""
        fresh = self._FRESH_WORLD_EACH_RESET
        if fresh or len(self._calls) >= MAX_REPLAYED_CALLS:
            self._history_cut = not fresh
            self._calls = []
        self._reset_start = (self.np_random.bit_generator.state, len(self._calls))
        return fresh

    def _record_reset(self, options: Any) -> None:
        assert self._reset_start is not None, "_start_reset must run first"
        start, mark = self._reset_start
        del self._calls[mark:]  # the steps reset took itself (its first observation's)
        self._calls.append(("reset", start, deepcopy(options)))
        self._reset_start = None

    def _start_step(self) -> None:
        self._step_start = self.np_random.bit_generator.state

    def _record_step(self, action: Any) -> None:
        assert self._step_start is not None, "_start_step must run first"
        kept: Any
        if isinstance(action, np.ndarray):
            kept = action.copy()
        elif isinstance(action, (int, float, np.generic)):
            kept = action  # immutable (deepcopy of a numpy scalar costs ~3 us a step)
        else:
            kept = deepcopy(action)
        self._calls.append(("step", self._step_start, kept))
        self._step_start = None

    def __getstate__(self) -> dict[str, Any]:
        if self._history_cut:
            warnings.warn(
                f"{type(self).__name__} has run more than {MAX_REPLAYED_CALLS:,} calls in one "
                "world: its copy replays the calls since then in a fresh world and follows "
                "the original only approximately",
                stacklevel=2,
            )
        return {
            "kwargs": self._init_kwargs,
            "calls": self._calls,
            "np_random": self._np_random,
            "np_random_seed": self._np_random_seed,
            "spec": self.spec,
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(**state["kwargs"])  # type: ignore[misc]
        render_mode = self.render_mode
        if render_mode == "human":
            self.render_mode = "rgb_array"  # replay without a window (the same world either way)
        self._replaying = True
        try:
            for kind, start, argument in state["calls"]:
                self._np_random = _generator_at(start)
                if kind == "reset":
                    self.reset(options=argument)  # type: ignore[attr-defined]
                else:
                    self.step(argument)  # type: ignore[attr-defined]
        finally:
            self._replaying = False
            self.render_mode = render_mode
        self._np_random = state["np_random"]
        self._np_random_seed = state["np_random_seed"]
        self.spec = state["spec"]
        self._after_replay()

    def _after_replay(self) -> None:
        """Redo what the replay skipped (CarRacing draws its observation here)."""
