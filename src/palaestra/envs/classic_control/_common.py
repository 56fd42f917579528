"""What every classic-control env shares: reset-bound parsing and rendering (the action checks
are :mod:`palaestra.envs.action_checks`, shared with the other env families)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.rendered import RenderedEnv

RENDER_MODES = ["human", "rgb_array"]


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


class ClassicControlEnv(RenderedEnv[np.ndarray, Any]):
    """The single classic-control (and Box2D) envs' base, rendering as every
    :class:`~palaestra.envs.rendered.RenderedEnv` does.

    Subclasses implement ``_frame()`` (the scene from ``palaestra.rendering.scenes``).
    """


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
