"""check_env: passes a good toy, and fails broken toys with gymnasium's errors and warnings."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator
from typing import Any

import gymnasium
import gymnasium.utils.env_checker as gym_env_checker
import numpy as np
import pytest
from tests.registry.toys import PalToy, toy_class

import palaestra
from palaestra.envs.registration import make, register, registry
from palaestra.utils.env_checker import check_env, data_equivalence

Outcome = tuple[list[str], str | None]


def outcome(fn: Callable[[], Any]) -> Outcome:
    """(warning messages, ``"Type: message"`` of the exception or None), library names unified."""
    raised = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            fn()
        except Exception as e:
            # First line only: pytest's assertion rewriting (when a checker module is given
            # on the command line) appends an introspection of the failed assert.
            raised = f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
    unify = lambda text: text.replace("gymnasium", "palaestra")  # noqa: E731
    return [unify(str(w.message)) for w in caught], None if raised is None else unify(raised)


def broken(lib: Any, with_spec: bool, **attrs: Any) -> Any:
    env = type("Broken", (toy_class(lib),), attrs)()
    if with_spec:  # the determinism checks only run on envs with a (deterministic) spec
        env.spec = lib.envs.registration.EnvSpec("Broken-v0", entry_point="nowhere:Broken")
    return env


def both(with_spec: bool = True, **attrs: Any) -> tuple[Outcome, Outcome]:
    """check_env's outcome on the same broken toy, for palaestra and gymnasium."""
    skip = {"skip_render_check": with_spec, "skip_close_check": with_spec}  # spec cannot make
    ours = outcome(lambda: check_env(broken(palaestra, with_spec, **attrs), **skip))
    theirs = outcome(
        lambda: gym_env_checker.check_env(broken(gymnasium, with_spec, **attrs), **skip)
    )
    return ours, theirs


NO_SPEC = "Not able to test alternative render modes due to the environment not having a spec"


@pytest.fixture
def toy_id() -> Iterator[str]:
    register("CheckToy-v0", entry_point="tests.registry.toys:PalToy")
    yield "CheckToy-v0"
    registry.pop("CheckToy-v0")


def test_good_env_passes_silently(toy_id: str) -> None:
    env = make(toy_id).unwrapped
    assert outcome(lambda: check_env(env)) == ([], None)
    assert env.closed == 0  # render and close checks use fresh envs


def test_good_env_without_spec_only_misses_the_render_modes() -> None:
    ours, theirs = both(with_spec=False)
    assert ours == theirs
    assert ours[1] is None and len(ours[0]) == 1 and NO_SPEC in ours[0][0]


def test_wrapped_env_and_warn_argument_are_reported(toy_id: str) -> None:
    messages, raised = outcome(lambda: check_env(make(toy_id), warn=True))
    assert raised is None
    assert any("`check_env(warn=...)` parameter is now ignored" in m for m in messages)
    assert any("is different from the unwrapped version" in m for m in messages)


def _float64_obs(self: Any, *, seed: Any = None, options: Any = None) -> Any:
    super(type(self), self).reset(seed=seed)
    return self.np_random.uniform(-0.5, 0.5, 2), {}


def _reused_buffer_step(self: Any, action: Any) -> Any:
    self._state += 0.01
    return self._state, 1.0, False, False, {}


def _unseeded_reset(self: Any, *, seed: Any = None, options: Any = None) -> Any:
    super(type(self), self).reset(seed=seed)
    return np.random.default_rng().uniform(-0.5, 0.5, 2).astype(np.float32), {}


def _no_super_reset(self: Any, *, seed: Any = None, options: Any = None) -> Any:
    return np.zeros(2, np.float32), {}


def _reset_without_seed(self: Any, *, options: Any = None) -> Any:
    return np.zeros(2, np.float32), {}


def _reset_without_options(self: Any, *, seed: Any = None) -> Any:
    super(type(self), self).reset(seed=seed)
    return np.zeros(2, np.float32), {}


def _noisy_step(self: Any, action: Any) -> Any:
    noise = np.random.default_rng().uniform(-0.5, 0.5, 2).astype(np.float32)
    return noise, 1.0, False, False, {}


def _truncating_step(self: Any, action: Any) -> Any:
    return np.zeros(2, np.float32), 1.0, False, True, {}


def _obs_only_reset(self: Any, *, seed: Any = None, options: Any = None) -> Any:
    return np.zeros(2, np.float32)


def _legacy_seed(self: Any, seed: Any = None) -> None:
    """The pre-0.26 seeding method."""


BROKEN: dict[str, tuple[dict[str, Any], str]] = {
    # case: (methods replaced on the toy, fragment of the expected warning or error)
    "wrong obs dtype": ({"reset": _float64_obs}, "`env.reset()` is not within the observation"),
    "reused obs buffer": ({"step": _reused_buffer_step}, "share an object"),
    "unseeded reset": ({"reset": _unseeded_reset}, "is non-deterministic"),
    "no super().reset": ({"reset": _no_super_reset}, "does not call `super().reset(seed=seed)`"),
    "reset without seed": ({"reset": _reset_without_seed}, "does not provide a `seed`"),
    "reset without options": ({"reset": _reset_without_options}, "does not provide an `options`"),
    "nondeterministic step": ({"step": _noisy_step}, "Deterministic step observations"),
    "truncates at once": ({"step": _truncating_step}, "truncates after 1 step"),
    "reset returns obs only": ({"reset": _obs_only_reset}, "was not a tuple of the form"),
    "legacy seed method": ({"seed": _legacy_seed}, "support for the `seed` function is dropped"),
}


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_broken_envs_fail_like_gymnasium(case: str) -> None:
    attrs, fragment = BROKEN[case]
    ours, theirs = both(**attrs)
    assert ours == theirs
    messages, raised = ours
    assert any(fragment in text for text in [*messages, raised or ""]), ours


def test_good_env_with_spec_passes_the_determinism_checks() -> None:
    assert both() == (([], None), ([], None))


def _space_env(lib: Any, action_space: Any, observation_space: Any) -> Any:
    env = toy_class(lib)()
    env.action_space, env.observation_space = action_space, observation_space
    return env


def test_space_limits_warn_like_gymnasium() -> None:
    def spaces_of(lib: Any) -> tuple[Any, Any]:
        box = lib.spaces.Box
        return box(-np.inf, np.inf, (2,), np.float32), box(-5.0, 5.0, (2,), np.float32)

    ours = outcome(
        lambda: check_env(_space_env(palaestra, *spaces_of(palaestra)), skip_render_check=True)
    )
    theirs = outcome(
        lambda: gym_env_checker.check_env(
            _space_env(gymnasium, *spaces_of(gymnasium)), skip_render_check=True
        )
    )
    assert ours == theirs
    assert any("minimum value is -infinity" in m for m in ours[0])
    assert any("symmetric and normalized space" in m for m in ours[0])


def test_not_an_env_or_no_spaces() -> None:
    with pytest.raises(TypeError, match=r"must inherit from the palaestra\.Env class"):
        check_env(gymnasium.make("CartPole-v1"))

    class NoSpaces(palaestra.Env):  # type: ignore[type-arg]
        pass

    with pytest.raises(AttributeError, match="must specify an action space"):
        check_env(NoSpaces())


def test_render_modes_are_each_checked_through_the_spec(toy_id: str) -> None:
    class BadAnsi(PalToy):  # type: ignore[misc,valid-type]
        def render(self) -> Any:
            return 3 if self.render_mode == "ansi" else super().render()

    registry[toy_id].entry_point = BadAnsi
    messages, raised = outcome(lambda: check_env(make(toy_id).unwrapped))
    assert raised is None
    assert messages == [
        "\x1b[33mWARN: ANSI/ASCII rendering should produce a string, got <class 'int'>\x1b[0m"
    ]
    assert outcome(lambda: check_env(make(toy_id).unwrapped, skip_render_check=True)) == ([], None)


def test_close_twice_is_checked(toy_id: str) -> None:
    class CloseOnce(PalToy):  # type: ignore[misc,valid-type]
        def close(self) -> None:
            super().close()
            if self.closed > 1:
                raise RuntimeError("closed twice")

    registry[toy_id].entry_point = CloseOnce
    messages, raised = outcome(lambda: check_env(make(toy_id).unwrapped, skip_render_check=True))
    assert raised is None
    assert any("on the closed environment should be allowed" in m for m in messages)
    assert outcome(
        lambda: check_env(make(toy_id).unwrapped, skip_render_check=True, skip_close_check=True)
    ) == ([], None)


@pytest.mark.parametrize(
    ("a", "b", "exact", "expected"),
    [
        (np.ones(2), np.ones(2) + 1e-7, False, True),
        (np.ones(2), np.ones(2) + 1e-7, True, False),
        (np.ones(2), np.ones(3), False, False),
        ({"a": (1, [2.0])}, {"a": (1, [2.0])}, True, True),
        ({"a": 1}, {"b": 1}, False, False),
        ((1, 2), [1, 2], False, False),
        (
            np.array([np.ones(1), None], dtype=object),
            np.array([np.ones(1), None], dtype=object),
            True,
            True,
        ),
        (np.int8(1), np.int8(1), True, True),
    ],
)
def test_data_equivalence_matches_gymnasium(a: Any, b: Any, exact: bool, expected: bool) -> None:
    assert data_equivalence(a, b, exact) is expected
    assert gym_env_checker.data_equivalence(a, b, exact) == expected


@pytest.mark.parametrize(
    "name",
    [
        "check_reset_return_info_deprecation",
        "check_seed_deprecation",
        "check_reset_options",
        "check_reset_return_type",
        "check_reset_seed_determinism",
        "check_returned_data_not_reused",
        "check_step_determinism",
    ],
)
def test_gymnasiums_helpers_are_public_and_warn_alike(name: str) -> None:
    """Issue 26: ``utils.env_checker``'s helpers at Gymnasium's names, on a legacy toy."""
    import palaestra.utils.env_checker as ours_module

    assert name in ours_module.__all__

    def legacy(lib: Any) -> Any:
        def reset(self: Any, *, seed: Any = None, options: Any = None, return_info: Any = 0):
            return toy_class(lib).reset(self, seed=seed, options=options)

        return type(
            "Legacy", (toy_class(lib),), {"seed": lambda self, s=None: None, "reset": reset}
        )()

    ours = outcome(lambda: getattr(ours_module, name)(legacy(palaestra)))
    theirs = outcome(lambda: getattr(gym_env_checker, name)(legacy(gymnasium)))
    assert ours == theirs
