"""Issue 16's differences on the SB3 face, each pinned against stable-baselines3 side by side.

Per-env composite actions (item 1), one shared env instance (3), ``reset`` without ``options``
(6), ``get_attr``/``vec_env_kwargs`` on the native batch (10), ``monitor_dir`` files (12),
``VecNormalize`` reward dtype (15), and the wrapper-finding helpers SB3 exports.
"""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from stable_baselines3.common import env_util as sb3_util
from stable_baselines3.common import vec_env as sb3

import palaestra as gym
from palaestra import spaces
from palaestra.vec_env import (
    DummyVecEnv,
    VecMonitor,
    VecNormalize,
    is_vecenv_wrapped,
    make_vec_env,
    sync_envs_normalization,
    unwrap_vec_normalize,
    unwrap_vec_wrapper,
)
from palaestra.wrappers import Monitor


def _recorder(base, space_module):
    """An env class (of ``base``) that records the actions it is given."""

    class Recorder(base):
        def __init__(self, action_space):
            self.action_space = action_space
            self.observation_space = space_module.Discrete(2)
            self.seen = []

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            return 0, {}

        def step(self, action):
            self.seen.append(action)
            return 0, 0.0, False, False, {}

    return Recorder


OurRecorder = _recorder(gym.Env, spaces)
TheirRecorder = _recorder(gymnasium.Env, gymnasium.spaces)


def _plain(value):
    """Python values of an action, whatever numpy scalar types hold them."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return tuple(_plain(v) for v in value)
    return np.asarray(value).tolist()


@pytest.mark.parametrize("n_envs", [2, 3, 5])
def test_per_env_tuple_actions_reach_their_env_as_in_sb3(n_envs):
    ours_space = spaces.Tuple((spaces.Discrete(7), spaces.Discrete(7)))
    theirs_space = gymnasium.spaces.Tuple(
        (gymnasium.spaces.Discrete(7), gymnasium.spaces.Discrete(7))
    )
    ours = DummyVecEnv([lambda: OurRecorder(ours_space) for _ in range(n_envs)])
    theirs = sb3.DummyVecEnv([lambda: TheirRecorder(theirs_space) for _ in range(n_envs)])
    ours.reset(), theirs.reset()
    actions = [(i, (i + 3) % 7) for i in range(n_envs)]
    ours.step(actions)
    theirs.step(actions)
    seen_ours = [[_plain(a) for a in env.seen] for env in ours.envs]
    seen_theirs = [[_plain(a) for a in env.seen] for env in theirs.envs]
    assert seen_ours == seen_theirs == [[(i, (i + 3) % 7)] for i in range(n_envs)]


def test_per_env_dict_actions_reach_their_env_as_in_sb3():
    ours_space = spaces.Dict({"a": spaces.Discrete(5), "b": spaces.Box(-1, 1, (2,))})
    theirs_space = gymnasium.spaces.Dict(
        {"a": gymnasium.spaces.Discrete(5), "b": gymnasium.spaces.Box(-1, 1, (2,))}
    )
    ours = DummyVecEnv([lambda: OurRecorder(ours_space) for _ in range(3)])
    theirs = sb3.DummyVecEnv([lambda: TheirRecorder(theirs_space) for _ in range(3)])
    ours.reset(), theirs.reset()
    actions = [{"a": i, "b": np.full(2, i / 4, np.float32)} for i in range(3)]
    ours.step(actions)
    theirs.step(actions)
    for mine, ref in zip(ours.envs, theirs.envs):
        assert _plain(mine.seen[0]) == _plain(ref.seen[0])


def test_wrong_number_of_per_env_actions_is_a_value_error():
    space = spaces.Tuple((spaces.Discrete(3), spaces.Discrete(3)))
    venv = DummyVecEnv([lambda: OurRecorder(space) for _ in range(3)])
    venv.reset()
    with pytest.raises(ValueError, match=r"Expected 3 actions \(one per env\).*got 2"):
        venv.step([(0, 1), (1, 2)])
    assert all(env.seen == [] for env in venv.envs)  # nothing was stepped


def test_shared_env_instance_is_refused_as_in_sb3():
    env = gym.make("CartPole-v1")
    with pytest.raises(ValueError, match="returned the same instance"):
        DummyVecEnv([lambda: env] * 2)
    with pytest.raises(ValueError, match="returned the same instance"):
        make_vec_env(lambda: env, n_envs=2)
    # SB3 raises the same error type for the same mistake.
    their_env = gymnasium.make("CartPole-v1")
    with pytest.raises(ValueError, match="returned the same instance"):
        sb3.DummyVecEnv([lambda: their_env] * 2)


class NoOptionsEnv(gym.Env):
    """An env written for SB3: ``reset`` takes a seed but no ``options``."""

    observation_space = spaces.Discrete(2)
    action_space = spaces.Discrete(2)

    def reset(self, seed=None):
        return 0, {}

    def step(self, action):
        return 0, 1.0, True, False, {}


def test_reset_without_options_keyword_works_as_in_sb3():
    venv = DummyVecEnv([NoOptionsEnv, NoOptionsEnv])
    assert venv.reset().tolist() == [0, 0]
    _, _, dones, infos = venv.step(np.array([0, 1]))  # autoreset calls reset() too
    assert dones.tolist() == [True, True] and infos[0]["terminal_observation"] == 0
    monitored = make_vec_env(NoOptionsEnv, n_envs=2)  # Monitor in between
    assert monitored.reset().tolist() == [0, 0]
    venv.set_options({"x": 1})  # options given: passed on, and this env cannot take them
    with pytest.raises(TypeError, match="options"):
        venv.reset()


def test_monitor_reset_keywords_accept_options():
    env = Monitor(gym.make("CartPole-v1"), reset_keywords=("options",))
    env.reset(options={"level": 2})
    assert env.current_reset_info == {"options": {"level": 2}}
    with pytest.raises(ValueError, match="Expected you to pass keyword argument options"):
        env.reset()


def test_native_get_attr_sees_env_kwargs_as_sb3_does():
    ours = make_vec_env("MountainCar-v0", n_envs=2, env_kwargs={"goal_velocity": 0.1})
    theirs = sb3_util.make_vec_env("MountainCar-v0", n_envs=2, env_kwargs={"goal_velocity": 0.1})
    assert ours.get_attr("goal_velocity") == theirs.get_attr("goal_velocity") == [0.1, 0.1]
    # set_attr reaches the physics: a goal at the left edge, any velocity, ends every episode.
    ours.set_attr("goal_position", -1.3)
    ours.set_attr("goal_velocity", -1.0)
    ours.reset()
    assert ours.get_attr("goal_position") == [-1.3, -1.3]
    _, _, dones, _ = ours.step(np.array([1, 1]))
    assert dones.tolist() == [True, True]


def test_vec_env_kwargs_are_not_ignored():
    with pytest.raises(TypeError):  # DummyVecEnv takes none: SB3 raises TypeError too
        make_vec_env("CartPole-v1", n_envs=2, vec_env_kwargs={"start_method": "fork"})
    with pytest.raises(TypeError):
        sb3_util.make_vec_env("CartPole-v1", n_envs=2, vec_env_kwargs={"start_method": "fork"})


def test_monitor_kwargs_reach_a_monitor_per_env():
    venv = make_vec_env("CartPole-v1", n_envs=2, monitor_kwargs={"allow_early_resets": False})
    assert all(venv.env_is_wrapped(Monitor))
    venv.reset()
    with pytest.raises(RuntimeError, match="Tried to reset an environment before done"):
        venv.reset()


def test_monitor_dir_writes_one_file_per_env_as_sb3(tmp_path):
    ours_dir, theirs_dir = tmp_path / "ours", tmp_path / "theirs"
    ours = make_vec_env("CartPole-v1", n_envs=3, seed=0, start_index=2, monitor_dir=str(ours_dir))
    theirs = sb3_util.make_vec_env(
        "CartPole-v1", n_envs=3, seed=0, start_index=2, monitor_dir=str(theirs_dir)
    )
    ours.reset(), theirs.reset()
    for _ in range(60):
        ours.step(np.ones(3, dtype=np.int64))
        theirs.step(np.ones(3, dtype=np.int64))
    ours.close(), theirs.close()
    names = sorted(p.name for p in ours_dir.iterdir())
    assert names == sorted(p.name for p in theirs_dir.iterdir())
    assert names == ["2.monitor.csv", "3.monitor.csv", "4.monitor.csv"]
    for name in names:  # the same episodes (r, l) in each file
        rows = [line.split(",")[:2] for line in (ours_dir / name).read_text().splitlines()[2:]]
        ref = [line.split(",")[:2] for line in (theirs_dir / name).read_text().splitlines()[2:]]
        assert rows == ref and rows


@pytest.mark.parametrize("norm_reward", [True, False])
def test_vec_normalize_rewards_are_float32_as_in_sb3(norm_reward):
    ours = VecNormalize(make_vec_env("CartPole-v1", n_envs=2, seed=0), norm_reward=norm_reward)
    theirs = sb3.VecNormalize(
        sb3_util.make_vec_env("CartPole-v1", n_envs=2, seed=0), norm_reward=norm_reward
    )
    ours.reset(), theirs.reset()
    for _ in range(5):
        _, r1, _, _ = ours.step(np.array([0, 1]))
        _, r2, _, _ = theirs.step(np.array([0, 1]))
        assert r1.dtype == r2.dtype == np.float32
        np.testing.assert_allclose(r1, r2, rtol=1e-6)


def test_unwrap_helpers_match_sb3():
    ours = VecNormalize(VecMonitor(DummyVecEnv([lambda: gym.make("CartPole-v1")])))
    theirs = sb3.VecNormalize(
        sb3.VecMonitor(sb3.DummyVecEnv([lambda: gymnasium.make("CartPole-v1")]))
    )
    assert unwrap_vec_normalize(ours) is ours
    assert unwrap_vec_wrapper(ours, VecMonitor) is ours.venv
    assert (unwrap_vec_normalize(ours.venv) is None) == (
        sb3.unwrap_vec_normalize(theirs.venv) is None
    )
    assert is_vecenv_wrapped(ours, VecMonitor) == sb3.is_vecenv_wrapped(theirs, sb3.VecMonitor)
    assert is_vecenv_wrapped(ours.venv, VecNormalize) == sb3.is_vecenv_wrapped(
        theirs.venv, sb3.VecNormalize
    )


def test_sync_envs_normalization_copies_statistics():
    train = VecNormalize(make_vec_env("CartPole-v1", n_envs=2, seed=0))
    evaluation = VecNormalize(make_vec_env("CartPole-v1", n_envs=1, seed=1), training=False)
    train.reset()
    for _ in range(20):
        train.step(np.array([0, 1]))
    sync_envs_normalization(train, evaluation)
    np.testing.assert_array_equal(evaluation.obs_rms.mean, train.obs_rms.mean)
    assert evaluation.obs_rms is not train.obs_rms  # a copy, as SB3's deepcopy
    assert evaluation.ret_rms.var == train.ret_rms.var
    with pytest.raises(AssertionError, match="expected the eval env to be a VecNormalize"):
        sync_envs_normalization(train, VecMonitor(DummyVecEnv([lambda: gym.make("CartPole-v1")])))


def test_render_with_another_mode_warns_and_returns_none_as_sb3():
    ours = DummyVecEnv([lambda: gym.make("CartPole-v1", render_mode="rgb_array")])
    theirs = sb3.DummyVecEnv([lambda: gymnasium.make("CartPole-v1", render_mode="rgb_array")])
    ours.reset(), theirs.reset()
    for venv in (ours, theirs):
        with pytest.warns(UserWarning, match=r"the mode \(depth\)\s+has to be the same"):
            assert venv.render(mode="depth") is None
    assert ours.render().shape == theirs.render().shape == (400, 600, 3)
    plain = DummyVecEnv([lambda: gym.make("CartPole-v1")])
    with pytest.warns(UserWarning, match="mode='human' but the render mode"):
        assert plain.render(mode="human") is None
    with pytest.warns(UserWarning, match="no `render_mode` was passed"):
        assert plain.render() is None


def test_vec_monitor_over_monitored_envs_warns_as_sb3():
    with pytest.warns(UserWarning, match="already wrapped with a `Monitor` wrapper"):
        sb3.VecMonitor(sb3_util.make_vec_env("CartPole-v1", n_envs=1))
    with pytest.warns(UserWarning, match="already wrapped with a `Monitor` wrapper"):
        VecMonitor(make_vec_env("CartPole-v1", n_envs=1, wrapper_class=lambda env: env))


def test_vec_monitor_over_a_native_batch_does_not_warn(recwarn):
    VecMonitor(make_vec_env("CartPole-v1", n_envs=2).venv)
    assert not [w for w in recwarn if "Monitor" in str(w.message)]


def test_loading_an_sb3_vec_normalize_pickle_says_what_palaestra_reads(tmp_path):
    from palaestra.algos.common.model_io import ModelFileError

    path = tmp_path / "vecnormalize.pkl"
    sb3.VecNormalize(sb3.DummyVecEnv([lambda: gymnasium.make("CartPole-v1")])).save(str(path))
    with pytest.raises(ModelFileError, match=r"is a pickle .*reads only the \.npz file") as info:
        VecNormalize.load(str(path), make_vec_env("CartPole-v1"))
    assert "allow_pickle" not in str(info.value)
