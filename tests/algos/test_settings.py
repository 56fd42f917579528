"""Constructor arguments taken by name (``palaestra.algos.common.settings``): an algorithm's
``__init__`` is its SB3 signature and ``self._configure(locals())``; each class takes its own
arguments from that one mapping, so a name a base class needs and the constructor lacks, or
an argument no class takes, is a ``TypeError`` naming it."""

from __future__ import annotations

import inspect
from typing import Any

import pytest

from palaestra.algos import A2C, DQN, PPO, SAC, TD3
from palaestra.algos.common.settings import Settings

# DDPG is TD3 with three arguments fixed in its constructor: TD3's layers cover it.
LAYERED = [DQN, PPO, A2C, SAC, TD3]


def _arguments(cls: type) -> dict[str, Any]:
    """What ``cls("MlpPolicy", None, _init_setup_model=False)`` hands ``_configure``."""
    bound = inspect.signature(cls).bind("MlpPolicy", None, _init_setup_model=False)
    bound.apply_defaults()
    return dict(bound.arguments)


def test_settings_hands_out_arguments_by_name_and_reports_the_rest() -> None:
    settings = Settings("Algo", {"self": object(), "__class__": type, "a": 1, "b": 2, "c": 3})
    assert settings["a"] == 1
    assert settings["b"] == 2 and settings["a"] == 1  # a name may be read by several layers
    with pytest.raises(TypeError, match=r"^Algo\(\) has no argument 'd', which one of its"):
        settings["d"]
    with pytest.raises(TypeError, match=r"^Algo\(\) got arguments that no part of it takes: 'c'$"):
        settings.check_all_taken()
    settings.unused("c")
    settings.check_all_taken()  # self and __class__ are never arguments


@pytest.mark.parametrize(
    ("cls", "name"),
    [(cls, name) for cls in LAYERED for name in _arguments(cls)],
    ids=lambda v: v.__name__ if isinstance(v, type) else v,
)
def test_every_argument_is_taken_by_name(cls: Any, name: str) -> None:
    """Leaving out any one of the signature's arguments is a TypeError naming it: every
    argument is read by some class, by its name (none is passed on by position)."""
    arguments = _arguments(cls)
    del arguments[name]
    with pytest.raises(TypeError, match=rf"^{cls.__name__}\(\) has no argument '{name}'"):
        cls.__new__(cls)._configure(arguments)


@pytest.mark.parametrize("cls", LAYERED, ids=lambda c: c.__name__)
def test_an_argument_no_class_takes_is_a_type_error(cls: Any) -> None:
    """A stray name (a local variable computed before ``_configure(locals())``, or a new
    hyperparameter no class reads) is refused, not ignored."""
    model = cls.__new__(cls)
    with pytest.raises(TypeError, match=r"no part of it takes: 'stray'$"):
        model._configure(_arguments(cls) | {"stray": 1})
    model._configure(_arguments(cls))  # and without it, the same call works
    assert model.env is None and model.verbose == 0
