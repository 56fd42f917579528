"""EnvSpec: derived fields, JSON round trip, pprint and pprint_registry output as gymnasium's."""

from __future__ import annotations

import pickle
from copy import deepcopy

import gymnasium
import gymnasium.envs.registration as gym_registration
import pytest

from palaestra.envs.registration import EnvSpec, WrapperSpec, make, pprint_registry, registry


def _full_spec(lib_spec: type, lib_wrapper_spec: type) -> object:
    return lib_spec(
        id="PalTest/Full-v4",
        entry_point="tests.registry.toys:PalToy",
        reward_threshold=9.5,
        nondeterministic=True,
        max_episode_steps=7,
        order_enforce=False,
        disable_env_checker=True,
        kwargs={"size": 3, "nested": {"a": [1, 2]}},
        additional_wrappers=(
            lib_wrapper_spec(
                "TimeLimit", "palaestra.wrappers.common:TimeLimit", {"max_episode_steps": 2}
            ),
            lib_wrapper_spec("Opaque", "somewhere:Opaque", None),
        ),
    )


def test_json_round_trip_keeps_every_field() -> None:
    full = _full_spec(EnvSpec, WrapperSpec)
    assert isinstance(full, EnvSpec)
    restored = EnvSpec.from_json(full.to_json())
    assert restored == full
    assert restored.additional_wrappers[0] == full.additional_wrappers[0]
    assert (restored.namespace, restored.name, restored.version) == ("PalTest", "Full", 4)
    assert deepcopy(full) == full == pickle.loads(pickle.dumps(full))


def test_json_matches_gymnasiums() -> None:
    pal = _full_spec(EnvSpec, WrapperSpec)
    gym = _full_spec(gym_registration.EnvSpec, gym_registration.WrapperSpec)
    assert pal.to_json() == gym.to_json()  # type: ignore[attr-defined]
    # A spec saved by gymnasium loads here.
    assert EnvSpec.from_json(gym.to_json()) == pal  # type: ignore[attr-defined]


def test_to_json_refuses_callables() -> None:
    with pytest.raises(ValueError, match="Callable found in Toy-v0 for entry_point attribute"):
        EnvSpec("Toy-v0", entry_point=lambda: None).to_json()


@pytest.mark.parametrize(
    ("payload", "match"),
    [
        ('{"id": "Toy-v0", "additional_wrappers": [{"name": "x"}]}', "a WrapperSpec"),
        ('{"id": "Toy-v0", "bogus": 1, "additional_wrappers": []}', "an EnvSpec"),
        ('{"id": "bad id", "additional_wrappers": []}', "an EnvSpec"),
    ],
)
def test_from_json_rejects_bad_payloads(payload: str, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        EnvSpec.from_json(payload)


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"include_entry_points": True},
        {"print_all": True},
        {"print_all": True, "include_entry_points": True},
    ],
)
@pytest.mark.parametrize("which", ["full", "minimal"])
def test_pprint_matches_gymnasium(which: str, options: dict[str, bool]) -> None:
    if which == "full":
        pal = _full_spec(EnvSpec, WrapperSpec)
        gym = _full_spec(gym_registration.EnvSpec, gym_registration.WrapperSpec)
    else:
        pal, gym = EnvSpec("Toy-v0", "m:E"), gym_registration.EnvSpec("Toy-v0", "m:E")
    expected = gym.pprint(disable_print=True, **options)  # type: ignore[attr-defined]
    assert pal.pprint(disable_print=True, **options) == expected  # type: ignore[attr-defined]


def test_pprint_prints_when_not_disabled(capsys: pytest.CaptureFixture[str]) -> None:
    assert EnvSpec("Toy-v0", reward_threshold=1.0).pprint() is None
    assert capsys.readouterr().out == "id=Toy-v0\nreward_threshold=1.0\n"


def test_spec_make_uses_make(toy_ids: tuple[str, ...]) -> None:
    env = registry["PalTest/Toy-v3"].make(size=4)
    assert env.observation_space.shape == (4,)
    assert str(env) == str(make("PalTest/Toy-v3", size=4))


def test_spec_make_without_an_installed_maker_says_what_to_do(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The registry installs make() when it is imported; the spec module never imports it.
    import palaestra.env_spec

    assert palaestra.env_spec._maker is make
    monkeypatch.setattr(palaestra.env_spec, "_maker", None)
    with pytest.raises(
        palaestra.error.Error, match=r"EnvSpec.make\('Toy-v0'\) needs palaestra's registry"
    ):
        EnvSpec("Toy-v0").make()


def _registry_of(lib_spec: type) -> dict[str, object]:
    ids_and_entries = [
        ("CartPole-v1", "palaestra.envs.classic_control.cartpole:CartPoleEnv"),
        ("CartPole-v0", "palaestra.envs.classic_control.cartpole:CartPoleEnv"),
        ("MountainCarContinuous-v0", "palaestra.envs.classic_control.cont:Env"),
        ("Acrobot-v1", "palaestra.envs.classic_control.acrobot:AcrobotEnv"),
        ("ALE/Pong-v5", "ale_py.env:AtariEnv"),
        ("ALE/Breakout-v5", "ale_py.env:AtariEnv"),
        ("shim-v0", "shimmy.atari_env:X"),
        ("Flat-v0", "flat:X"),
        ("Lonely-v0", "lonely"),
    ]
    return {env_id: lib_spec(env_id, entry) for env_id, entry in ids_and_entries}


@pytest.mark.parametrize("num_cols", [1, 2, 3, 5])
@pytest.mark.parametrize("exclude", [None, ["ALE"], ["classic_control", "atari_env"]])
def test_pprint_registry_matches_gymnasium(num_cols: int, exclude: list[str] | None) -> None:
    pal = pprint_registry(
        _registry_of(EnvSpec), num_cols=num_cols, exclude_namespaces=exclude, disable_print=True
    )
    gym = gymnasium.pprint_registry(
        _registry_of(gym_registration.EnvSpec),
        num_cols=num_cols,
        exclude_namespaces=exclude,
        disable_print=True,
    )
    assert pal == gym
    assert (pal is not None and "===== classic_control =====" in pal) or exclude


def test_pprint_registry_prints(capsys: pytest.CaptureFixture[str]) -> None:
    assert pprint_registry({"A-v0": EnvSpec("A-v0", "x.y:Z")}) is None
    assert capsys.readouterr().out == "===== y =====\nA-v0\n"


def test_pprint_registry_groups_callables_under_none_as_gymnasium() -> None:
    """Gymnasium's own test_pprint_namespace registry, on both (issue 26)."""

    def named(lib: str, lib_spec: type) -> dict[str, object]:
        cc = f"{lib}.envs.classic_control"
        return {
            "CartPole-v0": lib_spec("CartPole-v0", cc + ".cartpole:CartPoleEnv"),
            "CartPole-v1": lib_spec("CartPole-v1", cc + ":CartPoleEnv"),
            "CartPole-v2": lib_spec("CartPole-v2", f"{lib}.cartpole:CartPoleEnv"),
            "CartPole-v3": lib_spec("CartPole-v3", lambda: None),
            "ExampleNamespace/CartPole-v2": lib_spec(
                "ExampleNamespace/CartPole-v2", cc + ":CartPoleEnv"
            ),
        }

    pal = pprint_registry(named("palaestra", EnvSpec), disable_print=True)
    gym = gymnasium.pprint_registry(
        named("gymnasium", gym_registration.EnvSpec), disable_print=True
    )
    assert pal == gym
    assert pal is not None and "===== None =====\nCartPole-v3" in pal
    none_excluded = pprint_registry(
        named("palaestra", EnvSpec),
        exclude_namespaces=[None],  # type: ignore[list-item]
        disable_print=True,
    )
    assert none_excluded is not None and "CartPole-v3" not in none_excluded
