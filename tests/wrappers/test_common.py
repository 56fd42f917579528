"""TimeLimit, OrderEnforcing and PassiveEnvChecker: behaviour, messages and per-step cost."""

from __future__ import annotations

import copy
import pickle
import sys
import warnings
from collections.abc import Callable
from typing import Any

import gymnasium
import numpy as np
import pytest
from tests.registry.toys import GymToy, PalToy, toy_class

import palaestra
from palaestra.error import ResetNeeded
from palaestra.wrappers.common import OrderEnforcing, PassiveEnvChecker, TimeLimit


def warnings_of(fn: Callable[[], Any]) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fn()
    return [str(w.message).replace("gymnasium", "palaestra") for w in caught]


# --- TimeLimit -------------------------------------------------------------------------------


def test_time_limit_truncates_and_resets_its_count() -> None:
    env = TimeLimit(PalToy(), max_episode_steps=3)
    env.reset(seed=0)
    assert [env.step(1)[3] for _ in range(4)] == [False, False, True, True]
    env.reset()
    assert env.step(1)[3] is False


def test_time_limit_keeps_the_inner_truncation_and_termination() -> None:
    class Ends(PalToy):  # type: ignore[misc,valid-type]
        def step(self, action: Any) -> Any:
            obs = super().step(action)[0]
            return obs, 1.0, True, action == 1, {"k": 1}

    env = TimeLimit(Ends(), max_episode_steps=10)
    env.reset()
    assert env.step(1)[2:] == (True, True, {"k": 1})
    assert env.step(0)[2:] == (True, False, {"k": 1})


@pytest.mark.parametrize("bad", [0, -3, 1.5, None, "10"])
def test_time_limit_rejects_bad_limits_like_gymnasium(bad: Any) -> None:
    with pytest.raises((TypeError, ValueError)) as ours:
        TimeLimit(PalToy(), max_episode_steps=bad)
    with pytest.raises((TypeError, ValueError)) as theirs:
        gymnasium.wrappers.TimeLimit(GymToy(), max_episode_steps=bad)
    assert type(ours.value) is type(theirs.value)
    assert str(ours.value) == str(theirs.value)


def test_time_limit_before_reset_raises_like_gymnasium() -> None:
    with pytest.raises(TypeError):
        TimeLimit(PalToy(), 2).step(0)


def test_time_limit_spec_and_recorded_kwargs() -> None:
    env = TimeLimit(PalToy(), 4)
    assert env._saved_kwargs == {"max_episode_steps": 4}
    assert env.spec is None  # no spec below: nothing to describe
    inner = PalToy()
    inner.spec = palaestra.envs.registration.EnvSpec("Toy-v0", "tests.registry.toys:PalToy")
    spec = TimeLimit(inner, 4).spec
    assert spec is not None and spec.max_episode_steps == 4 and spec.additional_wrappers == ()
    assert inner.spec.max_episode_steps is None  # the inner spec was copied, not changed


# --- OrderEnforcing ---------------------------------------------------------------------------


def test_order_enforcing_messages_match_gymnasium() -> None:
    ours, theirs = (
        OrderEnforcing(PalToy("rgb_array")),
        gymnasium.wrappers.OrderEnforcing(GymToy("rgb_array")),
    )
    for call in (lambda e: e.step(0), lambda e: e.render()):
        with pytest.raises(ResetNeeded) as pal:
            call(ours)
        with pytest.raises(gymnasium.error.ResetNeeded) as gym:
            call(theirs)
        assert str(pal.value) == str(gym.value)
    assert ours.has_reset is False
    ours.reset()
    assert ours.has_reset is True
    assert ours.render().shape == (4, 4, 3)
    assert ours.step(0)[1] == 1.0


def test_order_enforcing_can_allow_render_before_reset() -> None:
    env = OrderEnforcing(PalToy("ansi"), disable_render_order_enforcing=True)
    assert isinstance(env.render(), str)
    with pytest.raises(ResetNeeded):
        env.step(0)
    assert env._saved_kwargs == {"disable_render_order_enforcing": True}


# --- PassiveEnvChecker ------------------------------------------------------------------------


def broken(lib: Any, **methods: Callable[..., Any]) -> Any:
    """A toy for ``lib`` with some methods replaced."""
    return type("Broken", (toy_class(lib),), methods)


def _run_checked(lib: Any, wrapper: Any, methods: dict[str, Callable[..., Any]]) -> list[str]:
    env = wrapper(broken(lib, **methods)("rgb_array"))

    def episode() -> None:
        env.reset(seed=0)
        for _ in range(3):
            env.step(0)
        env.render()

    return warnings_of(episode)


def _float64_obs(self: Any, *, seed: Any = None, options: Any = None) -> Any:
    type(self).__mro__[1].reset(self, seed=seed)
    return np.zeros(2), {}


def _shared_buffer(self: Any, action: Any) -> Any:
    self._state += 0.01
    return self._state, 1.0, False, False, {}


def _odd_step(self: Any, action: Any) -> Any:
    return np.zeros(2, np.float32), float("nan"), 0, None, {}


def _bad_frame(self: Any) -> Any:
    return np.zeros((4, 4), np.float32)


@pytest.mark.parametrize(
    ("methods", "expected"),
    [
        ({"reset": _float64_obs}, "was expecting numpy array dtype to be float32"),
        ({"step": _shared_buffer}, "share an object"),
        ({"step": _odd_step}, "The reward is a NaN value."),
        ({"step": _odd_step}, "Expects `terminated` signal to be a boolean"),
        ({"render": _bad_frame}, "with dtype uint8, got float32"),
    ],
)
def test_passive_checker_warns_like_gymnasium(
    methods: dict[str, Callable[..., Any]], expected: str
) -> None:
    ours = _run_checked(palaestra, PassiveEnvChecker, methods)
    theirs = _run_checked(gymnasium, gymnasium.wrappers.PassiveEnvChecker, methods)
    assert any(expected in message for message in ours), ours
    assert ours == theirs


def test_passive_checker_checks_only_the_first_calls() -> None:
    calls = []

    def counting_step(self: Any, action: Any) -> Any:
        calls.append(action)
        return np.zeros(2), 1.0, False, False, {}  # float64: warned about once

    env = PassiveEnvChecker(broken(palaestra, step=counting_step)())
    env.reset()
    assert any("dtype" in m for m in warnings_of(lambda: env.step(0)))
    assert warnings_of(lambda: [env.step(1) for _ in range(5)]) == []
    assert calls == [0, 1, 1, 1, 1, 1]


def test_passive_checker_raises_on_unusable_envs() -> None:
    def no_info(self: Any, action: Any) -> Any:
        return np.zeros(2, np.float32), 1.0, False, False, None

    env = PassiveEnvChecker(broken(palaestra, step=no_info)())
    env.reset()
    with pytest.raises(AssertionError, match="The `info` returned by `step\\(\\)` must be"):
        env.step(0)

    class NoSpaces(palaestra.Env):  # type: ignore[type-arg]
        pass

    with pytest.raises(AttributeError, match="must specify an action space"):
        PassiveEnvChecker(NoSpaces())
    bad_space = NoSpaces()
    bad_space.action_space = gymnasium.spaces.Discrete(2)  # type: ignore[assignment]
    with pytest.raises(TypeError, match="action space does not inherit from"):
        PassiveEnvChecker(bad_space)


def test_passive_checker_close_twice() -> None:
    def failing_close(self: Any) -> None:
        self.closed += 1
        if self.closed > 1:
            raise RuntimeError("already closed")

    env = PassiveEnvChecker(PalToy())
    env.close()
    env.close()
    assert env.unwrapped.closed == 2
    env = PassiveEnvChecker(broken(palaestra, close=failing_close)())
    env.close()
    with pytest.warns(UserWarning, match="on the closed environment should be allowed"):
        with pytest.raises(RuntimeError, match="already closed"):
            env.close()


# --- the stack make() builds ------------------------------------------------------------------


def _stack() -> Any:
    env = PalToy()
    env.spec = palaestra.envs.registration.EnvSpec("Toy-v0", "tests.registry.toys:PalToy")
    return TimeLimit(OrderEnforcing(PassiveEnvChecker(env)), max_episode_steps=100)


def _wrapper_frames_per_step(env: Any) -> list[str]:
    """Names of Python functions of this module's wrappers entered during one step."""
    entered: list[str] = []

    def profile(frame: Any, event: str, arg: Any) -> None:
        if event == "call" and frame.f_code.co_filename.endswith("wrappers/common.py"):
            entered.append(frame.f_code.co_name)

    sys.setprofile(profile)
    try:
        env.step(0)
    finally:
        sys.setprofile(None)
    return entered


def test_checked_stack_costs_one_wrapper_call_per_step() -> None:
    env = _stack()
    env.reset(seed=0)
    first = _wrapper_frames_per_step(env)
    assert "step" in first and len(first) >= 3  # checking: every layer takes part
    for _ in range(2):
        env.step(0)
    assert _wrapper_frames_per_step(env) == ["step"]  # only TimeLimit's
    assert env.env.step == env.unwrapped.step


def test_rebinding_survives_reset_copy_and_pickle() -> None:
    env = _stack()
    env.reset(seed=1)
    for _ in range(3):
        env.step(1)
    clone = copy.deepcopy(env)
    restored = pickle.loads(pickle.dumps(env))
    expected = env.step(0)[0]
    for other in (clone, restored):
        assert other.env.step.__self__ is other.unwrapped  # bound to its own copy
        np.testing.assert_array_equal(other.step(0)[0], expected)
    env.reset(seed=1)
    assert [env.step(1)[3] for _ in range(100)][-2:] == [False, True]
    with pytest.raises(ResetNeeded):
        OrderEnforcing(PassiveEnvChecker(PalToy())).step(0)
