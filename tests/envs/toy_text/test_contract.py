"""Every toy-text id: check_env, spaces, seeded determinism, every render mode, close twice."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pytest
from tests.envs.toy_text.cases import TOY_TEXT_IDS

import palaestra
from palaestra import error
from palaestra.rendering import window
from palaestra.utils.env_checker import check_env

SIZES = {
    "Blackjack-v1": (376, 384, 3),
    "CliffWalking-v1": (256, 768, 3),
    "CliffWalkingSlippery-v1": (256, 768, 3),
    "FrozenLake-v1": (256, 256, 3),
    "FrozenLake8x8-v1": (512, 512, 3),
    "Taxi-v4": (456, 536, 3),
}
SPACES = {
    "Blackjack-v1": ("Tuple(Discrete(32), Discrete(11), Discrete(2))", "Discrete(2)"),
    "CliffWalking-v1": ("Discrete(48)", "Discrete(4)"),
    "CliffWalkingSlippery-v1": ("Discrete(48)", "Discrete(4)"),
    "FrozenLake-v1": ("Discrete(16)", "Discrete(4)"),
    "FrozenLake8x8-v1": ("Discrete(64)", "Discrete(4)"),
    "Taxi-v4": ("Discrete(500)", "Discrete(6)"),
}


@pytest.mark.parametrize("env_id", TOY_TEXT_IDS)
def test_check_env_passes_without_warnings(env_id: str) -> None:
    env = palaestra.make(env_id, render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    assert [str(w.message) for w in caught] == []


@pytest.mark.parametrize("env_id", TOY_TEXT_IDS)
def test_spaces(env_id: str) -> None:
    env = palaestra.make(env_id)
    assert (repr(env.observation_space), repr(env.action_space)) == SPACES[env_id]
    obs, _ = env.reset(seed=0)
    assert obs in env.observation_space


@pytest.mark.parametrize("env_id", TOY_TEXT_IDS)
def test_seeded_runs_repeat_and_seeds_differ(env_id: str) -> None:
    def run(seed: int) -> list[Any]:
        env = palaestra.make(env_id)
        env.action_space.seed(seed)
        out = [env.reset(seed=seed)[0]]
        for _ in range(200):
            obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
            out.append((obs, reward, terminated, truncated))
            if terminated or truncated:
                out.append(env.reset()[0])
        return out

    assert run(3) == run(3)
    assert run(3) != run(4)


@pytest.mark.parametrize("env_id", TOY_TEXT_IDS)
def test_rgb_array_frames_follow_the_game(env_id: str) -> None:
    env = palaestra.make(env_id, render_mode="rgb_array")
    env.reset(seed=1)
    frames = [env.render()]
    for _ in range(30):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        frames.append(env.render())
        if terminated or truncated:
            env.reset()
            frames.append(env.render())
    assert all(f.shape == SIZES[env_id] and f.dtype == np.uint8 for f in frames)
    assert len({f.tobytes() for f in frames}) > 1  # the picture changes with the state
    env.close()
    env.close()


@pytest.mark.parametrize("env_id", [i for i in TOY_TEXT_IDS if i != "Blackjack-v1"])
def test_ansi_is_text(env_id: str) -> None:
    env = palaestra.make(env_id, render_mode="ansi")
    env.reset(seed=0)
    text = env.render()
    assert isinstance(text, str) and text.endswith("\n")


def test_blackjack_has_no_ansi_mode_like_gymnasium() -> None:
    with pytest.raises(error.UnsupportedMode, match="render_mode='ansi' is not one of"):
        palaestra.envs.toy_text.BlackjackEnv(render_mode="ansi")


class _FakeWindow:
    instances: list[_FakeWindow] = []

    def __init__(self, title: str, fps: int) -> None:
        self.title, self.fps, self.frames, self.closed = title, fps, [], False
        _FakeWindow.instances.append(self)

    def show(self, frame: np.ndarray) -> None:
        self.frames.append(frame)

    def close(self) -> None:
        self.closed = True


@pytest.mark.parametrize("env_id", TOY_TEXT_IDS)
def test_human_mode_shows_reset_and_each_step(env_id: str, monkeypatch: Any) -> None:
    monkeypatch.setattr(window, "HumanWindow", _FakeWindow)
    _FakeWindow.instances.clear()
    env = palaestra.make(env_id, render_mode="human")
    assert _FakeWindow.instances == []  # opened lazily
    env.reset(seed=0)
    env.step(0)
    (win,) = _FakeWindow.instances
    assert win.title == env_id and win.fps == 4 and len(win.frames) == 2
    assert win.frames[-1].shape == SIZES[env_id]
    assert env.render() is None
    env.close()
    assert win.closed
    env.close()


@pytest.mark.parametrize("env_id", TOY_TEXT_IDS)
def test_render_without_mode_warns(env_id: str) -> None:
    env = palaestra.make(env_id)
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="without specifying any render mode"):
        assert env.render() is None


@pytest.mark.parametrize("env_id", TOY_TEXT_IDS)
def test_step_and_render_before_reset(env_id: str) -> None:
    env = palaestra.make(env_id, render_mode="rgb_array").unwrapped
    with pytest.raises(error.ResetNeeded):
        env.step(0)
    with pytest.raises(error.ResetNeeded):
        env.render()


@pytest.mark.parametrize("env_id", TOY_TEXT_IDS)
def test_vector_render_mode_uses_real_envs(env_id: str) -> None:
    envs = palaestra.make_vec(env_id, num_envs=2, render_mode="rgb_array")
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 2 and frames[0].shape == SIZES[env_id]
    envs.close()


def test_a_single_env_does_not_load_the_vector_package() -> None:
    import subprocess
    import sys

    code = (
        "import sys, palaestra\n"
        "for i in ['FrozenLake-v1', 'Taxi-v4', 'CliffWalking-v1', 'Blackjack-v1']:\n"
        "    palaestra.make(i).reset(seed=0)\n"
        "print(sorted(m for m in ('palaestra.vector', 'multiprocessing', 'torch', 'pygame')"
        " if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
