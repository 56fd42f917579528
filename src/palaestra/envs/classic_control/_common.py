"""What every classic-control env shares: reset-bound parsing, action checks, rendering."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from palaestra import error, logger
from palaestra.core import Env
from palaestra.spaces import Box, Discrete

RENDER_MODES = ["human", "rgb_array"]
_INT64 = np.dtype(np.int64)
_FLOAT32 = np.dtype(np.float32)
_REAL_KINDS = "biuf"  # bool, ints, floats: what a float Box action may be made of (no complex, str)


def state_array(values: Any, dtype: Any = np.float64) -> np.ndarray:
    """The single env's state as a fresh, read-only array (``env.unwrapped.state``).

    The state lives in Python floats (the fast path), so this array is a copy: writing into it
    would silently change nothing. Read-only makes ``state[0] = x`` fail loudly instead;
    assign a whole new state (``env.unwrapped.state = [...]``) to change it.
    """
    arr = np.array(values, dtype=dtype)
    arr.flags.writeable = False
    return arr


def parse_number(name: str, value: Any) -> float:
    """A finite float from a reset option, or ``ValueError`` naming the option and value."""
    try:
        number = float(value)
    except (TypeError, ValueError) as e:  # Gymnasium's message, plus the option's name
        raise ValueError(f"An option ({name}={value!r}) could not be converted to a float.") from e
    if not math.isfinite(number):
        # Gymnasium lets NaN through to a NaN state and inf to numpy's OverflowError.
        raise ValueError(f"Reset option {name}={value!r} must be finite.")
    return number


def checked_options(options: Any, keys: Sequence[str]) -> Mapping[str, Any]:
    """``options`` as a mapping (``{}`` for None), or ``InvalidOptions`` naming it and ``keys``.

    Gymnasium looks keys up with ``in``, so a string passes silently ("low" in "x"), a list
    passes and an int raises ``TypeError``: anything but a mapping is refused here, as a
    ``TypeError`` (``InvalidOptions`` is one).
    """
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        wanted = ", ".join(repr(k) for k in keys)
        raise error.InvalidOptions(
            f"Reset options must be None or a dict (keys {wanted}), got {options!r:.200}"
        )
    return options


def parse_reset_bounds(
    options: dict[str, Any] | None, default_low: float, default_high: float
) -> tuple[float, float]:
    """``options["low"]``/``["high"]`` or the defaults, checked (Gymnasium's reset options)."""
    given = checked_options(options, ("low", "high"))
    low = parse_number("low", given["low"]) if "low" in given else default_low
    high = parse_number("high", given["high"]) if "high" in given else default_high
    if low > high:
        raise ValueError(f"Lower bound ({low}) must be lower than higher bound ({high}).")
    if not math.isfinite(high - low):
        # numpy's uniform (Gymnasium) raises OverflowError here; the draw would be inf.
        raise ValueError(
            f"Reset options low={low!r} and high={high!r} span more than a float can hold "
            "(high - low overflows)."
        )
    return low, high


def invalid_action(action: Any, space: Any, why: str = "") -> error.InvalidAction:
    """The exception for an action outside ``space``, naming both."""
    detail = f": {why}" if why else ""
    return error.InvalidAction(
        f"Invalid action {action!r} ({type(action).__name__}) for action space {space}{detail}"
    )


def check_discrete_action(action: Any, space: Any, n: int) -> int:
    """The slow path of a discrete step: an accepted action as an ``int`` in ``[0, n)``.

    ``np.int64`` (what ``Discrete.sample()`` returns) is checked first and cheaply; anything
    else goes through ``space.contains`` (ints, bools, 0-d integer numpy values that cast
    safely), as in Gymnasium. Anything rejected raises InvalidAction naming action and space.
    """
    if type(action) is np.int64:
        value = int(action)
        if 0 <= value < n:
            return value
    elif space.contains(action):
        return int(action)
    raise invalid_action(action, space)


def check_box_action(action: Any, space: Any) -> float:
    """The one component of a ``(1,)`` float action as a float32 value, else InvalidAction.

    Finite values outside the bounds are accepted: Gymnasium clips them inside the dynamics,
    and so do we. The value is rounded to float32, the space's dtype (Gymnasium would compute
    with a float64 action's full precision).
    """
    if type(action) is np.ndarray and action.dtype is _FLOAT32:  # what sample() gives: no cast
        arr = action
    else:
        try:
            raw = np.asarray(action)
        except (TypeError, ValueError) as e:
            raise invalid_action(action, space, "not a numeric array") from e
        if raw.dtype.kind not in _REAL_KINDS:
            # A float32 cast would parse strings and drop imaginary parts without a word.
            why = f"expected real numeric values, got dtype {raw.dtype}"
            raise invalid_action(action, space, why)
        arr = raw.astype(np.float32, copy=False)
    if arr.shape != space.shape:
        raise invalid_action(action, space, f"expected shape {space.shape}, got {arr.shape}")
    value = float(arr[0])
    if not math.isfinite(value):
        raise invalid_action(action, space, "actions must be finite (no NaN or inf)")
    return value


def check_discrete_batch(actions: Any, space: Discrete, num_envs: int) -> np.ndarray:
    """Validate N discrete actions at once: an int64 array ``[N]`` or InvalidAction."""
    if (
        type(actions) is np.ndarray
        and actions.dtype is _INT64
        and actions.shape == (num_envs,)
        and space.start == 0
        # The usual case (what Generator.integers returns): seen as unsigned, negative values
        # are huge, so one comparison finds both bounds (count_nonzero: cheaper than a reduce).
        and not np.count_nonzero(actions.view(np.uint64) >= int(space.n))
    ):
        return actions
    arr = np.asarray(actions)
    if arr.shape != (num_envs,) or arr.dtype.kind not in "iu":
        raise error.InvalidAction(
            f"Invalid actions {actions!r}: expected {num_envs} integers of {space}, "
            f"got shape {arr.shape} dtype {arr.dtype}"
        )
    lo, hi = int(space.start), int(space.start) + int(space.n)
    if lo == 0 and num_envs:
        # One reduction for both bounds: seen as unsigned, negative values are huge.
        out_of_range = bool(np.maximum.reduce(arr.view(arr.dtype.str.replace("i", "u"))) >= hi)
    else:
        out_of_range = num_envs > 0 and bool(arr.min() < lo or arr.max() >= hi)
    if out_of_range:
        bad = np.flatnonzero((arr < lo) | (arr >= hi))
        raise error.InvalidAction(
            f"Invalid actions at rows {bad[:10].tolist()}: {arr[bad[:10]].tolist()} "
            f"not in action space {space}"
        )
    return arr.astype(np.int64, copy=False)


def check_box_batch(actions: Any, space: Box, num_envs: int) -> np.ndarray:
    """Validate N ``(1,)`` float actions: float32 values as float64 ``[N]``, else InvalidAction."""
    if type(actions) is np.ndarray and actions.dtype is _FLOAT32:  # the usual case: no cast
        arr = actions
    else:
        try:
            raw = np.asarray(actions)
        except (TypeError, ValueError) as e:
            raise error.InvalidAction(f"Invalid actions {actions!r}: not numeric") from e
        if raw.dtype.kind not in _REAL_KINDS:
            # A float32 cast would parse strings and drop imaginary parts without a word.
            raise error.InvalidAction(
                f"Invalid actions {actions!r}: not numeric, expected real values for action "
                f"space {space}, got dtype {raw.dtype}"
            )
        arr = raw.astype(np.float32, copy=False)
    if arr.shape != (num_envs, *space.shape):
        raise error.InvalidAction(
            f"Invalid actions: expected shape {(num_envs, *space.shape)} for {num_envs} envs "
            f"of {space}, got {arr.shape}"
        )
    flat = arr[:, 0].astype(np.float64)  # [N]
    finite = np.isfinite(flat)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        raise error.InvalidAction(
            f"Invalid actions at rows {bad[:10].tolist()}: {flat[bad[:10]].tolist()} "
            f"are not finite (NaN/inf) for action space {space}"
        )
    return flat


class ClassicControlEnv(Env[np.ndarray, Any]):
    """Rendering and render-mode handling shared by the single classic-control envs.

    Subclasses implement ``_frame()`` (the scene from ``palaestra.rendering.scenes``).
    """

    _window: Any = None

    def _init_render(self, render_mode: str | None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise error.UnsupportedMode(
                f"render_mode={render_mode!r} is not one of {self.metadata['render_modes']}"
            )
        self.render_mode = render_mode

    def _frame(self) -> np.ndarray:
        raise NotImplementedError

    def render(self) -> np.ndarray | None:
        """The current frame (``"rgb_array"``) or show it in a window (``"human"``)."""
        if self.render_mode is None:
            name = self.spec.id if self.spec is not None else type(self).__name__
            logger.warn(
                "You are calling render method without specifying any render mode. "
                "You can specify the render_mode at initialization, "
                f'e.g. gym.make("{name}", render_mode="rgb_array")'
            )
            return None
        frame = self._frame()
        if self.render_mode == "rgb_array":
            return frame
        if self._window is None:  # created lazily: rgb_array users never need a display
            from palaestra.rendering.window import HumanWindow

            title = self.spec.id if self.spec is not None else type(self).__name__
            self._window = HumanWindow(title, self.metadata["render_fps"])
        self._window.show(frame)
        return None

    def close(self) -> None:
        """Close the human-mode window if one was opened."""
        if self._window is not None:
            self._window.close()
            self._window = None


def expose_params(cls: type, names: Sequence[str]) -> None:
    """Give ``cls`` Gymnasium's attribute names for its params (``env.unwrapped.dt = 0.05``).

    Reading returns the field of ``self.params``; assigning replaces ``self.params`` with a
    copy holding the new value, so the physics sees it on the next step.
    """

    def make(name: str) -> property:
        def get(self: Any) -> Any:
            return getattr(self.params, name)

        def set_(self: Any, value: Any) -> None:
            self.params = dataclasses.replace(self.params, **{name: value})

        return property(get, set_, doc=f"``params.{name}`` (settable).")

    for name in names:
        setattr(cls, name, make(name))
