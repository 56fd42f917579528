"""Bad actions and reset options get clear errors; finite out-of-range forces are clipped."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import palaestra
from palaestra import error
from palaestra.envs.classic_control import (
    AcrobotEnv,
    CartPoleEnv,
    Continuous_MountainCarEnv,
    MountainCarEnv,
    PendulumEnv,
)

DISCRETE = [CartPoleEnv, MountainCarEnv, AcrobotEnv]
CONTINUOUS = [Continuous_MountainCarEnv, PendulumEnv]


def test_tutorial_mountain_car_step_4_raises() -> None:
    env = palaestra.make("MountainCar-v0")
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=r"Invalid action 4 .*Discrete\(3\)"):
        env.step(4)


@pytest.mark.parametrize("cls", DISCRETE)
@pytest.mark.parametrize("action", [-1, 3, 2.0, "1", None, np.array([1]), np.float32(1)])
def test_discrete_rejects(cls: type, action: object) -> None:
    env = cls()
    env.reset(seed=0)
    if cls is CartPoleEnv and action == 2.0:
        action = 2  # CartPole has two actions: 2 is out of range there
    with pytest.raises(error.InvalidAction, match="Invalid action"):
        env.step(action)


@pytest.mark.parametrize("cls", DISCRETE)
@pytest.mark.parametrize("action", [1, np.int64(1), np.int8(1), np.array(1), True])
def test_discrete_accepts_what_the_space_contains(cls: type, action: object) -> None:
    env = cls()
    env.reset(seed=0)
    obs, *_ = env.step(action)
    ref = cls()
    ref.reset(seed=0)
    assert obs.tobytes() == ref.step(1)[0].tobytes()


@pytest.mark.parametrize("cls", CONTINUOUS)
@pytest.mark.parametrize(
    "action, match",
    [
        (np.array([np.nan], dtype=np.float32), "finite"),
        (np.array([np.inf]), "finite"),
        (np.array([-np.inf]), "finite"),
        (np.array([0.1, 0.2], dtype=np.float32), "shape"),
        (np.float32(0.1), "shape"),
        (np.zeros((1, 1), dtype=np.float32), "shape"),
        ("x", "numeric"),
        (None, "shape|numeric"),
    ],
)
def test_continuous_rejects(cls: type, action: object, match: str) -> None:
    env = cls()
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=match) as info:
        env.step(action)
    assert "Box(" in str(info.value)  # the message names the space


@pytest.mark.parametrize("cls", CONTINUOUS)
def test_continuous_clips_finite_out_of_range(cls: type) -> None:
    """As in Gymnasium, the force is clipped (the continuous MountainCar's reward is not)."""
    big, edge = cls(), cls()
    big.reset(seed=3)
    edge.reset(seed=3)
    high = float(big.action_space.high[0])
    obs_big, reward_big, *_ = big.step(np.array([10 * high], dtype=np.float32))
    obs_edge, reward_edge, *_ = edge.step(np.array([high], dtype=np.float32))
    assert obs_big.tobytes() == obs_edge.tobytes()
    if cls is Continuous_MountainCarEnv:
        assert reward_big == pytest.approx(reward_edge - 0.1 * (100 * high**2 - high**2))
    else:
        assert reward_big == reward_edge
    big.step([0.5])  # lists are accepted


@pytest.mark.parametrize("cls", DISCRETE + CONTINUOUS)
def test_step_before_reset(cls: type) -> None:
    env = cls()
    with pytest.raises(error.ResetNeeded):
        env.step(env.action_space.sample())


BOUNDED = [CartPoleEnv, MountainCarEnv, Continuous_MountainCarEnv, AcrobotEnv]


@pytest.mark.parametrize("cls", BOUNDED)
@pytest.mark.parametrize(
    "options, match",
    [
        ({"low": 0.1, "high": -0.1}, r"Lower bound \(0.1\) must be lower than higher bound"),
        ({"low": "abc"}, r"low='abc'.*could not be converted"),
        ({"high": None}, r"high=None"),
        ({"low": float("nan")}, r"low=nan must be finite"),
        ({"high": float("inf")}, r"high=inf must be finite"),
        ({"low": [0.0, 1.0]}, r"low=\[0.0, 1.0\]"),
    ],
)
def test_bad_reset_bounds(cls: type, options: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        cls().reset(seed=0, options=options)


@pytest.mark.parametrize(
    "options, match",
    [({"x_init": "pi"}, "x_init='pi'"), ({"y_init": float("nan")}, "y_init=nan must be finite")],
)
def test_bad_pendulum_options(options: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        PendulumEnv().reset(seed=0, options=options)


def test_unknown_options_are_ignored_like_gymnasium() -> None:
    obs, _ = CartPoleEnv().reset(seed=0, options={"something": 1})
    assert obs.tobytes() == CartPoleEnv().reset(seed=0)[0].tobytes()


def test_bad_render_mode() -> None:
    with pytest.raises(error.UnsupportedMode, match="ansi"):
        CartPoleEnv(render_mode="ansi")


@pytest.mark.parametrize("cls", CONTINUOUS)
@pytest.mark.parametrize(
    ("action", "dtype"),
    [
        (np.array([0.5 + 1j]), "complex128"),
        (np.array([0.5 + 0j]), "complex128"),  # numpy would drop the zero imaginary part
        ([0.5 + 0j], "complex128"),
        (np.array(["0.5"]), "<U3"),  # a float32 cast would parse it
        (["0.5"], "<U3"),
        (np.array([0.5], dtype=object), "object"),
        (b"1", "|S1"),
    ],
)
def test_continuous_rejects_complex_and_string_actions(
    cls: type, action: object, dtype: str
) -> None:
    env = cls()
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction) as info:
        env.step(action)
    space = repr(env.action_space)
    assert str(info.value) == (
        f"Invalid action {action!r} ({type(action).__name__}) for action space {space}: "
        f"expected real numeric values, got dtype {dtype}"
    )


RESET_OPTIONS = [
    ("Pendulum-v1", {"x_init": -5}, "Reset option x_init=-5 must be >= 0: the state is drawn "
     "from [-x_init, x_init]."),
    ("Pendulum-v1", {"y_init": -0.5}, "Reset option y_init=-0.5 must be >= 0"),
    ("Pendulum-v1", {"x_init": 1e308}, "Reset option x_init=1e+308 is too large: "
     "[-x_init, x_init] overflows a float."),
    ("Pendulum-v1", {"x_init": 0, "y_init": "2"}, None),  # a zero-width box; a numeric string
    ("CartPole-v1", {"low": -1e308, "high": 1e308}, "Reset options low=-1e+308 and high=1e+308 "
     "span more than a float can hold (high - low overflows)."),
    ("Acrobot-v1", {"low": -1e308, "high": 1e308}, "low=-1e+308 and high=1e+308 span more"),
    ("MountainCar-v0", {"low": -1e308, "high": 1e308}, "low=-1e+308 and high=1e+308 span more"),
    ("MountainCarContinuous-v0", {"low": -1e308, "high": 1e308}, "high - low overflows"),
    ("CartPole-v1", {"low": 0.1, "high": 0.1}, None),
    ("CartPole-v1", {"low": -0.2, "high": 0.2}, None),
]  # fmt: skip


@pytest.mark.parametrize(("env_id", "options", "message"), RESET_OPTIONS)
def test_reset_options_are_refused_where_gymnasium_refuses_them(
    env_id: str, options: dict, message: str | None
) -> None:
    import gymnasium

    theirs = gymnasium.make(env_id).unwrapped
    if message is None:
        theirs.reset(seed=0, options=options)
        palaestra.make(env_id).reset(seed=0, options=options)
        palaestra.make_vec(env_id, 2).reset(seed=0, options=options)
        return
    with pytest.raises((ValueError, OverflowError)), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # numpy's "overflow in subtract"
        theirs.reset(seed=0, options=options)  # numpy: "high - low < 0", "Range exceeds ..."
    for env in (palaestra.make(env_id), palaestra.make_vec(env_id, 2)):
        with pytest.raises(ValueError) as info:
            env.reset(seed=0, options=options)
        assert message in str(info.value)
