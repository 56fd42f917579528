"""ALE joystick actions by name: continuous-action mapping and the keyboard map for ``play``.

ALE's 18 action names are ``[UP|DOWN][LEFT|RIGHT][FIRE]`` (``NOOP`` when all are empty), so a
direction and a fire flag spell the action's name; no 18-branch table is needed.
"""

from __future__ import annotations

from typing import Any

# ale-py's keyboard layout: w/a/s/d move, space fires, e is the explicit no-op.
_KEYS = {"UP": "w", "DOWN": "s", "LEFT": "a", "RIGHT": "d", "FIRE": " "}


def action_name(horizontal: int, vertical: int, fire: bool) -> str:
    """The ALE action name for a direction in {-1, 0, 1}² and a fire flag.

    >>> action_name(1, -1, True), action_name(0, 0, False), action_name(-1, 0, False)
    ('DOWNRIGHTFIRE', 'NOOP', 'LEFT')
    """
    name = ("DOWN", "", "UP")[vertical + 1] + ("LEFT", "", "RIGHT")[horizontal + 1]
    name += "FIRE" if fire else ""
    return name or "NOOP"


def direction_table(action_enum: Any) -> dict[tuple[int, int, bool], Any]:
    """``(horizontal, vertical, fire) -> ale_py.Action`` for all 18 combinations."""
    members = action_enum.__members__
    return {
        (h, v, f): members[action_name(h, v, f)]
        for h in (-1, 0, 1)
        for v in (-1, 0, 1)
        for f in (False, True)
    }


def keys_for(name: str) -> tuple[str, ...]:
    """The keys that press action ``name``, in ale-py's order (vertical, horizontal, fire).

    >>> keys_for("UPLEFTFIRE"), keys_for("NOOP")
    (('w', 'a', ' '), ('e',))
    """
    if name == "NOOP":
        return ("e",)
    keys = []
    for part in ("UP", "DOWN", "LEFT", "RIGHT", "FIRE"):
        if part in name:
            keys.append(_KEYS[part])
    return tuple(keys)
