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
from palaestra.utils import seeding

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
    wrong shapes are refused with the action and the space in the message. A float array that
    needs no conversion is returned as is (callers only read it).
    """
    if (
        type(action) is np.ndarray
        and action.ndim == 1
        and action.shape == space.shape
        and (action.dtype == np.float64 or (keep_float_dtype and action.dtype.kind == "f"))
        and _all_finite(action.tolist())
    ):
        return action  # the common case, without the numpy calls below (~2 us a step)
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


def _all_finite(values: list[float]) -> bool:
    for value in values:
        if not math.isfinite(value):
            return False
    return True


def box_action_values(action: Any, space: Any) -> list[float]:
    """``box_action(action, space).tolist()`` for a 1-D space: the values as Python floats.

    A float array of the space's shape with finite values (what ``action_space.sample()`` and
    policies give: float32 values are exact in a float) is read directly, without the checks'
    ~2 us of numpy calls; anything else goes through :func:`box_action`, with its errors.
    """
    if type(action) is np.ndarray and action.shape == space.shape and action.dtype.kind == "f":
        values: list[float] = action.tolist()
        if _all_finite(values):
            return values
    return box_action(action, space).tolist()


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

    Reading the generator's state costs ~2 us, a tenth of a LunarLander step, so a step records
    it only when something besides the env may have drawn from the generator since the last
    call: when code outside the env was handed it (``np_random`` or ``_np_random`` read or
    assigned) since it was created by a seeded ``reset`` or on the env's first use. Otherwise
    the step records ``None`` and the replay simply goes on with the generator the previous
    call left, which is then in the same state. The env's own draws use :meth:`_own_random`,
    which hands the generator out to no one.

    Subclasses call :meth:`_record_init` in ``__init__``, :meth:`_start_reset` right after
    seeding in ``reset`` (True: build a fresh world now), :meth:`_record_reset` when ``reset``
    ends, :meth:`_start_step` and :meth:`_record_step` around ``step``.
    """

    _FRESH_WORLD_EACH_RESET = False
    _init_kwargs: dict[str, Any]
    # ("reset" | "step", the generator's state as the call began or None: as the last call left it,
    # argument)
    _calls: list[tuple[str, Mapping[str, Any] | None, Any]]
    _replaying = False
    _history_cut = False  # the recorded calls no longer start from a fresh world
    _rng: np.random.Generator | None = None  # what ``np_random`` returns
    _rng_private: np.random.Generator | None = None  # ``_rng`` while no one else was handed it
    _np_random_seed: int | None
    render_mode: str | None
    spec: Any
    np_random: np.random.Generator

    @property
    def _np_random(self) -> np.random.Generator | None:
        """The generator (LazyRandom's ``np_random`` reads it here): whoever reads it may draw
        from it between calls, so from now on each step records its state."""
        self._rng_private = None
        return self._rng

    @_np_random.setter
    def _np_random(self, value: np.random.Generator | None) -> None:
        self._rng = value
        self._rng_private = None  # the assigner may keep it (a seeded reset clears this)

    def _own_random(self) -> np.random.Generator:
        """The generator for the env's own draws, created on first use as ``np_random`` would;
        unlike ``np_random`` it leaves the generator private."""
        rng = self._rng
        if rng is None:
            rng, self._np_random_seed = seeding.np_random()
            self._rng = self._rng_private = rng
        return rng

    def _record_init(self, **kwargs: Any) -> None:
        self._init_kwargs = kwargs
        self._calls = []
        self._reset_start: tuple[Mapping[str, Any], int] | None = None
        self._step_start: Mapping[str, Any] | None = None

    def _start_reset(self, seed: int | None) -> bool:
        """Note the generator's state as ``reset`` begins (after ``super().reset(seed=seed)``,
        whose ``seed`` made a generator that no one else holds); True if the history restarts
        here with a fresh world (which the env must then build)."""
        fresh = self._FRESH_WORLD_EACH_RESET
        if fresh or len(self._calls) >= MAX_REPLAYED_CALLS:
            self._history_cut = not fresh
            self._calls = []
        if seed is not None:
            self._rng_private = self._rng
        self._reset_start = (self._own_random().bit_generator.state, len(self._calls))
        return fresh

    def _record_reset(self, options: Any) -> None:
        assert self._reset_start is not None, "_start_reset must run first"
        start, mark = self._reset_start
        del self._calls[mark:]  # the steps reset took itself (its first observation's)
        self._calls.append(("reset", start, deepcopy(options)))
        self._reset_start = None

    def _start_step(self) -> None:
        rng = self._rng
        self._step_start = None if rng is self._rng_private else rng.bit_generator.state  # type: ignore[union-attr]

    def _record_step(self, action: Any) -> None:
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
        rng, private = self._rng, self._rng is self._rng_private
        return {
            "kwargs": self._init_kwargs,
            "calls": self._calls,
            # A private generator goes as a copy (so that even a shallow copy of the env has its
            # own, still private); one held elsewhere goes as itself (deepcopy's memo then maps
            # it to the same copy for the env and the holder).
            "np_random": deepcopy(rng) if private else rng,
            "np_random_private": private,
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
                if start is not None:  # else the replay's generator is where the call began
                    self._np_random = _generator_at(start)
                if kind == "reset":
                    self.reset(options=argument)  # type: ignore[attr-defined]
                else:
                    self.step(argument)  # type: ignore[attr-defined]
        finally:
            self._replaying = False
            self.render_mode = render_mode
        self._np_random = state["np_random"]
        if state.get("np_random_private"):  # only the original held it: only the copy does
            self._rng_private = self._rng
        self._np_random_seed = state["np_random_seed"]
        self.spec = state["spec"]
        self._after_replay()

    def _after_replay(self) -> None:
        """Redo what the replay skipped (CarRacing draws its observation here)."""
