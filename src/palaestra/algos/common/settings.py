"""An algorithm's constructor arguments, captured once and taken by name.

An algorithm's ``__init__`` is SB3's public signature followed by ``self._configure(locals())``
(``BaseAlgorithm._configure``): the signature is the one place a hyperparameter is written.
Each layer of the class (the algorithm, the off-policy or on-policy loop, the base) then takes
the arguments it uses from one ``Settings`` by name, so no argument is passed on by position,
a name a layer needs and the constructor lacks is a ``TypeError`` naming it, and so is an
argument no layer took (a new hyperparameter nobody reads, or a stray local variable). A new
algorithm (or a subclass adding an argument) reads::

    def __init__(self, policy, env, learning_rate=1e-4, ..., my_arg=0.5, ...,
                 _init_setup_model=True):
        self._configure(locals())

    def _take_settings(self, settings):
        if not settings["my_arg"] > 0:  # its own checks first
            raise ValueError(...)
        self.my_arg = settings["my_arg"]
        super()._take_settings(settings)  # the layers below take theirs
        ...  # what needs the env (self.env, self.n_envs)

A subclass that only changes defaults passes its arguments on whole:
``super().__init__(**{k: v for k, v in locals().items() if k not in ("self", "__class__")})``.
A model file keeps the same arguments: ``BaseAlgorithm._hyperparameters`` reads the
constructor's signature (less ``_not_saved`` and the schedules) and the attributes of those
names, so ``self.my_arg`` is saved and handed back on ``load`` (once the package's
``hyperparams.py`` declares its rule: what a file may hand the constructor).
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
