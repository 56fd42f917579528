"""LunarLander: time limit, rendering, bad input and a missing box2d."""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import numpy as np
import pytest

import palaestra
from palaestra import error

pytest.importorskip("Box2D")


def test_time_limit_truncates_at_1000() -> None:
    env = palaestra.make("LunarLander-v3", max_episode_steps=3, gravity=-1.0)
    env.reset(seed=0)
    assert [env.step(0)[3] for _ in range(3)] == [False, False, True]


@pytest.mark.parametrize("continuous", [False, True])
def test_rgb_array_frames_show_the_scene(continuous: bool) -> None:
    env = palaestra.make("LunarLander-v3", continuous=continuous, render_mode="rgb_array")
    env.reset(seed=0)
    main = np.array([1.0, 0.0], dtype=np.float32) if continuous else 2
    for _ in range(8):
        env.step(main)
    frame = env.render()
    assert frame.shape == (400, 600, 3) and frame.dtype == np.uint8
    colors = {tuple(c) for c in frame.reshape(-1, 3)[::7]}
    assert (0, 0, 0) in colors and (255, 255, 255) in colors  # sky, ground
    assert (128, 102, 230) in colors  # the lander's hull
    assert (204, 204, 0) in colors  # the flags
    assert len(env.unwrapped.particles) > 0  # the main engine's exhaust
    env.close()
    env.close()


def test_frames_look_like_gymnasiums() -> None:
    """Not pixel copies, but the same picture: >= 98% of pixels equal on a busy frame."""
    gymnasium = pytest.importorskip("gymnasium")
    pytest.importorskip("pygame")
    ours = palaestra.make("LunarLander-v3", render_mode="rgb_array")
    ref = gymnasium.make("LunarLander-v3", render_mode="rgb_array")
    ours.reset(seed=3)
    ref.reset(seed=3)
    for t in range(50):
        action = 2 if t % 3 else 1
        ours.step(action)
        ref.step(action)
    same = (ours.render() == ref.render()).all(axis=-1).mean()
    assert same >= 0.98, same


class _FakeWindow:
    instances: list[_FakeWindow] = []

    def __init__(self, title: str, fps: int) -> None:
        self.title, self.fps, self.frames, self.closed = title, fps, [], False
        _FakeWindow.instances.append(self)

    def show(self, frame: np.ndarray) -> None:
        self.frames.append(frame)

    def close(self) -> None:
        self.closed = True


def test_human_mode_shows_reset_and_steps(monkeypatch: Any) -> None:
    from palaestra.rendering import window

    monkeypatch.setattr(window, "HumanWindow", _FakeWindow)
    _FakeWindow.instances.clear()
    env = palaestra.make("LunarLander-v3", render_mode="human")
    env.reset(seed=0)
    env.step(0)
    (win,) = _FakeWindow.instances
    # Gymnasium renders in reset, in the no-op step reset takes, and in each step.
    assert win.fps == 50 and len(win.frames) == 3 and win.title == "LunarLander-v3"
    env.close()
    assert win.closed
    env.close()


def test_render_without_mode_warns_and_before_reset_raises() -> None:
    env = palaestra.make("LunarLander-v3")
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="without specifying any render mode"):
        assert env.render() is None
    with pytest.raises(error.ResetNeeded):
        palaestra.make("LunarLander-v3", render_mode="rgb_array").unwrapped.render()


def test_step_before_reset() -> None:
    with pytest.raises(error.ResetNeeded):
        palaestra.make("LunarLander-v3").unwrapped.step(0)


# -- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "action, match",
    [
        (np.array([0.5, 0.0]), r"array given to a discrete env\? use continuous=True"),
        (4, "Invalid action 4"),
        (-1, "Invalid action -1"),
        (1.5, "Invalid action 1.5"),
        ("2", "Invalid action '2'"),
    ],
)
def test_discrete_env_refuses(action: Any, match: str) -> None:
    env = palaestra.make("LunarLander-v3").unwrapped
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=match) as info:
        env.step(action)
    assert "Discrete(4)" in str(info.value)


@pytest.mark.parametrize(
    "action, match",
    [
        (2, r"expected shape \(2,\), got \(\) \(a discrete action given to a continuous env\?\)"),
        (np.zeros(3, dtype=np.float32), r"expected shape \(2,\), got \(3,\)"),
        (np.zeros((1, 2), dtype=np.float32), r"expected shape \(2,\), got \(1, 2\)"),
        (np.array([np.nan, 0.0]), "must be finite"),
        (np.array([0.0, np.inf]), "must be finite"),
        (np.array([np.nan, 0.0], dtype=np.float32), "must be finite"),
        (np.array(["a", "b"]), "expected real numeric values, got dtype <U1"),
        (np.array([1j, 0]), "expected real numeric values, got dtype complex128"),
    ],
)
def test_continuous_env_refuses(action: Any, match: str) -> None:
    env = palaestra.make("LunarLanderContinuous-v3").unwrapped
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=match) as info:
        env.step(action)
    assert "Box(-1.0, 1.0, (2,), float32)" in str(info.value)


def test_continuous_env_accepts_lists_and_clips_like_gymnasium() -> None:
    env = palaestra.make("LunarLanderContinuous-v3")
    env.reset(seed=0)
    a = env.step([5, -5])
    env.reset(seed=0)
    b = env.step(np.array([1.0, -1.0], dtype=np.float32))
    assert a[0].tobytes() == b[0].tobytes() and a[1] == b[1]


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        ({"gravity": 0.0}, ValueError, r"gravity \(current value: 0.0\) must be between -12 and 0"),
        ({"gravity": -12}, ValueError, r"gravity \(current value: -12\) must be between"),
        ({"gravity": 3}, ValueError, r"current value: 3\)"),
        ({"gravity": float("nan")}, ValueError, "gravity must be finite, got nan"),
        ({"gravity": "-10"}, TypeError, r"gravity must be a real number, got '-10' \(str\)"),
        ({"wind_power": None}, TypeError, "wind_power must be a real number, got None"),
        ({"turbulence_power": float("inf")}, ValueError, "turbulence_power must be finite"),
        ({"continuous": "yes"}, TypeError, "continuous must be a bool, got 'yes'"),
        ({"enable_wind": 1}, TypeError, r"enable_wind must be a bool, got 1 \(int\)"),
        ({"render_mode": "ansi"}, error.UnsupportedMode, "render_mode='ansi' is not one of"),
    ],
)
@pytest.mark.filterwarnings("ignore:.*initialised with render_mode='ansi'")
def test_bad_kwargs(kwargs: dict[str, Any], exc: type, match: str) -> None:
    with pytest.raises(exc, match=match):
        palaestra.make("LunarLander-v3", **kwargs)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"wind_power": 25.0}, r"wind_power value is recommended .* \(current value: 25.0\)"),
        ({"wind_power": -1}, r"\(current value: -1\)"),
        ({"turbulence_power": 2.5}, r"turbulence_power value .* \(current value: 2.5\)"),
    ],
)
def test_wind_outside_gymnasiums_advice_warns_as_gymnasium(
    kwargs: dict[str, Any], match: str
) -> None:
    # Gymnasium accepts these (with this warning); refusing them would break its users' code.
    with pytest.warns(UserWarning, match=match):
        env = palaestra.make("LunarLander-v3", enable_wind=True, **kwargs)
    env.reset(seed=0)
    env.step(0)


@pytest.mark.parametrize("env_id", ["LunarLander-v3", "BipedalWalkerHardcore-v3"])
def test_missing_box2d_names_the_extra(env_id: str) -> None:
    """With ``Box2D`` unimportable, make() raises DependencyNotInstalled with the pip command."""
    code = (
        "import sys\n"
        "sys.modules['Box2D'] = None  # import Box2D now raises ImportError\n"
        "import palaestra\n"
        "from palaestra import error\n"
        "try:\n"
        f"    palaestra.make({env_id!r})\n"
        "except error.DependencyNotInstalled as e:\n"
        "    print('raised:', e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == (
        'raised: box2d is not installed, run `pip install "palaestra[box2d]"` (needed for the '
        "Box2D environments: LunarLander, BipedalWalker, CarRacing)"
    ), out.stderr
