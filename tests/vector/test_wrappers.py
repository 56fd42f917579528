"""Vector wrappers against gymnasium's ``gymnasium.wrappers.vector`` on the same steps."""

from __future__ import annotations

from functools import partial

import gymnasium
import gymnasium.wrappers.vector as gym_vw
import numpy as np
import pytest

import palaestra as gym
import palaestra.wrappers.vector as vw
from palaestra.error import InvalidBound
from palaestra.vector import SyncVectorEnv

from .toys import assert_infos_equal, gym_counter, pal_counter

N = 3


def _cartpoles(mode: str = "NextStep"):
    ours = gym.make_vec("CartPole-v1", N, max_episode_steps=20, autoreset_mode=mode)
    theirs = gymnasium.vector.SyncVectorEnv(
        [lambda: gymnasium.make("CartPole-v1", max_episode_steps=20)] * N,
        autoreset_mode=gymnasium.vector.AutoresetMode(mode),
    )
    return ours, theirs


def _run(ours, theirs, steps=60, compare_infos=True, rtol=0.0):
    a, b = ours.reset(seed=1), theirs.reset(seed=1)
    np.testing.assert_allclose(a[0], b[0], rtol=rtol)
    rng = np.random.default_rng(0)
    for _ in range(steps):
        actions = rng.integers(0, 2, size=N)
        a, b = ours.step(actions), theirs.step(actions)
        for x, y in zip(a[:4], b[:4]):
            np.testing.assert_allclose(x, y, rtol=rtol)
        if compare_infos:
            yield a[4], b[4]


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_record_episode_statistics(mode):
    ours, theirs = _cartpoles(mode)
    ours, theirs = vw.RecordEpisodeStatistics(ours), gym_vw.RecordEpisodeStatistics(theirs)
    seen = 0
    for a, b in _run(ours, theirs):
        assert ("episode" in a) == ("episode" in b)
        if "episode" in b:
            seen += 1
            np.testing.assert_array_equal(a["_episode"], b["_episode"])
            np.testing.assert_array_equal(a["episode"]["r"], b["episode"]["r"])
            np.testing.assert_array_equal(a["episode"]["l"], b["episode"]["l"])
    assert seen and ours.episode_count == theirs.episode_count
    assert list(ours.return_queue) == list(theirs.return_queue)


def test_normalize_observation_and_reward():
    ours, theirs = _cartpoles()
    ours = vw.NormalizeReward(vw.NormalizeObservation(ours), gamma=0.95)
    theirs = gym_vw.NormalizeReward(gym_vw.NormalizeObservation(theirs), gamma=0.95)
    for _ in _run(ours, theirs, rtol=1e-6):
        pass
    assert ours.single_observation_space == gym.spaces.Box(-np.inf, np.inf, (4,), np.float32)
    with pytest.raises(ValueError, match="NEXT_STEP"):
        vw.NormalizeObservation(gym.make_vec("CartPole-v1", 2, autoreset_mode="SameStep"))
    with pytest.raises(InvalidBound):
        vw.NormalizeReward(gym.make_vec("CartPole-v1", 2), gamma=2.0)


def test_clip_and_transform_reward_and_observation():
    ours, theirs = _cartpoles()
    ours = vw.ClipReward(vw.TransformReward(ours, lambda r: r * 3 - 1), 0.0, 1.5)
    theirs = gym_vw.ClipReward(gym_vw.TransformReward(theirs, lambda r: r * 3 - 1), 0.0, 1.5)
    ours = vw.TransformObservation(ours, lambda o: o * 2)
    theirs = gym_vw.TransformObservation(theirs, lambda o: o * 2)
    for _ in _run(ours, theirs):
        pass
    with pytest.raises(InvalidBound):
        vw.ClipReward(gym.make_vec("CartPole-v1", 2))


def test_vectorize_transforms_and_dict_info_to_list():
    from palaestra.wrappers.transform_observation import TransformObservation as SingleObs
    from palaestra.wrappers.transform_reward import TransformReward as SingleReward

    ours = SyncVectorEnv([partial(pal_counter, n) for n in (2, 3, 4)])
    theirs = gymnasium.vector.SyncVectorEnv([partial(gym_counter, n) for n in (2, 3, 4)])
    ours = vw.VectorizeTransformObservation(
        ours, SingleObs, func=lambda o: o + 1, observation_space=None
    )
    theirs = gym_vw.VectorizeTransformObservation(
        theirs,
        gymnasium.wrappers.TransformObservation,
        func=lambda o: o + 1,
        observation_space=None,
    )
    ours = vw.VectorizeTransformReward(ours, SingleReward, func=lambda r: r * 10)
    theirs = gym_vw.VectorizeTransformReward(
        theirs, gymnasium.wrappers.TransformReward, func=lambda r: r * 10
    )
    ours, theirs = vw.DictInfoToList(ours), gym_vw.DictInfoToList(theirs)
    a, b = ours.reset(seed=0), theirs.reset(seed=0)
    assert a[1] == b[1]
    for _ in range(8):
        actions = np.array([0, 1, 2])
        a, b = ours.step(actions), theirs.step(actions)
        for x, y in zip(a[:4], b[:4]):
            np.testing.assert_array_equal(x, y)
        assert len(a[4]) == len(b[4]) == 3
        for x, y in zip(a[4], b[4]):
            assert_infos_equal(x, y)


def test_vectorize_transform_action():
    from palaestra.wrappers.transform_action import TransformAction as SingleAct

    envs = vw.VectorizeTransformAction(
        SyncVectorEnv([partial(pal_counter, 5)] * 2),
        SingleAct,
        func=lambda a: 2 - a,
        action_space=None,
    )
    envs.reset(seed=0)
    obs = envs.step(np.array([0, 2]))[0]
    start = envs.reset(seed=0)[0]
    envs.step(np.array([0, 2]))
    np.testing.assert_array_equal(obs[:, 0] - start[:, 0], [2, 0])
    batch = vw.TransformAction(gym.make_vec("CartPole-v1", 2), lambda a: 1 - a)
    batch.reset(seed=0)
    batch.step(np.array([0, 1]))
