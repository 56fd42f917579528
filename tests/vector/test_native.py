"""The native batches behind ``make_vec``: row i == a single env seeded ``seed + i``, and the
whole vector env == gymnasium's ``SyncVectorEnv`` of gymnasium envs, in every autoreset mode.

Short time limits (``max_episode_steps``) make every run cross several episode ends.
"""

from __future__ import annotations

import copy
import pickle

import gymnasium
import numpy as np
import pytest

import palaestra as gym
from palaestra.vector import BatchedVectorEnv, SyncVectorEnv

from .toys import assert_infos_equal

IDS = ["CartPole-v1", "MountainCar-v0", "MountainCarContinuous-v0", "Pendulum-v1", "Acrobot-v1"]
N, LIMIT, STEPS = 4, 25, 80


def _actions(env_id: str, rng: np.random.Generator) -> np.ndarray:
    if env_id in ("MountainCarContinuous-v0", "Pendulum-v1"):
        return rng.uniform(-2.5, 2.5, size=(N, 1)).astype(np.float32)  # out of range: clipped
    return rng.integers(0, 3 if env_id in ("MountainCar-v0", "Acrobot-v1") else 2, size=N)


def test_make_vec_returns_the_native_batch():
    envs = gym.make_vec("MountainCar-v0", num_envs=3)
    assert isinstance(envs, BatchedVectorEnv)
    assert repr(envs) == "BatchedVectorEnv(MountainCar-v0, num_envs=3)"
    assert str(envs.single_observation_space) == "Box([-1.2  -0.07], [0.6  0.07], (2,), float32)"
    assert str(envs.action_space) == "MultiDiscrete([3 3 3])"
    assert envs.observation_space.shape == (3, 2)
    sync = gym.make_vec("MountainCar-v0", num_envs=3, vectorization_mode="sync")
    assert isinstance(sync, SyncVectorEnv)
    assert envs.observation_space == sync.observation_space
    assert envs.action_space == sync.action_space


@pytest.mark.parametrize("env_id", IDS)
def test_rows_are_single_envs_seeded_seed_plus_i(env_id):
    envs = gym.make_vec(env_id, num_envs=N, max_episode_steps=LIMIT)
    singles = [gym.make(env_id, max_episode_steps=LIMIT) for _ in range(N)]
    obs, _ = envs.reset(seed=123)
    expected = [s.reset(seed=123 + i)[0] for i, s in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(expected))
    ended = [False] * N
    rng = np.random.default_rng(1)
    for _ in range(STEPS):
        actions = _actions(env_id, rng)
        obs, rew, term, trunc, infos = envs.step(actions)
        assert infos == {}
        for i, single in enumerate(singles):
            if ended[i]:  # NEXT_STEP: this step is the reset
                o, r, te, tr = single.reset()[0], 0.0, False, False
            else:
                o, r, te, tr, _ = single.step(actions[i])
            ended[i] = te or tr
            np.testing.assert_array_equal(obs[i], o)
            assert (rew[i], term[i], trunc[i]) == (r, te, tr)
    assert rew.dtype == np.float64 and term.dtype == np.bool_ and obs.dtype == np.float32


@pytest.mark.parametrize("mode", ["NextStep", "SameStep", "Disabled"])
@pytest.mark.parametrize("env_id", ["CartPole-v1", "MountainCar-v0", "Pendulum-v1"])
def test_native_and_sync_match_gymnasium_sync_vector_env(env_id, mode):
    ours = [
        gym.make_vec(env_id, N, max_episode_steps=LIMIT, autoreset_mode=mode),
        gym.make_vec(
            env_id,
            N,
            vectorization_mode="sync",
            vector_kwargs={"autoreset_mode": mode},
            max_episode_steps=LIMIT,
        ),
    ]
    theirs = gymnasium.vector.SyncVectorEnv(
        [lambda: gymnasium.make(env_id, max_episode_steps=LIMIT) for _ in range(N)],
        autoreset_mode=gymnasium.vector.AutoresetMode(mode),
    )
    ref = theirs.reset(seed=5)
    for env in ours:
        got = env.reset(seed=5)
        np.testing.assert_array_equal(got[0], ref[0])
    rng = np.random.default_rng(2)
    for _ in range(STEPS):
        actions = _actions(env_id, rng)
        ref = theirs.step(actions)
        for env in ours:
            got = env.step(actions)
            for a, b in zip(got[:4], ref[:4]):
                np.testing.assert_array_equal(a, b)
                assert a.dtype == b.dtype
            assert_infos_equal(got[4], ref[4])
        done = ref[2] | ref[3]
        if mode == "Disabled" and done.any():
            ref_obs, _ = theirs.reset(options={"reset_mask": done.copy()})
            for env in ours:
                obs, _ = env.reset(options={"reset_mask": done.copy()})
                np.testing.assert_array_equal(obs, ref_obs)


def test_gymnasium_own_cartpole_vector_env_does_not_match_single_envs_but_ours_does():
    ours = gym.make_vec("CartPole-v1", num_envs=3)
    theirs = gymnasium.make_vec("CartPole-v1", num_envs=3, vectorization_mode="vector_entry_point")
    singles = np.stack([gymnasium.make("CartPole-v1").reset(seed=9 + i)[0] for i in range(3)])
    np.testing.assert_array_equal(ours.reset(seed=9)[0], singles)
    assert not np.array_equal(theirs.reset(seed=9)[0], singles)


def test_reset_options_and_partial_reset_keep_other_rows():
    envs = gym.make_vec("MountainCar-v0", num_envs=3)
    obs, _ = envs.reset(seed=0, options={"low": -0.3, "high": -0.2})
    assert ((obs[:, 0] >= -0.3) & (obs[:, 0] <= -0.2)).all()
    before = envs.step(np.array([2, 2, 2]))[0]
    after, _ = envs.reset(options={"reset_mask": np.array([False, True, False])})
    np.testing.assert_array_equal(after[[0, 2]], before[[0, 2]])
    assert after[1, 1] == 0.0


def test_call_and_attrs_on_native():
    envs = gym.make_vec("CartPole-v1", num_envs=2)
    envs.reset(seed=4)
    assert envs.np_random_seed == (4, 5)
    assert envs.get_attr("num_envs") == (2, 2)
    envs.set_attr("sutton_barto_reward", True)
    with pytest.raises(ValueError, match="share their attributes"):
        envs.set_attr("sutton_barto_reward", [True, False])


@pytest.mark.parametrize("env_id", ["CartPole-v1", "Pendulum-v1", "Acrobot-v1"])
def test_native_vector_envs_copy_and_continue(env_id: str) -> None:
    """Issue 26: a copied batch writes its physics into its own state (views are rebuilt), and
    its pre-drawn reset numbers stay its generator's, across autoresets."""
    envs = gym.make_vec(env_id, num_envs=3)
    envs.reset(seed=0)
    envs.action_space.seed(0)
    for _ in range(30):
        envs.step(envs.action_space.sample())
    clones = [copy.deepcopy(envs), pickle.loads(pickle.dumps(envs))]
    actions = [envs.action_space.sample() for _ in range(250)]  # through several autoresets
    want = [envs.step(a) for a in actions]
    for clone in clones:
        for action, (obs, reward, terminated, truncated, _) in zip(actions, want):
            got = clone.step(action)
            np.testing.assert_array_equal(got[0], obs)
            np.testing.assert_array_equal(got[1], reward)
            np.testing.assert_array_equal(got[2] | got[3], terminated | truncated)
