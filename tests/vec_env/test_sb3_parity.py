"""The SB3 face against stable-baselines3 itself, on the same seeds and actions.

``make_vec_env`` (native batch under a VecMonitor) and ``DummyVecEnv`` of palaestra envs must
give SB3's ``make_vec_env`` / ``DummyVecEnv`` over gymnasium envs: observations, rewards and
their dtype, dones, ``TimeLimit.truncated``, ``terminal_observation``, ``episode`` r/l, and
``reset_infos``.
"""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from stable_baselines3.common import env_util as sb3_util
from stable_baselines3.common import vec_env as sb3

import palaestra as gym
from palaestra.vec_env import BatchedVecEnv, DummyVecEnv, VecMonitor, make_vec_env

N = 4


def _compare_steps(ours, theirs, actions_fn, steps):
    np.testing.assert_array_equal(ours.reset(), theirs.reset())
    assert ours.reset_infos == theirs.reset_infos
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(steps):
        actions = actions_fn(rng)
        o1, r1, d1, i1 = ours.step(actions)
        o2, r2, d2, i2 = theirs.step(actions)
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)
        assert r1.dtype == r2.dtype and d1.dtype == d2.dtype
        np.testing.assert_array_equal(d1, d2)
        assert len(i1) == len(i2) == len(o1)
        for a, b in zip(i1, i2):
            assert sorted(a) == sorted(b)  # VecMonitor adds "episode" last, Monitor first
            assert a["TimeLimit.truncated"] == b["TimeLimit.truncated"]
            if "terminal_observation" in b:
                np.testing.assert_array_equal(a["terminal_observation"], b["terminal_observation"])
            if "episode" in b:
                ends += 1
                assert a["episode"]["r"] == b["episode"]["r"]
                assert a["episode"]["l"] == b["episode"]["l"]
        assert ours.reset_infos == theirs.reset_infos
    return ends


@pytest.mark.parametrize(
    ("env_id", "n_actions", "steps"), [("MountainCar-v0", 3, 450), ("CartPole-v1", 2, 200)]
)
def test_make_vec_env_native_matches_sb3(env_id, n_actions, steps):
    ours = make_vec_env(env_id, n_envs=N, seed=11)
    assert isinstance(ours, VecMonitor) and isinstance(ours.venv, BatchedVecEnv)
    theirs = sb3_util.make_vec_env(env_id, n_envs=N, seed=11)
    ends = _compare_steps(ours, theirs, lambda rng: rng.integers(0, n_actions, size=N), steps)
    assert ends >= N  # every env finished at least one episode


def test_dummy_vec_env_matches_sb3_with_monitor_and_start_index():
    ours = make_vec_env("CartPole-v1", n_envs=N, seed=3, start_index=2, vec_env_cls=DummyVecEnv)
    theirs = sb3_util.make_vec_env("CartPole-v1", n_envs=N, seed=3, start_index=2)
    assert isinstance(ours, DummyVecEnv)
    ends = _compare_steps(ours, theirs, lambda rng: rng.integers(0, 2, size=N), 120)
    assert ends >= N
    # Monitor-wrapped, like SB3's
    from palaestra.wrappers.monitor import Monitor

    assert ours.env_is_wrapped(Monitor) == [True] * N
    assert ours.get_attr("render_mode") == theirs.get_attr("render_mode") == ["rgb_array"] * N


def test_continuous_env_and_options_and_seed():
    ours = DummyVecEnv([lambda: gym.make("Pendulum-v1")] * 2)
    theirs = sb3.DummyVecEnv([lambda: gymnasium.make("Pendulum-v1")] * 2)
    for venv in (ours, theirs):
        venv.seed(5)
        venv.set_options({"x_init": 0.5, "y_init": 0.5})
    _compare_steps(
        ours, theirs, lambda rng: rng.uniform(-2, 2, size=(2, 1)).astype(np.float32), 210
    )


def test_methods_with_indices():
    venv = DummyVecEnv([lambda: gym.make("MountainCar-v0")] * 3)
    venv.reset()
    assert venv.get_attr("goal_position", indices=[0, 2]) == [0.5, 0.5]
    venv.set_attr("goal_position", 0.2, indices=1)
    assert venv.get_attr("goal_position") == [0.5, 0.2, 0.5]
    assert venv.env_method("get_wrapper_attr", "max_speed", indices=0) == [0.07]
    assert venv.has_attr("goal_position") and not venv.has_attr("nope")
    native = make_vec_env("MountainCar-v0", n_envs=3)
    assert native.get_attr("num_envs", indices=[0, 1]) == [3, 3]
    native.close()
    native.close()


def test_make_vec_env_paths():
    from palaestra.wrappers.monitor import Monitor
    from palaestra.wrappers.transform_reward import ClipReward

    native = make_vec_env("MountainCar-v0", n_envs=2, env_kwargs={"goal_velocity": 0.01})
    assert isinstance(native.venv, BatchedVecEnv)
    assert native.venv.batch.params.goal_velocity == 0.01
    rendering = make_vec_env("CartPole-v1", n_envs=2, env_kwargs={"render_mode": "rgb_array"})
    assert isinstance(rendering.venv, BatchedVecEnv)  # the batch draws its rows (issue 26)
    rendering.reset()
    assert rendering.get_images()[0].shape == (400, 600, 3)
    assert rendering.render().shape == (800, 600, 3)  # 2 frames tiled as SB3 tiles them
    wrapped = make_vec_env(
        "CartPole-v1", n_envs=2, wrapper_class=ClipReward, wrapper_kwargs={"max_reward": 0.5}
    )
    assert isinstance(wrapped, DummyVecEnv) and wrapped.env_is_wrapped(Monitor) == [True, True]
    wrapped.reset()
    assert wrapped.step(np.array([0, 1]))[1].tolist() == [0.5, 0.5]
    from_callable = make_vec_env(lambda: gym.make("Pendulum-v1"), n_envs=2, seed=0)
    assert isinstance(from_callable, DummyVecEnv)
    assert from_callable.reset().shape == (2, 3)


@pytest.mark.parametrize("env_id", ["Pendulum-v1", "MountainCarContinuous-v0"])
def test_one_env_takes_an_action_without_the_batch_axis_as_sb3(env_id):
    """SB3's DummyVecEnv of one env steps ``actions[0]``, so it takes an action without the
    batch axis (and hands its env a scalar, which Gymnasium's Pendulum cannot index); palaestra
    adds the axis: the same step as SB3's for the batched action."""
    ours = DummyVecEnv([lambda: gym.make(env_id)])
    theirs = sb3.DummyVecEnv([lambda: gymnasium.make(env_id)])
    ours.seed(3), theirs.seed(3)
    np.testing.assert_allclose(ours.reset(), theirs.reset(), atol=1e-6)
    for value in (0.5, -0.25, 1.0):
        action = np.array([value], dtype=np.float32)  # shape (1,): one action, no batch axis
        o1, r1, d1, _ = ours.step(action)
        o2, r2, d2, _ = theirs.step(action[None])
        assert o1.shape == o2.shape == (1, *ours.observation_space.shape)
        np.testing.assert_allclose(o1, o2, atol=1e-5)
        np.testing.assert_allclose(r1, r2, atol=1e-5)
        np.testing.assert_array_equal(d1, d2)
    with pytest.raises(ValueError, match=r"Expected a batch of actions of shape \(2, 1\)"):
        two = DummyVecEnv([lambda: gym.make(env_id), lambda: gym.make(env_id)])
        two.reset()
        two.step(np.array([0.5], dtype=np.float32))  # two envs: still a batch needed
