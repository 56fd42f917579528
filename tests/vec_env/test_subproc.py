"""SubprocVecEnv: the DummyVecEnv results from worker processes, SB3's methods, and errors."""

from __future__ import annotations

import os
import signal

import numpy as np
import psutil
import pytest

import palaestra as gym
from palaestra.error import ClosedEnvironmentError, InvalidAction
from palaestra.vec_env import DummyVecEnv, SubprocVecEnv, make_vec_env
from palaestra.vector import WorkerDiedError

pytestmark = pytest.mark.timeout(60)


def _mc():
    return gym.make("MountainCar-v0")


class _Fragile(gym.Env):
    def __init__(self):
        from palaestra import spaces

        self.observation_space = spaces.Box(-1, 1, (1,), np.float32)
        self.action_space = spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(1, np.float32), {"fresh": True}

    def step(self, action):
        if action == 1:
            raise ZeroDivisionError("the env divided by zero")
        return np.zeros(1, np.float32), 0.0, True, False, {"k": 1}

    def secret(self, x):
        return x * 2


def test_subproc_matches_dummy_fork():
    ours = SubprocVecEnv([_mc] * 3, start_method="fork")
    ref = DummyVecEnv([_mc] * 3)
    for venv in (ours, ref):
        venv.seed(7)
    np.testing.assert_array_equal(ours.reset(), ref.reset())
    rng = np.random.default_rng(0)
    for _ in range(210):
        actions = rng.integers(0, 3, size=3)
        a, b = ours.step(actions), ref.step(actions)
        np.testing.assert_array_equal(a[0], b[0])
        np.testing.assert_array_equal(a[2], b[2])
        assert [sorted(i) for i in a[3]] == [sorted(i) for i in b[3]]
    assert a[1].dtype == np.float64 and b[1].dtype == np.float32  # as in SB3
    assert ours.get_attr("goal_position", indices=[1]) == [0.5]
    ours.close()
    ours.close()


def test_subproc_methods_errors_and_reset_infos():
    before = {p.pid for p in psutil.Process().children(recursive=True)}
    venv = SubprocVecEnv([_Fragile] * 2, start_method="fork")
    venv.reset()
    assert venv.reset_infos == [{"fresh": True}] * 2
    assert venv.env_method("secret", 21, indices=1) == [42]
    _, _, dones, infos = venv.step(np.array([0, 0]))
    assert dones.all() and infos[0]["k"] == 1 and "terminal_observation" in infos[0]
    assert venv.reset_infos[0] == {"fresh": True}
    with pytest.raises(ZeroDivisionError, match="divided by zero") as info:
        venv.step(np.array([0, 1]))
    assert "SubprocVecEnv worker 1" in "\n".join(info.value.__notes__)
    with pytest.raises(InvalidAction):
        venv.step(np.array([0, 0, 0]))
    os.kill(venv.engine.processes[0].pid, signal.SIGKILL)
    with pytest.raises(WorkerDiedError, match="SIGKILL"):
        venv.step(np.array([0, 0]))
    with pytest.raises(ClosedEnvironmentError):
        venv.reset()
    venv.close()
    after = {p.pid for p in psutil.Process().children(recursive=True) if p.is_running()}
    assert not {p for p in after - before if psutil.Process(p).status() != psutil.STATUS_ZOMBIE} - {
        p.pid for p in psutil.Process().children() if "multiprocessing" in " ".join(p.cmdline())
    }


def test_make_vec_env_with_subproc_default_start_method():
    venv = make_vec_env("CartPole-v1", n_envs=2, seed=1, vec_env_cls=SubprocVecEnv)
    ref = make_vec_env("CartPole-v1", n_envs=2, seed=1, vec_env_cls=DummyVecEnv)
    np.testing.assert_array_equal(venv.reset(), ref.reset())
    for _ in range(40):
        a, b = venv.step(np.array([1, 0])), ref.step(np.array([1, 0]))
        np.testing.assert_array_equal(a[0], b[0])
        for x, y in zip(a[3], b[3]):
            assert ("episode" in x) == ("episode" in y)
    venv.close()
