"""ANSI colouring for terminal messages."""

from __future__ import annotations

_COLORS = {
    "gray": 30, "red": 31, "green": 32, "yellow": 33,
    "blue": 34, "magenta": 35, "cyan": 36, "white": 37, "crimson": 38,
}  # fmt: skip


def colorize(string: str, color: str, bold: bool = False, highlight: bool = False) -> str:
    """Wrap ``string`` in the ANSI codes for ``color``.

    >>> colorize("hi", "red")
    '\\x1b[31mhi\\x1b[0m'
    """
    code = _COLORS[color] + (10 if highlight else 0)
    attrs = f"{code};1" if bold else str(code)
    return f"\x1b[{attrs}m{string}\x1b[0m"
