"""SB3's vec_env names at ``palaestra.vec_env`` with SB3's behaviour, side by side.

``VecCheckNan``, ``VecExtractDictObs``, ``StackedObservations``, ``VecVideoRecorder`` and
``RunningMeanStd.combine``/``copy`` (issue 16, "public names users call").
"""

from __future__ import annotations

import warnings

import gymnasium
import numpy as np
import pytest
from stable_baselines3.common import vec_env as sb3
from stable_baselines3.common.running_mean_std import RunningMeanStd as SB3RunningMeanStd

import palaestra as gym
from palaestra import spaces
from palaestra.vec_env import (
    DummyVecEnv,
    StackedObservations,
    VecCheckNan,
    VecExtractDictObs,
    VecVideoRecorder,
)
from palaestra.wrappers.running_mean_std import RunningMeanStd


def _nan_env(base, module):
    class NanEnv(base):
        """Observation NaN on the third step."""

        def __init__(self):
            self.observation_space = module.Box(-np.inf, np.inf, (2,), np.float32)
            self.action_space = module.Box(-1, 1, (1,), np.float32)
            self.t = 0

        def reset(self, *, seed=None, options=None):
            self.t = 0
            return np.zeros(2, np.float32), {}

        def step(self, action):
            self.t += 1
            value = np.nan if self.t == 3 else 0.0
            return np.full(2, value, np.float32), 0.0, False, False, {}

    return NanEnv


def _messages(venv, actions):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        venv.reset()
        for action in actions:
            venv.step(action)
    return [str(w.message) for w in caught if "found" in str(w.message)]


def test_vec_check_nan_warns_as_sb3():
    actions = [np.zeros((1, 1), np.float32), np.full((1, 1), np.inf, np.float32)] + [
        np.zeros((1, 1), np.float32)
    ] * 3
    ours = VecCheckNan(DummyVecEnv([_nan_env(gym.Env, spaces)]), warn_once=False)
    theirs = sb3.VecCheckNan(
        sb3.DummyVecEnv([_nan_env(gymnasium.Env, gymnasium.spaces)]), warn_once=False
    )
    got, ref = _messages(ours, actions), _messages(theirs, actions)
    assert got == ref and len(got) == 2
    assert got[0].startswith("found inf in actions.\r\nOriginated from the RL model")


def test_vec_check_nan_raises_on_request():
    venv = VecCheckNan(DummyVecEnv([_nan_env(gym.Env, spaces)]), raise_exception=True)
    venv.reset()
    venv.step(np.zeros((1, 1), np.float32))
    venv.step(np.zeros((1, 1), np.float32))
    with pytest.raises(
        ValueError, match=r"found nan in observations\.\r\nOriginated from the environment"
    ):
        venv.step(np.zeros((1, 1), np.float32))


def _dict_env(base, module):
    class DictEnv(base):
        def __init__(self):
            self.observation_space = module.Dict(
                {"a": module.Box(0, 10, (2,), np.float32), "b": module.Discrete(3)}
            )
            self.action_space = module.Discrete(2)
            self.t = 0

        def reset(self, *, seed=None, options=None):
            self.t = 0
            return {"a": np.zeros(2, np.float32), "b": 0}, {}

        def step(self, action):
            self.t += 1
            obs = {"a": np.full(2, self.t, np.float32), "b": self.t % 3}
            return obs, 1.0, self.t == 2, False, {}

    return DictEnv


def test_vec_extract_dict_obs_matches_sb3():
    ours = VecExtractDictObs(DummyVecEnv([_dict_env(gym.Env, spaces)] * 2), "a")
    theirs = sb3.VecExtractDictObs(
        sb3.DummyVecEnv([_dict_env(gymnasium.Env, gymnasium.spaces)] * 2), "a"
    )
    assert ours.observation_space.shape == theirs.observation_space.shape == (2,)
    np.testing.assert_array_equal(ours.reset(), theirs.reset())
    for _ in range(3):
        o1, _, _, i1 = ours.step(np.array([0, 1]))
        o2, _, _, i2 = theirs.step(np.array([0, 1]))
        np.testing.assert_array_equal(o1, o2)
        for a, b in zip(i1, i2):
            if "terminal_observation" in b:
                np.testing.assert_array_equal(a["terminal_observation"], b["terminal_observation"])
    with pytest.raises(TypeError, match="can only be used with Dict obs space"):
        VecExtractDictObs(DummyVecEnv([lambda: gym.make("CartPole-v1")]), "a")


@pytest.mark.parametrize(
    ("shape", "dtype", "order"),
    [
        ((3,), np.float32, None),
        ((2, 8, 8), np.uint8, None),
        ((8, 8, 1), np.uint8, None),
        ((4, 6), np.float32, "first"),
    ],
)
def test_stacked_observations_match_sb3(shape, dtype, order):
    high = 255 if dtype == np.uint8 else 1.0
    ours = StackedObservations(3, 4, spaces.Box(0, high, shape, dtype), order)
    theirs = sb3.StackedObservations(3, 4, gymnasium.spaces.Box(0, high, shape, dtype), order)
    np.testing.assert_array_equal(
        ours.stacked_observation_space.low, theirs.stacked_observation_space.low
    )
    rng = np.random.default_rng(0)
    first = rng.integers(0, 200, (3, *shape)).astype(dtype)
    np.testing.assert_array_equal(ours.reset(first), theirs.reset(first.copy()))
    for step in range(6):
        obs = rng.integers(0, 200, (3, *shape)).astype(dtype)
        dones = np.array([step == 2, False, step == 4])
        infos = [{"terminal_observation": obs[i].copy()} if dones[i] else {} for i in range(3)]
        got, got_infos = ours.update(obs, dones, [dict(i) for i in infos])
        ref, ref_infos = theirs.update(obs.copy(), dones, [dict(i) for i in infos])
        np.testing.assert_array_equal(got, ref)
        for a, b in zip(got_infos, ref_infos):
            if "terminal_observation" in b:
                np.testing.assert_array_equal(a["terminal_observation"], b["terminal_observation"])


def test_stacked_observations_on_dict_spaces_match_sb3():
    ours_space = spaces.Dict(
        {"x": spaces.Box(0, 1, (2,)), "img": spaces.Box(0, 255, (1, 6, 6), np.uint8)}
    )
    theirs_space = gymnasium.spaces.Dict(
        {
            "x": gymnasium.spaces.Box(0, 1, (2,)),
            "img": gymnasium.spaces.Box(0, 255, (1, 6, 6), np.uint8),
        }
    )
    ours, theirs = (
        StackedObservations(2, 3, ours_space),
        sb3.StackedObservations(2, 3, theirs_space),
    )
    assert (
        ours.stacked_observation_space["img"].shape == theirs.stacked_observation_space["img"].shape
    )
    rng = np.random.default_rng(1)

    def batch():
        return {
            "x": rng.random((2, 2)).astype(np.float32),
            "img": rng.integers(0, 255, (2, 1, 6, 6)).astype(np.uint8),
        }

    first = batch()
    for key, value in ours.reset(first).items():
        np.testing.assert_array_equal(value, theirs.reset(first)[key])
    obs = batch()
    dones = np.array([True, False])
    make_infos = lambda: [{"terminal_observation": {k: v[0].copy() for k, v in obs.items()}}, {}]  # noqa: E731
    got, got_infos = ours.update(obs, dones, make_infos())
    ref, ref_infos = theirs.update(obs, dones, make_infos())
    for key in ref:
        np.testing.assert_array_equal(got[key], ref[key])
        np.testing.assert_array_equal(
            got_infos[0]["terminal_observation"][key], ref_infos[0]["terminal_observation"][key]
        )


def test_stacked_observations_refuse_other_spaces():
    with pytest.raises(TypeError, match="only supports Box and Dict"):
        StackedObservations(1, 2, spaces.Discrete(3))
    with pytest.raises(ValueError, match="channels_order"):
        StackedObservations(1, 2, spaces.Box(0, 1, (2,)), "middle")


def test_vec_video_recorder_names_and_writes_as_sb3(tmp_path):
    venv = DummyVecEnv([lambda: gym.make("CartPole-v1", render_mode="rgb_array")] * 2)
    recorder = VecVideoRecorder(
        venv,
        str(tmp_path),
        record_video_trigger=lambda step: step == 0,
        video_length=5,
        video_suffix=".gif",
    )
    recorder.reset()
    for _ in range(8):
        recorder.step(np.array([0, 1]))
    recorder.close()
    assert [p.name for p in tmp_path.iterdir()] == ["rl-video-step-0-to-step-5.gif"]
    from PIL import Image

    with Image.open(tmp_path / "rl-video-step-0-to-step-5.gif") as gif:
        # two 600x400 frames tiled as SB3 tiles them (2 rows, 1 column): PIL says (W, H)
        tiled = sb3.base_vec_env.tile_images([np.zeros((400, 600, 3), np.uint8)] * 2)
        assert gif.size == (tiled.shape[1], tiled.shape[0]) == (600, 800)
        assert gif.n_frames >= 2


def test_vec_video_recorder_needs_rgb_array():
    with pytest.raises(ValueError, match="render_mode must be 'rgb_array'"):
        VecVideoRecorder(DummyVecEnv([lambda: gym.make("CartPole-v1")]), "/tmp/x", lambda s: True)


def test_running_mean_std_combine_and_copy_match_sb3():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(50, 3)), rng.normal(2.0, 3.0, size=(20, 3))
    ours, ours_other = RunningMeanStd(shape=(3,)), RunningMeanStd(shape=(3,))
    theirs, theirs_other = SB3RunningMeanStd(shape=(3,)), SB3RunningMeanStd(shape=(3,))
    ours.update(a), theirs.update(a)
    ours_other.update(b), theirs_other.update(b)
    copy = ours.copy()
    ours.combine(ours_other)
    theirs.combine(theirs_other)
    np.testing.assert_array_equal(ours.mean, theirs.mean)
    np.testing.assert_array_equal(ours.var, theirs.var)
    assert ours.count == theirs.count
    assert copy.count != ours.count and copy.mean is not ours.mean  # the copy did not move
