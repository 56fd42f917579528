"""``VecNormalize.set_venv`` and pickling, with SB3's semantics: a pickled VecNormalize keeps its
statistics and settings but not the wrapped env; ``set_venv`` attaches one of the same
observation shapes (any number of envs). Errors are palaestra errors that are also what SB3
raises on the same input."""

from __future__ import annotations

import importlib.util
import pickle
from typing import Any

import numpy as np
import pytest
from tests.raised import raised

from palaestra import error, spaces
from palaestra.vec_env import DummyVecEnv, VecNormalize, make_vec_env

HAS_SB3 = importlib.util.find_spec("stable_baselines3") is not None


def _trained(n_envs: int = 2) -> VecNormalize:
    norm = VecNormalize(make_vec_env("CartPole-v1", n_envs=n_envs, seed=0), gamma=0.9)
    norm.reset()
    for _ in range(20):
        norm.step(np.zeros(n_envs, dtype=np.int64))
    return norm


def _sb3_pair(ours_env: str, n_envs: int) -> Any:
    from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize as SB3VecNormalize

    norm = SB3VecNormalize(sb3_make_vec_env("CartPole-v1", n_envs=2))
    return pickle.loads(pickle.dumps(norm)), sb3_make_vec_env(ours_env, n_envs=n_envs)


def test_pickle_leaves_out_the_env_and_set_venv_attaches_one() -> None:
    norm = _trained()
    restored = pickle.loads(pickle.dumps(norm))
    assert restored.venv is None and not hasattr(restored, "returns")
    assert restored.gamma == 0.9 and restored.obs_rms.count == norm.obs_rms.count
    np.testing.assert_array_equal(restored.obs_rms.mean, norm.obs_rms.mean)
    np.testing.assert_array_equal(restored.ret_rms.var, norm.ret_rms.var)

    venv = make_vec_env("CartPole-v1", n_envs=3, seed=5)
    restored.set_venv(venv)
    assert restored.venv is venv and restored.num_envs == 3
    np.testing.assert_array_equal(restored.returns, np.zeros(3))
    restored.training = False  # same statistics, same arithmetic as the original
    norm.training = False
    raw = venv.reset()
    np.testing.assert_allclose(restored.normalize_obs(raw), norm.normalize_obs(raw))
    obs, rewards, dones, _ = restored.step(np.zeros(3, dtype=np.int64))
    assert obs.shape == (3, 4) and rewards.shape == (3,) and dones.shape == (3,)
    restored.close()
    norm.close()


def test_set_venv_on_a_wrapper_that_has_an_env() -> None:
    norm = _trained()
    other = make_vec_env("CartPole-v1", n_envs=2)
    ours = raised(lambda: norm.set_venv(other))
    if HAS_SB3:
        from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env
        from stable_baselines3.common.vec_env import VecNormalize as SB3VecNormalize

        sb3 = SB3VecNormalize(sb3_make_vec_env("CartPole-v1", n_envs=2))
        theirs = raised(lambda: sb3.set_venv(sb3_make_vec_env("CartPole-v1", n_envs=2)))
        assert type(theirs) is ValueError and isinstance(ours, ValueError)
    assert type(ours) is error.VecEnvAlreadySet
    assert str(ours) == (
        "Trying to set venv of already initialized VecNormalize wrapper: it wraps "
        f"{norm.venv!r}; set_venv({other!r}) expects a VecNormalize without one (unpickled). "
        "Wrap the new env in VecNormalize, or VecNormalize.load the saved statistics around it."
    )
    assert norm.venv is not other


@pytest.mark.parametrize("env_id", ["Pendulum-v1", "MountainCar-v0"])
def test_set_venv_with_other_observation_shapes(env_id: str) -> None:
    restored = pickle.loads(pickle.dumps(_trained()))
    venv = make_vec_env(env_id, n_envs=2)
    ours = raised(lambda: restored.set_venv(venv))
    if HAS_SB3:
        sb3, sb3_venv = _sb3_pair(env_id, 2)
        theirs = raised(lambda: sb3.set_venv(sb3_venv))
        assert type(theirs) is AssertionError and isinstance(ours, AssertionError)
    assert type(ours) is error.InvalidObservation and isinstance(ours, ValueError)
    shape = venv.observation_space.shape
    assert str(ours) == (
        f"VecNormalize.set_venv: the env's observation space {venv.observation_space} has "
        f"shape {shape}, but the statistics were gathered on {restored.observation_space} "
        "(shape (4,))"
    )
    assert restored.venv is None  # nothing half-set


def test_set_venv_with_something_that_is_not_a_vec_env() -> None:
    restored = pickle.loads(pickle.dumps(_trained()))
    ours = raised(lambda: restored.set_venv(123))  # type: ignore[arg-type]
    if HAS_SB3:
        sb3, _ = _sb3_pair("CartPole-v1", 2)
        theirs = raised(lambda: sb3.set_venv(123))
        assert type(theirs) is AttributeError and isinstance(ours, AttributeError)
    assert type(ours) is error.NotAVecEnv and isinstance(ours, TypeError)
    assert str(ours) == "VecNormalize.set_venv expects a palaestra.vec_env.VecEnv, got 123"


def _dict_env(keys: tuple[str, ...]) -> Any:
    from palaestra.core import Env

    class DictEnv(Env):
        def __init__(self) -> None:
            self.observation_space = spaces.Dict({k: spaces.Box(-1, 1, (2,)) for k in keys})
            self.action_space = spaces.Discrete(2)

        def reset(self, *, seed: int | None = None, options: dict | None = None) -> Any:
            super().reset(seed=seed)
            return {k: np.zeros(2, np.float32) for k in keys}, {}

        def step(self, action: Any) -> Any:
            return {k: np.zeros(2, np.float32) for k in keys}, 0.0, False, False, {}

    return DictEnv


def test_set_venv_with_other_dict_keys() -> None:
    norm = VecNormalize(DummyVecEnv([_dict_env(("a", "b"))]))
    restored = pickle.loads(pickle.dumps(norm))
    ours = raised(lambda: restored.set_venv(DummyVecEnv([_dict_env(("a", "c"))])))
    assert type(ours) is error.InvalidObservation and isinstance(ours, AssertionError)
    assert "does not have the keys of the one the statistics were gathered on" in str(ours)
    restored.set_venv(DummyVecEnv([_dict_env(("b", "a"))]))  # order does not matter (SB3)
    assert set(restored.reset()) == {"a", "b"}
