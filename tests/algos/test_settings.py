"""Constructor arguments taken by name (``palaestra.algos.common.settings``): an algorithm's
``__init__`` is its SB3 signature and ``self._configure(locals())``; each class takes its own
arguments from that one mapping, so a name a base class needs and the constructor lacks, or
an argument no class takes, is a ``TypeError`` naming it."""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any

import pytest

from palaestra.algos import A2C, DDPG, DQN, PPO, SAC, TD3
from palaestra.algos.common import hyperparams as hp
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


# -- what a model file keeps: the constructor's arguments, by their current values ------------
class _WiderDQN(DQN):
    """A user's variant: another default and one hyperparameter of its own."""

    def __init__(
        self, policy: Any, env: Any, batch_size: int = 64, margin: float = 0.5, **kwargs: Any
    ) -> None:
        self.margin = margin
        super().__init__(policy, env, batch_size=batch_size, **kwargs)


class _FewerArgumentsDQN(DQN):
    """sb3-contrib's way (QRDQN): its own signature with other defaults, passed on whole."""

    def __init__(
        self,
        policy: Any,
        env: Any,
        learning_rate: float = 5e-4,
        buffer_size: int = 500,
        exploration_fraction: float = 0.5,
        policy_kwargs: dict[str, Any] | None = None,
        device: str = "auto",
        _init_setup_model: bool = True,
    ) -> None:
        super().__init__(**{k: v for k, v in locals().items() if k not in ("self", "__class__")})


@pytest.fixture
def rules(monkeypatch: pytest.MonkeyPatch) -> None:
    """Hyperparameter rules for the subclasses above (a new algorithm declares its own)."""
    extra = {"margin": hp._number(0.0, 1.0)}
    for name in ("_WiderDQN", "_FewerArgumentsDQN"):
        monkeypatch.setitem(hp.HYPERPARAMETERS, name, hp.HYPERPARAMETERS["DQN"] | extra)
        monkeypatch.setitem(hp.SCHEDULES, name, hp.SCHEDULES["DQN"])
        monkeypatch.setitem(hp.POLICY_KWARGS, name, hp.POLICY_KWARGS["DQN"])


def test_a_subclass_saves_its_defaults_and_its_own_hyperparameter(
    rules: None, tmp_path: Path
) -> None:
    model = _WiderDQN("MlpPolicy", "CartPole-v1", buffer_size=100, margin=0.25)
    plain = DQN("MlpPolicy", "CartPole-v1", buffer_size=100, batch_size=64)
    assert model._hyperparameters() == plain._hyperparameters() | {"margin": 0.25}
    model.margin, model.gamma = 0.75, 0.5  # changed on the model before save: saved as changed
    model.save(tmp_path / "wider.zip")
    loaded = _WiderDQN.load(tmp_path / "wider.zip")
    assert (loaded.margin, loaded.gamma, loaded.batch_size) == (0.75, 0.5, 64)


def test_a_subclass_taking_fewer_arguments_saves_only_those(rules: None, tmp_path: Path) -> None:
    """What its constructor cannot take, a file cannot hand it back: the rest are the
    defaults its constructor passes on."""
    model = _FewerArgumentsDQN("MlpPolicy", "CartPole-v1", buffer_size=200)
    assert model._hyperparameters() == {"buffer_size": 200, "exploration_fraction": 0.5}
    assert model._schedules()["learning_rate"](1.0) == 5e-4
    model.save(tmp_path / "fewer.zip")
    loaded = _FewerArgumentsDQN.load(tmp_path / "fewer.zip")
    assert (loaded.buffer_size, loaded.exploration_fraction, loaded.batch_size) == (200, 0.5, 32)
    assert loaded.lr_schedule(1.0) == 5e-4


@pytest.mark.parametrize("cls", [DQN, PPO, A2C, SAC, TD3, DDPG], ids=lambda c: c.__name__)
def test_the_saved_hyperparameters_are_the_signature_less_what_is_not_kept(cls: Any) -> None:
    """Every argument of the public signature is saved unless named in ``_not_saved`` or
    saved as a schedule; DDPG's three fixed TD3 settings are not arguments, so not saved."""
    env = "Pendulum-v1" if issubclass(cls, (SAC, TD3)) else "CartPole-v1"
    model = cls("MlpPolicy", env, **({"n_steps": 64} if cls is PPO else {}))
    expected = [
        name
        for name in inspect.signature(cls).parameters
        if name not in cls._not_saved and name not in model._schedules()
    ]
    assert list(model._hyperparameters()) == expected
    assert {"policy", "env", "device", "tensorboard_log"}.isdisjoint(model._hyperparameters())
    if cls is DDPG:
        assert {"policy_delay", "target_policy_noise", "target_noise_clip"}.isdisjoint(expected)
