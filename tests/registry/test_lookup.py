"""Id parsing, register, spec, and lookup errors: same types and messages as gymnasium."""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable
from typing import Any

import gymnasium
import gymnasium.envs.registration as gym_registration
import pytest
from tests.registry.toys import PalToy

import palaestra.envs.lookup as lookup
from palaestra import error
from palaestra.envs.registration import (
    find_highest_version,
    get_env_id,
    make,
    parse_env_id,
    register,
    register_envs,
    registry,
    spec,
)
from palaestra.envs.registration import namespace as registration_namespace


def _raised(fn: Callable[[], Any]) -> BaseException:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(Exception) as info:
            fn()
    return info.value


def assert_same_error(
    env_id: str, pal_fn: Callable[[str], Any], gym_fn: Callable[[str], Any]
) -> str:
    """Both libraries raise the same error class with the same message; return the message."""
    pal, gym = _raised(lambda: pal_fn(env_id)), _raised(lambda: gym_fn(env_id))
    assert type(pal).__name__ == type(gym).__name__, (pal, gym)
    assert str(pal) == str(gym)
    return str(pal)


@pytest.mark.parametrize(
    ("env_id", "expected"),
    [
        ("CartPole-v1", (None, "CartPole", 1)),
        ("ALE/Breakout-v5", ("ALE", "Breakout", 5)),
        ("Unversioned", (None, "Unversioned", None)),
        ("my-ns/My.Env-with-dashes-v12", ("my-ns", "My.Env-with-dashes", 12)),
        ("Name-v0-v1", (None, "Name-v0", 1)),
    ],
)
def test_parse_env_id_matches_gymnasium(env_id: str, expected: tuple[Any, ...]) -> None:
    assert parse_env_id(env_id) == expected == gym_registration.parse_env_id(env_id)
    assert get_env_id(*expected) == env_id


@pytest.mark.parametrize("env_id", ["", "ns/", "/Name-v0", "a/b/c-v0", "Name v0", "Name-v0!"])
def test_malformed_ids_raise_gymnasiums_error(env_id: str) -> None:
    message = assert_same_error(env_id, spec, gymnasium.spec)
    assert message.startswith(f"Malformed environment ID: {env_id}.")
    assert_same_error(env_id, make, gymnasium.make)


@pytest.mark.usefixtures("toy_ids")
@pytest.mark.parametrize(
    ("env_id", "error_type", "fragment"),
    [
        ("PalTst/Toy-v0", error.NamespaceNotFound, "Did you mean: `PalTest`?"),
        ("Qqqqqqqq/Toy-v0", error.NamespaceNotFound, "Have you installed the proper package"),
        ("PalTest/Tyo-v0", error.NameNotFound, "Did you mean: `Toy`?"),
        ("PalTest/Unrelated-v0", error.NameNotFound, "doesn't exist in namespace PalTest."),
        ("Zyxwvu-v0", error.NameNotFound, "Did you mean: `Zyxwvut`?"),
        ("PalTest/Toy-v9", error.VersionNotFound, "[ `v0`, `v1`, `v3` ]"),
        ("PalTest/Toy-v2", error.DeprecatedEnv, "Please use `PalTest/Toy-v3` instead."),
        ("PalTest/Plain-v1", error.DeprecatedEnv, "default version `PalTest/Plain`"),
        ("PalTest/Solo-v1", error.DeprecatedEnv, "is deprecated"),
    ],
)
def test_lookup_errors_match_gymnasium(
    env_id: str, error_type: type[Exception], fragment: str
) -> None:
    for pal_fn, gym_fn in ((spec, gymnasium.spec), (make, gymnasium.make)):
        message = assert_same_error(env_id, pal_fn, gym_fn)
        assert fragment in message
    with pytest.raises(error_type):
        spec(env_id)


def test_unversioned_id_resolves_to_the_latest_version(toy_ids: tuple[str, ...]) -> None:
    with pytest.warns(UserWarning, match="Using the latest versioned environment `PalTest/Toy-v3`"):
        env = make("PalTest/Toy")
    assert env.spec is not None and env.spec.id == "PalTest/Toy-v3"
    assert find_highest_version("PalTest", "Toy") == 3
    assert find_highest_version("PalTest", "Plain") is None
    assert find_highest_version("PalTest", "Missing") is None


def test_out_of_date_version_warns(toy_ids: tuple[str, ...]) -> None:
    with pytest.warns(DeprecationWarning, match=r"PalTest/Toy-v0 is out of date.*`v3`"):
        make("PalTest/Toy-v0")


def test_spec_returns_the_registered_spec(toy_ids: tuple[str, ...]) -> None:
    toy = spec("PalTest/Toy-v3")
    assert toy is registry["PalTest/Toy-v3"]
    assert (toy.namespace, toy.name, toy.version, toy.max_episode_steps) == (
        "PalTest",
        "Toy",
        3,
        5,
    )


@pytest.mark.usefixtures("clean_registry")
def test_register_refuses_to_mix_versioned_and_unversioned() -> None:
    register("Mixed-v0", entry_point=PalToy)
    with pytest.raises(error.RegistrationError, match="Can't register the unversioned"):
        register("Mixed", entry_point=PalToy)
    register("Other", entry_point=PalToy)
    with pytest.raises(error.RegistrationError, match="Can't register the versioned"):
        register("Other-v0", entry_point=PalToy)


@pytest.mark.usefixtures("clean_registry")
def test_register_needs_an_entry_point_and_warns_on_override() -> None:
    with pytest.raises(ValueError, match="Either `entry_point` or `vector_entry_point`"):
        register("NoEntry-v0")
    register("Twice-v0", entry_point=PalToy)
    with pytest.warns(UserWarning, match="Overriding environment Twice-v0 already in registry."):
        register("Twice-v0", entry_point=PalToy, kwargs={"size": 3})
    assert registry["Twice-v0"].kwargs == {"size": 3}
    with pytest.raises(error.Error, match="Malformed environment ID"):
        register("bad id", entry_point=PalToy)


@pytest.mark.usefixtures("clean_registry")
def test_module_prefix_imports_the_module_first() -> None:
    assert "Zyxwvut-v0" not in registry
    # tests.registry.conftest imports fine but registers nothing: the lookup then fails by name.
    with pytest.raises(error.NameNotFound):
        make("tests.registry.toys:NotRegistered-v0")
    register("ViaModule-v0", entry_point="tests.registry.toys:PalToy")
    env = make("tests.registry.toys:ViaModule-v0")
    assert env.unwrapped.__class__ is PalToy
    with pytest.raises(
        ModuleNotFoundError, match="Environment registration via importing a module"
    ):
        make("no_such_module_xyz:Env-v0")


def test_missing_optional_package_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(lookup, "_package_installed", lambda module_name: False)
    monkeypatch.setitem(sys.modules, "ale_py", None)  # the ALE ids are registered: the env says
    with pytest.raises(error.DependencyNotInstalled, match=r'pip install "palaestra\[atari\]"'):
        make("ALE/Breakout-v5")
    monkeypatch.setitem(lookup.NAMESPACE_PACKAGES, "Fake", ("fake_pkg", "fake-pkg", "fake"))
    with pytest.raises(error.DependencyNotInstalled, match=r"fake-pkg is not installed"):
        spec("Fake/Thing-v0")


def test_namespace_of_an_installed_package_is_still_not_found(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(lookup, "_package_installed", lambda module_name: True)
    if any(s.namespace == "ALE" for s in registry.values()):
        pytest.skip("ALE environments are registered")
    with pytest.raises(error.NamespaceNotFound, match="Namespace ALE not found"):
        spec("ALE/Breakout-v5")


def test_register_envs_is_a_no_op() -> None:
    before = dict(registry)
    assert register_envs(gymnasium) is None
    assert registry == before


@pytest.mark.usefixtures("clean_registry")
def test_namespace_context_registers_under_the_namespace() -> None:
    with registration_namespace("Plugin"):
        register("Thing-v0", entry_point=PalToy)
        with pytest.warns(UserWarning, match="Custom namespace `Other` is being overridden"):
            register("Other/Stuff-v1", entry_point=PalToy, kwargs={"namespace": "Other"})
    register("Outside-v0", entry_point=PalToy)
    assert {"Plugin/Thing-v0", "Plugin/Stuff-v1", "Outside-v0"} <= set(registry)
    assert lookup.current_namespace is None
