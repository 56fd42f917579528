"""Action checks shared by the env families (classic control, toy text, Atari, Box2D).

Each has a fast path for what ``space.sample()`` gives and raises ``InvalidAction`` naming the
action and the space for anything rejected; the ``*_batch`` forms check N actions at once.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from palaestra import error
from palaestra.spaces import Box, Discrete

__all__ = [
    "check_box_action",
    "check_box_batch",
    "check_discrete_action",
    "check_discrete_batch",
    "invalid_action",
]

_INT64 = np.dtype(np.int64)
_FLOAT32 = np.dtype(np.float32)
_REAL_KINDS = "biuf"  # bool, ints, floats: what a float Box action may be made of (no complex, str)


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
