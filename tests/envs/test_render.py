"""render(): frames from palaestra.rendering, a lazily opened window, Gymnasium's warning."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from palaestra.envs.classic_control import (
    AcrobotEnv,
    CartPoleEnv,
    Continuous_MountainCarEnv,
    MountainCarEnv,
    PendulumEnv,
)

SIZES = [
    (CartPoleEnv, (400, 600, 3)),
    (MountainCarEnv, (400, 600, 3)),
    (Continuous_MountainCarEnv, (400, 600, 3)),
    (PendulumEnv, (500, 500, 3)),
    (AcrobotEnv, (500, 500, 3)),
]


@pytest.mark.parametrize("cls, shape", SIZES)
def test_rgb_array_frames(cls: type, shape: tuple[int, int, int]) -> None:
    pytest.importorskip("palaestra.rendering.scenes")
    env = cls(render_mode="rgb_array")
    env.reset(seed=0)
    first = env.render()
    assert first.shape == shape and first.dtype == np.uint8
    for _ in range(5):
        env.step(env.action_space.sample())
    assert env.render().shape == shape
    env.close()


def test_frame_follows_the_state() -> None:
    pytest.importorskip("palaestra.rendering.scenes")
    env = CartPoleEnv(render_mode="rgb_array")
    env.reset(seed=0)
    before = env.render()
    env.state = np.array([1.5, 0.0, 0.1, 0.0])
    assert not np.array_equal(before, env.render())


def test_no_render_mode_warns_and_returns_none() -> None:
    env = MountainCarEnv()
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="without specifying any render mode"):
        assert env.render() is None


class _FakeWindow:
    instances: list[_FakeWindow] = []

    def __init__(self, title: str, fps: int) -> None:
        self.title, self.fps, self.frames, self.closed = title, fps, [], False
        _FakeWindow.instances.append(self)

    def show(self, frame: np.ndarray) -> None:
        self.frames.append(frame)

    def close(self) -> None:
        self.closed = True


def test_human_mode_shows_each_step_in_one_window(monkeypatch: Any) -> None:
    window = pytest.importorskip("palaestra.rendering.window")
    pytest.importorskip("palaestra.rendering.scenes")
    monkeypatch.setattr(window, "HumanWindow", _FakeWindow)
    _FakeWindow.instances.clear()
    env = PendulumEnv(render_mode="human")
    assert _FakeWindow.instances == []  # opened lazily
    env.reset(seed=0)
    for _ in range(3):
        env.step(np.array([0.5], dtype=np.float32))
    (win,) = _FakeWindow.instances
    assert win.fps == 30 and len(win.frames) == 4  # reset + 3 steps, as Gymnasium renders
    assert env.render() is None
    env.close()
    assert win.closed
    env.close()  # twice is harmless


def test_render_before_reset() -> None:
    from palaestra import error

    with pytest.raises(error.ResetNeeded):
        CartPoleEnv(render_mode="rgb_array").render()
