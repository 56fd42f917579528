"""Argument checks for ``AtariEnv``: each bad value gets an error naming it and the choices.

The messages keep ale-py's wording where it has one (``Invalid observation type``) and the
exception type it raises (``error.Error``, Gymnasium's base error), so code catching one
catches the other.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from palaestra import error

OBS_TYPES = ("rgb", "grayscale", "ram")
RENDER_MODES = ["human", "rgb_array"]


def import_ale_py() -> Any:
    """The ``ale_py`` module, or ``DependencyNotInstalled`` naming the extra to install."""
    try:
        import ale_py
    except ImportError as e:
        raise error.dependency_not_installed("ale-py", "atari", "the Atari environments") from e
    return ale_py


def _is_int(value: Any) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def check_frameskip(frameskip: Any) -> int | tuple[int, int]:
    """An ``int >= 1`` or a ``(low, high)`` pair with ``1 <= low < high``, else ``error.Error``.

    A pair draws ``np_random.integers(low, high)`` frames per step (``high`` excluded).
    """
    if _is_int(frameskip) and frameskip >= 1:
        return int(frameskip)
    if isinstance(frameskip, (tuple, list)) and len(frameskip) == 2:
        low, high = frameskip
        if _is_int(low) and _is_int(high) and 1 <= low < high:
            return int(low), int(high)
    raise error.Error(
        f"Invalid frameskip {frameskip!r}: expected a positive int (frames repeated per step) "
        "or a (low, high) tuple of ints with 1 <= low < high (a random count in [low, high) "
        "per step)"
    )


def check_options(obs_type: Any, render_mode: Any, repeat_action_probability: Any) -> None:
    """Raise for an unknown ``obs_type`` / ``render_mode`` or a probability outside [0, 1]."""
    if obs_type not in OBS_TYPES:
        raise error.Error(
            f"Invalid observation type: {obs_type!r}. Expecting: rgb, grayscale, ram."
        )
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise error.UnsupportedMode(
            f"render_mode={render_mode!r} is not one of {RENDER_MODES} (or None)"
        )
    p = repeat_action_probability
    if isinstance(p, bool) or not (isinstance(p, (int, float, np.number)) and 0.0 <= p <= 1.0):
        raise error.Error(
            f"Invalid repeat_action_probability {p!r}: expected a probability in [0, 1] "
            "(0.25 in v5, 0 for no sticky actions)"
        )


def check_choice(what: str, value: int | None, available: Sequence[int], game: str) -> None:
    """Raise unless ``value`` (a mode or difficulty) is None or one the game offers."""
    if value is not None and value not in available:
        raise error.Error(f"Invalid {what} {value!r} for {game}: expected one of {list(available)}")
