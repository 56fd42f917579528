"""The passive checks: same warnings and errors as gymnasium's for the same broken input."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import gymnasium
import gymnasium.utils.passive_env_checker as gym_checker
import numpy as np
import pytest
from tests.registry.toys import toy_class

import palaestra
import palaestra.utils.passive_env_checker as checker


def outcome(fn: Callable[[], Any]) -> tuple[list[str], str | None]:
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
    messages = [str(w.message) for w in caught]
    unify = lambda text: text.replace("gymnasium", "palaestra")  # noqa: E731
    return [unify(m) for m in messages], None if raised is None else unify(raised)


def same_outcome(
    ours: Callable[[], Any], theirs: Callable[[], Any]
) -> tuple[list[str], str | None]:
    result = outcome(ours)
    assert result == outcome(theirs)
    assert result != ([], None), "the case was meant to warn or raise"
    return result


# --- spaces -----------------------------------------------------------------------------------


def _degenerate(lib: Any, case: str) -> Any:
    s = lib.spaces
    if case == "equal bounds":
        return s.Box(0.0, 0.0, (2,))
    if case == "zero discrete":
        space = s.Discrete(2)
        space.n = np.int64(0)
        return space
    if case == "empty tuple":
        return s.Tuple([])
    if case == "empty dict":
        return s.Dict({})
    if case == "nested":
        return s.Dict({"a": s.Tuple([s.Box(1.0, 1.0, (1,))])})
    if case == "not a space":
        return [0, 1]
    raise AssertionError(case)


@pytest.mark.parametrize(
    "case", ["equal bounds", "zero discrete", "empty tuple", "empty dict", "nested", "not a space"]
)
@pytest.mark.parametrize("kind", ["observation", "action"])
def test_space_checks_match_gymnasium(case: str, kind: str) -> None:
    ours = getattr(checker, f"check_{kind}_space")
    theirs = getattr(gym_checker, f"check_{kind}_space")
    same_outcome(
        lambda: ours(_degenerate(palaestra, case)), lambda: theirs(_degenerate(gymnasium, case))
    )


def test_valid_spaces_pass_silently() -> None:
    s = palaestra.spaces
    for space in (
        s.Box(-1.0, 1.0, (3,)),
        s.Discrete(3),
        s.MultiDiscrete([2, 3]),
        s.MultiBinary(4),
        s.Dict({"a": s.Tuple([s.Discrete(2), s.Box(0.0, 1.0)])}),
    ):
        assert outcome(lambda s=space: checker.check_observation_space(s)) == ([], None)


# --- observations -----------------------------------------------------------------------------


def _obs_case(lib: Any, case: str) -> tuple[Any, Any]:
    s = lib.spaces
    box = s.Box(-1.0, 1.0, (2,), np.float32)
    return {
        "discrete float": (1.5, s.Discrete(3)),
        "box list": ([0.0, 0.0], box),
        "box float64": (np.zeros(2), box),
        "box outside": (np.full(2, 5, np.float32), box),
        "multibinary list": ([0, 1], s.MultiBinary(2)),
        "tuple as list": ([0, 1], s.Tuple([s.Discrete(2), s.Discrete(2)])),
        "tuple too short": ((0,), s.Tuple([s.Discrete(2), s.Discrete(2)])),
        "dict keys": ({"b": 0}, s.Dict({"a": s.Discrete(2)})),
        "dict not dict": (0, s.Dict({"a": s.Discrete(2)})),
    }[case]


@pytest.mark.parametrize(
    "case",
    [
        "discrete float",
        "box list",
        "box float64",
        "box outside",
        "multibinary list",
        "tuple as list",
        "tuple too short",
        "dict keys",
        "dict not dict",
    ],
)
def test_check_obs_matches_gymnasium(case: str) -> None:
    ours = _obs_case(palaestra, case)
    theirs = _obs_case(gymnasium, case)
    same_outcome(
        lambda: checker.check_obs(*ours, "reset"), lambda: gym_checker.check_obs(*theirs, "reset")
    )


def test_check_obs_accepts_good_observations() -> None:
    s = palaestra.spaces
    space = s.Dict({"pos": s.Box(-1.0, 1.0, (2,), np.float32), "n": s.Discrete(3)})
    obs = {"pos": np.zeros(2, np.float32), "n": np.int64(2)}
    assert outcome(lambda: checker.check_obs(obs, space, "step")) == ([], None)


def test_data_shares_objects() -> None:
    buffer = np.zeros(3)
    info: dict[str, Any] = {"x": [1]}
    assert checker.data_shares_objects(buffer, buffer[1:])
    assert checker.data_shares_objects({"a": {"b": buffer}}, {"a": {"b": buffer}})
    assert checker.data_shares_objects(info, info)
    assert checker.data_shares_objects((1, buffer), (2, buffer))
    objects = np.array([buffer, None], dtype=object)
    assert checker.data_shares_objects(objects, np.array([buffer, None], dtype=object))
    assert not checker.data_shares_objects(buffer, buffer.copy())
    assert not checker.data_shares_objects(1000, 1000)
    assert not checker.data_shares_objects(buffer, list(buffer))
    assert not checker.data_shares_objects({"a": np.zeros(1)}, {"a": np.zeros(1)})


# --- reset / step / render --------------------------------------------------------------------


def _env(lib: Any, render_mode: str | None = None, metadata: Any = None, **methods: Any) -> Any:
    attrs = dict(methods)
    if metadata is not None:
        attrs["metadata"] = metadata
    return type("Broken", (toy_class(lib),), attrs)(render_mode)


def _reset_no_seed(self: Any) -> Any:
    return np.zeros(2, np.float32), {}


def _reset_seed_default(self: Any, *, seed: Any = 3, options: Any = None) -> Any:
    return np.zeros(2, np.float32), {}


RESET_CASES: dict[str, Callable[..., Any]] = {
    "no seed or options": _reset_no_seed,
    "seed default": _reset_seed_default,
    "obs only": lambda self, *, seed=None, options=None: np.zeros(2, np.float32),
    "three items": lambda self, *, seed=None, options=None: (np.zeros(2, np.float32), {}, 0),
    "info list": lambda self, *, seed=None, options=None: (np.zeros(2, np.float32), []),
}


@pytest.mark.parametrize("case", sorted(RESET_CASES))
def test_reset_checks_match_gymnasium(case: str) -> None:
    method = RESET_CASES[case]
    same_outcome(
        lambda: checker.env_reset_passive_checker(_env(palaestra, reset=method)),
        lambda: gym_checker.env_reset_passive_checker(_env(gymnasium, reset=method)),
    )


def _step(*result: Any) -> Callable[..., Any]:
    return lambda self, action: result


OBS = np.zeros(2, np.float32)
STEP_CASES: dict[str, Callable[..., Any]] = {
    "old api": _step(OBS, 1.0, False, {}),
    "old api int done": _step(OBS, 1.0, 0, {}),
    "six items": _step(OBS, 1.0, False, False, {}, None),
    "not a tuple": _step,  # returns a lambda: not a tuple
    "np.bool_ flags": _step(OBS, 1.0, np.bool_(False), np.bool_(True), {}),
    "string reward": _step(OBS, "1", False, False, {}),
    "nan reward": _step(OBS, float("nan"), False, False, {}),
    "inf reward": _step(OBS, np.float32("inf"), False, False, {}),
    "int flags": _step(OBS, 1, 1, 0, {}),
    "info none": _step(OBS, 1.0, False, False, None),
}


@pytest.mark.parametrize("case", sorted(STEP_CASES))
def test_step_checks_match_gymnasium(case: str) -> None:
    method = STEP_CASES[case]
    ours = outcome(lambda: checker.env_step_passive_checker(_env(palaestra, step=method), 0))
    theirs = outcome(lambda: gym_checker.env_step_passive_checker(_env(gymnasium, step=method), 0))
    assert ours == theirs
    assert (ours == ([], None)) == (case == "np.bool_ flags")


def _frame(value: Any) -> Callable[..., Any]:
    return lambda self: value


DEPTH = {"render_modes": ["depth_array"], "render_fps": 4}
RENDER_CASES: dict[str, tuple[str | None, Any, Any]] = {
    # case: (render mode, metadata or None for the toy's, render() result)
    "no render_modes": (None, {}, None),
    "modes not a list": (None, {"render_modes": "rgb_array", "render_fps": 4}, None),
    "modes not strings": (None, {"render_modes": [1], "render_fps": 4}, None),
    "no fps": ("rgb_array", {"render_modes": ["rgb_array"]}, np.zeros((2, 2, 3), np.uint8)),
    "fps string": ("rgb_array", {"render_modes": ["rgb_array"], "render_fps": "4"}, None),
    "fps zero": ("rgb_array", {"render_modes": ["rgb_array"], "render_fps": 0}, None),
    "unsupported mode": ("human", None, None),
    "mode without modes": ("ansi", {"render_modes": []}, "x"),
    "rgb not array": ("rgb_array", None, [1]),
    "rgb wrong dtype and axes": ("rgb_array", None, np.zeros((2, 2), np.float64)),
    "rgb four channels": ("rgb_array", None, np.zeros((2, 2, 4), np.uint8)),
    "ansi not string": ("ansi", None, 3),
    "human returns": ("human", {"render_modes": ["human"], "render_fps": 4}, 1),
    "depth not 2d": (
        "depth_array",
        {"render_modes": ["depth_array"], "render_fps": 4},
        np.zeros(3),
    ),
    "depth not array": ("depth_array", {"render_modes": ["depth_array"], "render_fps": 4}, 0),
    "list not list": ("rgb_array_list", {"render_modes": ["rgb_array_list"], "render_fps": 4}, 0),
    "list bad item": (
        "rgb_array_list",
        {"render_modes": ["rgb_array_list"], "render_fps": 4},
        [np.zeros((2, 2, 3), np.uint8), "x"],
    ),
}


@pytest.mark.parametrize("case", sorted(RENDER_CASES))
def test_render_checks_match_gymnasium(case: str) -> None:
    mode, metadata, frame = RENDER_CASES[case]
    same_outcome(
        lambda: checker.env_render_passive_checker(
            _env(palaestra, mode, metadata, render=_frame(frame))
        ),
        lambda: gym_checker.env_render_passive_checker(
            _env(gymnasium, mode, metadata, render=_frame(frame))
        ),
    )


def test_good_env_passes_every_passive_check() -> None:
    env = _env(palaestra, "rgb_array")
    assert outcome(lambda: checker.env_reset_passive_checker(env, seed=0)) == ([], None)
    assert outcome(lambda: checker.env_step_passive_checker(env, 1)) == ([], None)
    assert outcome(lambda: checker.env_render_passive_checker(env)) == ([], None)
