"""What the Box2D envs share: the lazy ``Box2D`` import, action checks and kwarg checks."""

from __future__ import annotations

import math
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
