"""An algorithm's constructor arguments, captured once and taken by name.

An algorithm's ``__init__`` is SB3's public signature followed by ``self._configure(locals())``
(``BaseAlgorithm._configure``): the signature is the one place a hyperparameter is written.
Each layer of the class (the algorithm, the off-policy or on-policy loop, the base) then takes
the arguments it uses from one ``Settings`` by name, so no argument is passed on by position,
a name a layer needs and the constructor lacks is a ``TypeError`` naming it, and so is an
argument no layer took (a new hyperparameter nobody reads, or a stray local variable).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["Settings"]


class Settings:
    """The arguments of one constructor call; each layer takes its own."""

    def __init__(self, owner: str, arguments: Mapping[str, Any]) -> None:
        """``owner`` names the class in errors; ``arguments`` is the constructor's
        ``locals()`` (``self`` and ``__class__`` are left out)."""
        self._owner = owner
        self._values = {k: v for k, v in arguments.items() if k not in ("self", "__class__")}
        self._taken: set[str] = set()

    def __getitem__(self, name: str) -> Any:
        """The argument ``name``; a ``TypeError`` naming it if the constructor has none."""
        if name not in self._values:
            raise TypeError(
                f"{self._owner}() has no argument {name!r}, which one of its base classes "
                "takes: its constructor must accept it (or pass a value on to super().__init__)"
            )
        self._taken.add(name)
        return self._values[name]

    def unused(self, *names: str) -> None:
        """Mark SB3 arguments that are accepted and change nothing (so they are not
        reported as untaken)."""
        for name in names:
            self[name]

    def check_all_taken(self) -> None:
        """A ``TypeError`` naming the arguments no layer took."""
        left = sorted(set(self._values) - self._taken)
        if left:
            raise TypeError(
                f"{self._owner}() got arguments that no part of it takes: "
                f"{', '.join(map(repr, left))}"
            )
