"""``AtariVecEnv``: the native vector Atari with SB3's ``VecEnv`` API, and the opt-in route
``make_atari_env(..., vec_env_cls=AtariVecEnv)``.

The reference is ale-py's ``AtariVectorEnv`` in SAME_STEP mode (what SB3's autoreset is): the
same seeds and actions must give the same observations, rewards, dones and terminal
observations.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import pytest

from palaestra import error
from palaestra.envs.atari.ale_engine import ALESettings
from palaestra.vec_env import AtariVecEnv, SubprocVecEnv, VecMonitor, make_atari_env
from palaestra.vec_env.atari_vec_env import AtariGameMonitor, atari_wrapper_settings
from palaestra.vec_env.env_util import _atari_engine

pytest.importorskip("ale_py")
ale_vector_env = pytest.importorskip("ale_py.vector_env")


def _reference(n: int, **settings: Any) -> Any:
    return ale_vector_env.AtariVectorEnv("breakout", n, autoreset_mode="SameStep", **settings)


def test_parity_with_ale_py_same_step() -> None:
    venv = AtariVecEnv("ALE/Breakout-v5", 2, max_num_frames_per_episode=300, life_loss_info=True)
    ref = _reference(
        2, repeat_action_probability=0.25, max_num_frames_per_episode=300, life_loss_info=True
    )
    assert venv.observation_space.shape == (4, 84, 84) and str(venv.action_space) == "Discrete(4)"
    venv.seed(5)
    obs = venv.reset()
    ref_obs, ref_info = ref.reset(seed=5)
    np.testing.assert_array_equal(obs, ref_obs)
    assert [info["lives"] for info in venv.reset_infos] == ref_info["lives"].tolist()
    rng = np.random.default_rng(5)
    seen = {"timeout": 0, "life": 0}
    for t in range(200):
        actions = rng.integers(0, 4, 2)
        obs, rewards, dones, infos = venv.step(actions)
        r_obs, r_rewards, r_terminated, r_truncated, r_info = ref.step(actions)
        np.testing.assert_array_equal(obs, r_obs, err_msg=str(t))
        assert rewards.dtype == np.float32 and dones.dtype == np.bool_
        np.testing.assert_array_equal(rewards, r_rewards)
        np.testing.assert_array_equal(dones, r_terminated | r_truncated)
        for i, info in enumerate(infos):
            assert info["lives"] == r_info["lives"][i] or dones[i]
            assert info["TimeLimit.truncated"] == bool(r_truncated[i] and not r_terminated[i])
            if not dones[i]:
                assert "terminal_observation" not in info
            elif r_truncated[i]:  # a new game: ale-py's final_obs is the last frame
                np.testing.assert_array_equal(info["terminal_observation"], r_info["final_obs"][i])
                seen["timeout"] += 1
            else:  # a lost life: the game goes on from this very frame
                np.testing.assert_array_equal(info["terminal_observation"], obs[i])
                seen["life"] += 1
    assert seen["timeout"] >= 2 and seen["life"] >= 2
    venv.close()
    venv.close()
    with pytest.raises(error.ClosedEnvironmentError, match="after a call to `close\\(\\)`"):
        venv.reset()


def test_vec_monitor_counts_episodes() -> None:
    venv = VecMonitor(AtariVecEnv("breakout", 2, max_num_frames_per_episode=120))
    venv.seed(0)
    venv.reset()
    returns = np.zeros(2)
    episodes = []
    for _ in range(60):
        _, rewards, dones, infos = venv.step(np.ones(2, dtype=np.int64))
        returns += rewards
        for i in np.flatnonzero(dones):
            episodes.append((infos[i]["episode"]["r"], infos[i]["episode"]["l"]))
            assert infos[i]["episode"]["r"] == returns[i]
            returns[i] = 0
    assert [length for _, length in episodes] == [30, 30, 30, 30]  # 120 frames / frameskip 4
    with pytest.raises(error.InvalidAction, match=r"Actions \[9\] of sub-environments \[0\]"):
        venv.step(np.array([9, 0]))
    venv.close()


def test_make_atari_env_native_route() -> None:
    """vec_env_cls=AtariVecEnv: ALE's preprocessing, SB3's shapes, Monitor's game stats."""
    venv = make_atari_env("BreakoutNoFrameskip-v4", n_envs=2, seed=3, vec_env_cls=AtariVecEnv)
    assert isinstance(venv, AtariGameMonitor) and isinstance(venv.venv, AtariVecEnv)
    assert venv.venv.spec.id == "BreakoutNoFrameskip-v4"
    expected = ALESettings(
        repeat_action_probability=0.0, stack_num=1, life_loss_info=True, reward_clipping=True
    )
    assert venv.venv.engine.settings == expected
    assert venv.observation_space.shape == (84, 84, 1)
    # The reference: the same ALE settings, unclipped, to read the games' scores.
    ref = _reference(2, stack_num=1, life_loss_info=True, reward_clipping=False)
    obs = venv.reset()
    np.testing.assert_array_equal(obs, ref.reset(seed=3)[0].reshape(2, 84, 84, 1))
    rng = np.random.default_rng(3)
    scores = np.zeros(2)
    frames = np.zeros(2, dtype=np.int64)
    games = 0
    for t in range(160):
        actions = rng.integers(0, 4, 2)
        obs, rewards, _, infos = venv.step(actions)
        r_obs, r_rewards, _, _, r_info = ref.step(actions)
        np.testing.assert_array_equal(obs, r_obs.reshape(2, 84, 84, 1), err_msg=str(t))
        np.testing.assert_array_equal(rewards, np.clip(r_rewards, -1, 1))
        scores += r_rewards
        for i in range(2):
            # A game over resets the game: its frame count starts again.
            game_over = bool(r_info["episode_frame_number"][i] < frames[i])
            assert ("episode" in infos[i]) == game_over, t
            if game_over:
                assert infos[i]["episode"]["r"] == scores[i]
                assert infos[i]["episode"]["l"] == infos[i]["episode_frame_number"]
                scores[i] = 0
                games += 1
        frames[:] = r_info["episode_frame_number"]
    assert games >= 1
    venv.close()


@pytest.mark.parametrize(
    ("env_id", "wrapper_kwargs", "env_kwargs", "reason"),
    [
        (lambda: None, {}, {}, "env_id is a callable"),
        ("CartPole-v1", {}, {}, "'CartPole-v1' is not an Atari id"),
        ("ALE/Breakout-v5", {}, {}, "the env skips frames itself"),
        ("BreakoutNoFrameskip-v4", {}, {"obs_type": "ram"}, r"env_kwargs \['obs_type'\]"),
        ("BreakoutNoFrameskip-v4", {"scale": 2}, {}, r"wrapper_kwargs \['scale'\] are not"),
        (
            "ALE/Breakout-v5",
            {"action_repeat_probability": 0.25},
            {"frameskip": 1},
            "both the env and the wrapper repeat actions",
        ),
    ],
)
def test_settings_that_do_not_map(
    env_id: Any, wrapper_kwargs: dict[str, Any], env_kwargs: dict[str, Any], reason: str
) -> None:
    mapped = atari_wrapper_settings(env_id, wrapper_kwargs, env_kwargs)
    assert isinstance(mapped, str)
    assert re.search(reason, mapped), mapped


def test_settings_that_map() -> None:
    wrapper_kwargs = {
        "noop_max": 0,
        "frame_skip": 2,
        "screen_size": 64,
        "terminal_on_life_loss": False,
        "clip_reward": False,
        "action_repeat_probability": 0.25,
    }
    env_kwargs = {"frameskip": 1, "repeat_action_probability": 0.0, "full_action_space": True}
    assert atari_wrapper_settings("ALE/Pong-v5", wrapper_kwargs, env_kwargs) == (
        "pong",
        ALESettings(
            repeat_action_probability=0.25,
            full_action_space=True,
            max_num_frames_per_episode=108_000,
            img_height=64,
            img_width=64,
            stack_num=1,
            frameskip=2,
            noop_max=0,
            life_loss_info=False,
            reward_clipping=False,
        ),
    )


def test_unmapped_settings_are_left_to_single_envs() -> None:
    with pytest.warns(UserWarning, match="the env skips frames itself .* SubprocVecEnv workers"):
        assert _atari_engine("ALE/Breakout-v5", 2, {}, {}, AtariVecEnv, 0) is None
    with pytest.warns(UserWarning, match=r"\['monitor_kwargs'\] need single envs"):
        engine = _atari_engine("PongNoFrameskip-v4", 2, {}, {}, AtariVecEnv, 0, ("monitor_kwargs",))
    assert engine is None
    assert _atari_engine("PongNoFrameskip-v4", 2, {}, {}, None, 0) is None  # the default: SB3's


@pytest.mark.slow
def test_unmapped_settings_fall_back_to_subprocess_workers(tmp_path: Any) -> None:
    with pytest.warns(UserWarning, match=r"\['monitor_dir'\] need single envs; running SB3's"):
        venv = make_atari_env(
            "BreakoutNoFrameskip-v4",
            n_envs=1,
            seed=0,
            monitor_dir=str(tmp_path),
            vec_env_cls=AtariVecEnv,
        )
    try:
        assert isinstance(venv, SubprocVecEnv)
        assert venv.reset().shape == (1, 84, 84, 1)
    finally:
        venv.close()


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="needs an Atari id such as 'ALE/Breakout-v5'"):
        AtariVecEnv("CartPole-v1")
    with pytest.raises(TypeError, match=r"AtariVecEnv got unexpected keyword arguments \['x'\]"):
        AtariVecEnv("breakout", 1, x=1)
    with pytest.raises(ValueError, match="frames_last needs stack_num=1, got 4"):
        AtariVecEnv("breakout", 1, frames_last=True)
