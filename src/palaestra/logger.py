"""Warnings and errors shown to users, with Gymnasium's levels and colours."""

from __future__ import annotations

import warnings

from palaestra.utils.colorize import colorize

DEBUG = 10
INFO = 20
WARN = 30
ERROR = 40
DISABLED = 50

min_level = WARN


def set_level(level: int) -> None:
    """Show only messages at ``level`` or above (``DISABLED`` silences everything)."""
    global min_level
    min_level = level


def warn(
    msg: str, *args: object, category: type[Warning] | None = None, stacklevel: int = 1
) -> None:
    """Emit a yellow ``WARN:`` warning if the level allows it."""
    if min_level <= WARN:
        warnings.warn(
            colorize(f"WARN: {msg % args}", "yellow"), category=category, stacklevel=stacklevel + 1
        )


def deprecation(msg: str, *args: object) -> None:
    """Emit a deprecation warning."""
    warn(msg, *args, category=DeprecationWarning, stacklevel=2)


def error(msg: str, *args: object) -> None:
    """Emit a red ``ERROR:`` warning if the level allows it."""
    if min_level <= ERROR:
        warnings.warn(colorize(f"ERROR: {msg % args}", "red"), stacklevel=3)
