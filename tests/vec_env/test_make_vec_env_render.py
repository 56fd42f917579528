"""``make_vec_env(id)`` as SB3's (issue 26): its envs have ``render_mode="rgb_array"``, so SB3's
video recipe ``VecVideoRecorder(make_vec_env(id), ...)`` records, and ``env_kwargs`` may hold
``make``'s ``max_episode_steps``. Built-in ids keep their native batch: each row is drawn from
the batch's state, frame for frame what the single env in that state draws."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("torch")

import gymnasium
from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env

from palaestra.algos.env_util import make_vec_env
from palaestra.algos.vec_env import DummyVecEnv, VecVideoRecorder
from palaestra.vec_env.engine_vec_env import BatchedVecEnv

# Every built-in id with a native batch.
NATIVE_IDS = [
    "CartPole-v1",
    "MountainCar-v0",
    "MountainCarContinuous-v0",
    "Pendulum-v1",
    "Acrobot-v1",
    "Blackjack-v1",
    "FrozenLake-v1",
    "CliffWalking-v1",
    "Taxi-v4",
]


def _batch(venv: Any) -> BatchedVecEnv:
    inner = venv.venv
    assert isinstance(inner, BatchedVecEnv), inner
    return inner


@pytest.mark.parametrize("env_id", NATIVE_IDS)
def test_make_vec_env_renders_rgb_array_as_sb3(env_id: str) -> None:
    ours = make_vec_env(env_id, n_envs=2, seed=0)
    theirs = sb3_make_vec_env(env_id, n_envs=2, seed=0)
    _batch(ours)  # still the native batch
    assert ours.render_mode == theirs.render_mode == "rgb_array"
    assert ours.metadata["render_modes"] == theirs.metadata["render_modes"]
    fps = ours.get_attr("metadata")[0]["render_fps"]
    assert fps == theirs.get_attr("metadata")[0]["render_fps"]
    ours.reset()
    theirs.reset()
    images, their_images = ours.get_images(), theirs.get_images()
    assert [i.shape for i in images] == [i.shape for i in their_images]
    assert [i.dtype for i in images] == [i.dtype for i in their_images]
    tiled = ours.render()
    assert tiled is not None and tiled.shape == theirs.render().shape
    assert ours.render(mode="human") is not None  # SB3: human over rgb_array envs tiles too
    ours.close()
    theirs.close()


@pytest.mark.parametrize("env_id", NATIVE_IDS)
def test_each_row_is_drawn_as_the_single_env_draws_it(env_id: str) -> None:
    # Episodes of 4 steps, so rows are reset (no last action) and step again on the way.
    kwargs = {"max_episode_steps": 4}
    native = make_vec_env(env_id, n_envs=3, seed=5, env_kwargs=kwargs)
    singles = make_vec_env(env_id, n_envs=3, seed=5, env_kwargs=kwargs, vec_env_cls=DummyVecEnv)
    _batch(native)
    assert singles.render_mode == "rgb_array"
    native.reset()
    singles.reset()
    space = native.action_space
    space.seed(1)
    for step in range(11):
        for a, b in zip(native.get_images(), singles.get_images()):
            assert np.array_equal(a, b), f"{env_id}: a frame differs at step {step}"
        actions = np.stack([space.sample() for _ in range(3)])
        native.step(actions)
        singles.step(actions)
    assert np.array_equal(native.render(), singles.render())
    ours, theirs = (v.env_method("render", indices=[1]) for v in (native, singles))
    assert len(ours) == len(theirs) == 1 and np.array_equal(ours[0], theirs[0])


def test_render_mode_none_in_env_kwargs_keeps_no_frames() -> None:
    ours = make_vec_env("CartPole-v1", n_envs=2, env_kwargs={"render_mode": None})
    theirs = sb3_make_vec_env("CartPole-v1", n_envs=2, env_kwargs={"render_mode": None})
    _batch(ours)
    assert ours.render_mode is theirs.render_mode is None
    ours.reset()
    assert ours.get_images() == [None, None]
    with pytest.warns(UserWarning, match="no `render_mode` was passed"):
        assert ours.render() is None


def test_sb3s_video_recipe_records(tmp_path: Path) -> None:
    # SB3's documented recipe (guide/examples "Record a Video"), on make_vec_env's envs.
    venv = VecVideoRecorder(
        make_vec_env("CartPole-v1", n_envs=1, seed=0),
        str(tmp_path),
        record_video_trigger=lambda x: x == 0,
        video_length=20,
        name_prefix="cartpole",
    )
    venv.reset()
    for _ in range(21):
        venv.step(np.array([venv.action_space.sample()]))
    venv.close()
    videos = sorted(p.name for p in tmp_path.iterdir())
    assert videos == ["cartpole-step-0-to-step-20.mp4"]
    assert (tmp_path / videos[0]).stat().st_size > 0


@pytest.mark.parametrize("env_id", ["CartPole-v1", "Pendulum-v1", "FrozenLake-v1"])
def test_max_episode_steps_in_env_kwargs_as_sb3(env_id: str) -> None:
    # SB3 passes env_kwargs to gym.make, whose max_episode_steps sets the TimeLimit.
    ours = make_vec_env(env_id, n_envs=2, seed=3, env_kwargs={"max_episode_steps": 5})
    theirs = sb3_make_vec_env(env_id, n_envs=2, seed=3, env_kwargs={"max_episode_steps": 5})
    _batch(ours)
    assert ours.get_attr("spec")[0].max_episode_steps == 5
    ours.reset()
    theirs.reset()
    done_at: list[list[bool]] = [[], []]
    for _ in range(12):
        actions = np.zeros((2, *ours.action_space.shape), ours.action_space.dtype)
        _, _, dones, infos = ours.step(actions)
        _, _, their_dones, their_infos = theirs.step(actions)
        done_at[0].append(dones.tolist())
        done_at[1].append(their_dones.tolist())
        assert [i["TimeLimit.truncated"] for i in infos] == [
            i["TimeLimit.truncated"] for i in their_infos
        ]
    assert done_at[0] == done_at[1]
    assert any(any(d) for d in done_at[0])


def test_max_episode_steps_minus_one_is_no_time_limit() -> None:
    venv = make_vec_env("Pendulum-v1", n_envs=1, env_kwargs={"max_episode_steps": -1})
    assert _batch(venv).engine.max_episode_steps is None
    venv.reset()
    for _ in range(250):  # past Pendulum's 200
        _, _, dones, _ = venv.step(np.zeros((1, 1), np.float32))
        assert not dones.any()


def test_gymnasium_sees_the_same_limit() -> None:
    # The reference for what make's max_episode_steps means.
    assert gymnasium.make("CartPole-v1", max_episode_steps=5).spec.max_episode_steps == 5
    assert (
        make_vec_env("CartPole-v1", env_kwargs={"max_episode_steps": 5})
        .get_attr("spec")[0]
        .max_episode_steps
        == 5
    )


def test_a_human_render_mode_builds_real_envs() -> None:
    # A window per env is not a batch's to open: SB3's DummyVecEnv of real envs instead.
    venv = make_vec_env("CartPole-v1", n_envs=1, env_kwargs={"render_mode": "human"})
    theirs = sb3_make_vec_env("CartPole-v1", n_envs=1, env_kwargs={"render_mode": "human"})
    assert type(venv).__name__ == type(theirs).__name__ == "DummyVecEnv"
    assert venv.render_mode == theirs.render_mode == "human"
    venv.close()
    theirs.close()
