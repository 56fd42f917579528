"""VecNormalize, VecFrameStack, VecTransposeImage and VecMonitor against SB3's."""

from __future__ import annotations

import re

import gymnasium
import numpy as np
import pytest
from stable_baselines3.common import vec_env as sb3

import palaestra as gym
from palaestra.vec_env import (
    DummyVecEnv,
    VecFrameStack,
    VecMonitor,
    VecNormalize,
    VecTransposeImage,
    make_vec_env,
)


def _pair(env_id: str, n: int = 3):
    ours = DummyVecEnv([lambda: gym.make(env_id)] * n)
    theirs = sb3.DummyVecEnv([lambda: gymnasium.make(env_id)] * n)
    ours.seed(0)
    theirs.seed(0)
    return ours, theirs


def _run_pair(ours, theirs, steps, n_actions=2, n=3, check_terminal=True):
    np.testing.assert_allclose(ours.reset(), theirs.reset(), rtol=1e-6, atol=1e-6)
    rng = np.random.default_rng(0)
    for _ in range(steps):
        actions = rng.integers(0, n_actions, size=n)
        o1, r1, d1, i1 = ours.step(actions)
        o2, r2, d2, i2 = theirs.step(actions)
        np.testing.assert_allclose(o1, o2, rtol=1e-5, atol=1e-6)
        np.testing.assert_allclose(r1, r2, rtol=1e-5, atol=1e-7)
        np.testing.assert_array_equal(d1, d2)
        for a, b in zip(i1, i2):
            if check_terminal and "terminal_observation" in b:
                np.testing.assert_allclose(
                    a["terminal_observation"], b["terminal_observation"], rtol=1e-5, atol=1e-6
                )


def test_vec_normalize_matches_sb3():
    ours, theirs = _pair("CartPole-v1")
    ours = VecNormalize(ours, gamma=0.9, clip_obs=5.0)
    theirs = sb3.VecNormalize(theirs, gamma=0.9, clip_obs=5.0)
    _run_pair(ours, theirs, 150)
    np.testing.assert_allclose(ours.obs_rms.mean, theirs.obs_rms.mean, rtol=1e-9)
    np.testing.assert_allclose(ours.ret_rms.var, theirs.ret_rms.var, rtol=1e-9)
    np.testing.assert_allclose(ours.get_original_obs(), theirs.get_original_obs())
    np.testing.assert_allclose(ours.get_original_reward(), theirs.get_original_reward())


def test_vec_normalize_save_load_without_pickle(tmp_path):
    venv = VecNormalize(make_vec_env("MountainCar-v0", n_envs=2, seed=0), norm_reward=False)
    venv.reset()
    for _ in range(50):
        venv.step(np.array([2, 0]))
    path = tmp_path / "vecnormalize.npz"
    venv.save(path)
    loaded = VecNormalize.load(path, make_vec_env("MountainCar-v0", n_envs=2, seed=0))
    np.testing.assert_array_equal(loaded.obs_rms.mean, venv.obs_rms.mean)
    np.testing.assert_array_equal(loaded.obs_rms.var, venv.obs_rms.var)
    assert loaded.obs_rms.count == venv.obs_rms.count
    assert (loaded.norm_reward, loaded.gamma) == (False, venv.gamma)
    obs = np.array([[-0.5, 0.01]], dtype=np.float32)
    np.testing.assert_array_equal(loaded.normalize_obs(obs), venv.normalize_obs(obs))
    with np.load(path, allow_pickle=False) as data:  # plain arrays only
        assert set(data.files) == {"settings", "obs_mean", "obs_var", "ret_mean", "ret_var"}


def test_vec_normalize_refuses_bad_files(tmp_path):
    bad = tmp_path / "x.npz"
    bad.write_bytes(b"\x80\x04not a numpy file")  # starts like a pickle (SB3's format)
    with pytest.raises(ValueError, match="is a pickle"):
        VecNormalize.load(bad, make_vec_env("MountainCar-v0", n_envs=1))
    bad.write_bytes(b"neither a zip nor a pickle")
    with pytest.raises(ValueError, match="not a palaestra VecNormalize file"):
        VecNormalize.load(bad, make_vec_env("MountainCar-v0", n_envs=1))
    other = tmp_path / "y.npz"
    VecNormalize(make_vec_env("CartPole-v1", n_envs=1)).save(other)
    with pytest.raises(ValueError, match="shape"):
        VecNormalize.load(other, make_vec_env("MountainCar-v0", n_envs=1))


def test_vec_frame_stack_matches_sb3():
    ours, theirs = _pair("CartPole-v1")
    ours, theirs = VecFrameStack(ours, 3), sb3.VecFrameStack(theirs, 3)
    assert ours.observation_space.shape == theirs.observation_space.shape == (12,)
    _run_pair(ours, theirs, 80)


def test_vec_frame_stack_channels_first_images():
    venv = DummyVecEnv([lambda: gym.make("CartPole-v1")] * 2)
    with pytest.raises(ValueError, match="channels_order"):
        VecFrameStack(venv, 2, channels_order="middle")


@pytest.mark.parametrize(
    ("n_stack", "exc", "match"),
    [
        ("4", TypeError, "n_stack must be a positive integer, got '4' (str)"),
        (2.7, TypeError, "n_stack must be a positive integer, got 2.7 (float)"),
        (True, TypeError, "n_stack must be a positive integer, got True (bool)"),
        (None, TypeError, "n_stack must be a positive integer, got None (NoneType)"),
        (0, ValueError, "n_stack must be a positive integer, got 0"),
        (-2, ValueError, "n_stack must be a positive integer, got -2"),
    ],
)
def test_vec_frame_stack_refuses_a_bad_n_stack(n_stack, exc, match):
    # SB3 accepts "4" and 2.7 and fails later in numpy, or stacks 2.7 frames as 2.
    venv = DummyVecEnv([lambda: gym.make("CartPole-v1")] * 2)
    with pytest.raises(exc, match=f"^{re.escape(match)}$"):
        VecFrameStack(venv, n_stack)


def test_vec_frame_stack_larger_than_memory_is_refused_before_allocating(monkeypatch):
    # 2**62 frames used to crash the interpreter inside np.repeat (a segfault, no exception).
    import palaestra.vec_env.image as image

    venv = DummyVecEnv([lambda: gym.make("CartPole-v1")] * 2)
    expected = (
        r"^n_stack=4611686018427387904 would need 295,147,905,179,352,825,856 bytes for the "
        r"stacked observations \(64 per frame\), more than this machine's [\d,]+ bytes of memory$"
    )
    with pytest.raises(ValueError, match=expected):
        VecFrameStack(venv, 2**62)
    monkeypatch.setattr(image, "physical_memory", lambda: 64 * 1000)
    with pytest.raises(ValueError, match="n_stack=1001 would need 64,064 bytes"):
        VecFrameStack(venv, 1001)
    assert VecFrameStack(venv, 1000).observation_space.shape == (4000,)
    monkeypatch.setattr(image, "physical_memory", lambda: None)  # the OS does not say
    with pytest.raises(ValueError, match="more than this machine's address space"):
        VecFrameStack(venv, 2**62)


class _ImageEnv(gym.Env):
    def __init__(self):
        from palaestra import spaces

        self.observation_space = spaces.Box(0, 255, (6, 5, 3), np.uint8)
        self.action_space = spaces.Discrete(2)
        self.t = 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return np.full((6, 5, 3), self.t, np.uint8), {}

    def step(self, action):
        self.t += 1
        obs = np.arange(90, dtype=np.uint8).reshape(6, 5, 3) + self.t
        return obs, 1.0, self.t >= 3, False, {}


def test_vec_transpose_image_and_image_frame_stack():
    venv = VecTransposeImage(DummyVecEnv([_ImageEnv] * 2))
    assert venv.observation_space.shape == (3, 6, 5)
    assert venv.reset().shape == (2, 3, 6, 5)
    for _ in range(3):
        _, _, dones, infos = venv.step(np.array([0, 1]))
    assert dones.all() and infos[0]["terminal_observation"].shape == (3, 6, 5)
    stacked = VecFrameStack(DummyVecEnv([_ImageEnv] * 2), 4)
    assert stacked.observation_space.shape == (6, 5, 12)
    assert stacked.reset().shape == (2, 6, 5, 12)
    with pytest.raises(ValueError, match="uint8 images"):
        VecTransposeImage(DummyVecEnv([lambda: gym.make("CartPole-v1")]))


def test_vec_monitor_writes_episodes(tmp_path):
    from palaestra.wrappers.monitor import get_monitor_files, read_monitor_file

    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0, monitor_dir=str(tmp_path))
    assert isinstance(venv, VecMonitor)
    venv.reset()
    episodes = 0
    for _ in range(100):
        _, _, dones, infos = venv.step(np.array([1, 1]))
        for done, info in zip(dones, infos):
            if done:
                episodes += 1
                assert set(info["episode"]) == {"r", "l", "t"}
                assert info["episode"]["r"] == info["episode"]["l"]
    venv.close()
    assert episodes >= 2
    # One file per env, as SB3's Monitor per env writes (0.monitor.csv, 1.monitor.csv).
    paths = sorted(get_monitor_files(str(tmp_path)))
    assert [p.rsplit("/", 1)[1] for p in paths] == ["0.monitor.csv", "1.monitor.csv"]
    total = 0
    for path in paths:
        header, columns = read_monitor_file(path)
        assert header["env_id"] == "CartPole-v1"
        total += len(columns["r"])
    assert total == episodes
