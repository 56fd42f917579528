"""Every Box2D id: check_env, Gymnasium's spec and spaces, seeding, close twice."""

from __future__ import annotations

import warnings

import pytest
from tests.envs.box2d.cases import BOX2D_IDS, id_params

import palaestra
from palaestra.utils.env_checker import check_env

pytest.importorskip("Box2D")


@pytest.mark.parametrize("env_id", id_params(BOX2D_IDS))
def test_check_env_passes_without_warnings(env_id: str) -> None:
    env = palaestra.make(env_id, render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    messages = [str(w.message) for w in caught]
    if env_id == "CarRacing-v3":  # Gymnasium's checker says the same of its CarRacing
        messages = [m for m in messages if "symmetric" not in m and "normalised" not in m]
    assert messages == []


@pytest.mark.parametrize("env_id", BOX2D_IDS)
def test_spec_and_spaces_match_gymnasium(env_id: str) -> None:
    gymnasium = pytest.importorskip("gymnasium")
    ours, ref = palaestra.spec(env_id), gymnasium.spec(env_id)
    assert ours.max_episode_steps == ref.max_episode_steps
    assert ours.reward_threshold == ref.reward_threshold
    assert ours.kwargs == ref.kwargs
    assert ours.entry_point.split(":")[1] == ref.entry_point.split(":")[1]
    env, ref_env = palaestra.make(env_id), gymnasium.make(env_id)
    assert repr(env.observation_space) == repr(ref_env.observation_space)
    assert repr(env.action_space) == repr(ref_env.action_space)
    assert env.unwrapped.metadata == ref_env.unwrapped.metadata


@pytest.mark.parametrize("env_id", id_params(BOX2D_IDS))
def test_seeding_is_deterministic_and_seeds_differ(env_id: str) -> None:
    def rollout(seed: int) -> bytes:
        env = palaestra.make(env_id)
        obs, _ = env.reset(seed=seed)
        env.action_space.seed(seed)
        frames = [obs.tobytes()]
        for _ in range(30):
            frames.append(env.step(env.action_space.sample())[0].tobytes())
        return b"".join(frames)

    assert rollout(1) == rollout(1)
    assert rollout(1) != rollout(2)


@pytest.mark.parametrize("env_id", BOX2D_IDS)
def test_every_box2d_id_is_registered_like_gymnasium(env_id: str) -> None:
    gymnasium = pytest.importorskip("gymnasium")
    box2d_ids = {i for i, s in gymnasium.registry.items() if "box2d" in str(s.entry_point)}
    assert box2d_ids == set(BOX2D_IDS)
    env = palaestra.make(env_id)
    env.reset(seed=0)
    env.close()
    env.close()  # twice is harmless
