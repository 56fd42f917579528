"""The Atari ids: the same set and settings as ale-py's, no ale-py import, all makeable."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import palaestra
from palaestra.envs.atari import ROM_IDS
from palaestra.envs.registration import registry
from palaestra.utils.env_checker import check_env

ATARI_IDS = sorted(
    i for i, s in registry.items() if str(s.entry_point).startswith("palaestra.envs.atari")
)


def gymnasium_atari_specs(suffix: str) -> dict:
    gymnasium = pytest.importorskip("gymnasium")
    ale_py = pytest.importorskip("ale_py")
    gymnasium.register_envs(ale_py)
    specs = gymnasium.registry.items()
    return {i: s for i, s in specs if i.endswith(suffix) and "ale_py" in str(s.entry_point)}


def test_static_game_list_is_ale_pys_rom_list() -> None:
    roms = pytest.importorskip("ale_py.roms")
    assert ROM_IDS == tuple(sorted(roms.get_all_rom_ids()))


@pytest.mark.parametrize("suffix", ["-v5", "NoFrameskip-v4"])
def test_ids_and_settings_equal_ale_pys(suffix: str) -> None:
    ref = gymnasium_atari_specs(suffix)
    ours = {i: registry[i] for i in ATARI_IDS if i.endswith(suffix)}
    assert sorted(ours) == sorted(ref)
    assert len(ours) == (104 if suffix == "-v5" else 62)
    for env_id, spec in ours.items():
        assert spec.kwargs == ref[env_id].kwargs, env_id
        assert spec.max_episode_steps == ref[env_id].max_episode_steps, env_id
        assert spec.entry_point == "palaestra.envs.atari.env:AtariEnv"
        expected_vector = "palaestra.envs.atari.vector:AtariVectorEnv" if suffix == "-v5" else None
        assert spec.vector_entry_point == expected_vector


def test_import_palaestra_does_not_load_ale_py() -> None:
    code = "import sys, palaestra; palaestra.spec('ALE/Pong-v5'); print('ale_py' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_make_wraps_as_gymnasium_does() -> None:
    env = palaestra.make("ALE/Breakout-v5")
    assert str(env) == "<OrderEnforcing<PassiveEnvChecker<AtariEnv<ALE/Breakout-v5>>>>"
    assert env.spec is not None and env.spec.kwargs["game"] == "breakout"
    assert env.unwrapped.frameskip == 4 and env.unwrapped.game == "breakout"


def test_check_env_passes() -> None:
    env = palaestra.make("ALE/Pong-v5", render_mode="rgb_array")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning either
        check_env(env.unwrapped)


def test_make_vec_sync() -> None:
    envs = palaestra.make_vec("ALE/Pong-v5", 2, vectorization_mode="sync")
    obs, info = envs.reset(seed=0)
    assert obs.shape == (2, 210, 160, 3) and obs.dtype == np.uint8
    obs, rewards, *_, info = envs.step(np.array([0, 1]))
    assert obs.shape == (2, 210, 160, 3) and rewards.shape == (2,)
    assert info["lives"].tolist() == [0, 0] and info["frame_number"].tolist() == [4, 4]
    envs.close()


def test_render_rgb_array_is_the_screen() -> None:
    env = palaestra.make("ALE/Breakout-v5", render_mode="rgb_array")
    obs, _ = env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (210, 160, 3) and frame.dtype == np.uint8
    np.testing.assert_array_equal(frame, obs)
    assert frame is not obs


def test_human_render_shows_each_step_in_a_window(monkeypatch: pytest.MonkeyPatch) -> None:
    from palaestra.rendering import window

    shown = []
    monkeypatch.setattr(window.HumanWindow, "show", lambda self, frame: shown.append(frame))
    env = palaestra.make("ALE/Breakout-v5", render_mode="human")
    env.reset(seed=0)
    assert env.render() is None
    env.step(0)
    assert len(shown) == 3 and shown[0].shape == (210, 160, 3)
    assert env.unwrapped._window.fps == 15  # 60 Hz / frameskip 4: the game's real speed
    env.close()
    assert env.unwrapped._window is None


@pytest.mark.slow
@pytest.mark.parametrize("env_id", ATARI_IDS)
def test_every_id_makes_resets_and_steps(env_id: str) -> None:
    env = palaestra.make(env_id)
    obs, info = env.reset(seed=0)
    assert obs in env.observation_space
    assert set(info) == {"lives", "episode_frame_number", "frame_number", "seeds"}
    for action in np.random.default_rng(0).integers(0, env.action_space.n, 20):
        obs, reward, terminated, truncated, info = env.step(action)
        assert obs in env.observation_space and type(reward) is float
        assert type(terminated) is bool and type(truncated) is bool
