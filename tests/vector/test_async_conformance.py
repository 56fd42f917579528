"""Issue 16, item 5 and 7: ``AsyncVectorEnv`` behaving as Gymnasium's does, side by side.

``observation_mode="different"`` batches each worker's own space, ``reset_async`` starts the
reset and ``reset_wait(timeout)`` honours the timeout, ``close()`` with a call pending warns,
shared memory does not cast actions, and the error types callers catch are Gymnasium's.
"""

from __future__ import annotations

import multiprocessing as mp
import time
from functools import partial

import gymnasium
import numpy as np
import pytest

import palaestra as gym
from palaestra import error, spaces
from palaestra.vector import AsyncVectorEnv, SyncVectorEnv
from palaestra.vector.utils import create_shared_memory

pytestmark = pytest.mark.timeout(60)


def _boxed(base, space_module, high, sleep_on_reset=0.0):
    class Boxed(base):
        metadata = {"render_modes": []}

        def __init__(self):
            self.observation_space = space_module.Box(-high, high, (2,), np.float32)
            self.action_space = space_module.Box(-1, 1, (1,), np.float32)
            self.last_action = None

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            time.sleep(sleep_on_reset)
            return np.zeros(2, np.float32), {"pid": __import__("os").getpid()}

        def step(self, action):
            self.last_action = action
            return np.zeros(2, np.float32), 0.0, False, False, {}

    return Boxed()


def test_observation_mode_different_batches_each_workers_space_as_gymnasium():
    ours = AsyncVectorEnv(
        [partial(_boxed, gym.Env, spaces, h) for h in (1.0, 2.0, 3.0)],
        context="fork",
        observation_mode="different",
    )
    theirs = gymnasium.vector.AsyncVectorEnv(
        [partial(_boxed, gymnasium.Env, gymnasium.spaces, h) for h in (1.0, 2.0, 3.0)],
        context="fork",
        observation_mode="different",
    )
    try:
        np.testing.assert_array_equal(ours.observation_space.high, theirs.observation_space.high)
        assert ours.observation_space.high[:, 0].tolist() == [1.0, 2.0, 3.0]
        assert ours.single_observation_space.high.tolist() == [1.0, 1.0]
    finally:
        ours.close(), theirs.close()


def test_reset_async_starts_the_reset_and_reset_wait_times_out():
    envs = AsyncVectorEnv(
        [partial(_boxed, gym.Env, spaces, 1.0, sleep_on_reset=0.4)] * 2, context="fork"
    )
    envs.reset_async(seed=0)
    time.sleep(0.6)  # the workers reset meanwhile: collecting is then immediate
    start = time.monotonic()
    envs.reset_wait(timeout=5)
    assert time.monotonic() - start < 0.3
    envs.reset_async(seed=0)
    with pytest.raises(mp.TimeoutError, match="did not answer 'reset' in time"):
        envs.reset_wait(timeout=0.05)
    with pytest.raises(error.ClosedEnvironmentError):
        envs.reset()


def test_close_with_a_pending_call_warns_as_gymnasium():
    ours = AsyncVectorEnv([partial(_boxed, gym.Env, spaces, 1.0)] * 2, context="fork")
    theirs = gymnasium.vector.AsyncVectorEnv(
        [partial(_boxed, gymnasium.Env, gymnasium.spaces, 1.0)] * 2, context="fork"
    )
    for envs in (ours, theirs):
        envs.reset(seed=0)
        envs.step_async(np.zeros((2, 1), np.float32))
        with pytest.warns(UserWarning, match="Calling `close` while waiting for a pending call"):
            envs.close()
        assert envs.closed


def test_call_async_sends_and_call_wait_collects():
    envs = AsyncVectorEnv([partial(_boxed, gym.Env, spaces, 1.0)] * 2, context="fork")
    envs.reset(seed=0)
    envs.call_async("reset", seed=3)
    results = envs.call_wait(timeout=5)
    assert len(results) == 2 and all(isinstance(r, tuple) for r in results)
    envs.close()


@pytest.mark.parametrize("shared_memory", [True, False])
def test_actions_reach_the_env_uncast_as_in_sync(shared_memory):
    sync = SyncVectorEnv([partial(_boxed, gym.Env, spaces, 1.0)] * 2)
    envs = AsyncVectorEnv(
        [partial(_boxed, gym.Env, spaces, 1.0)] * 2, shared_memory=shared_memory, context="fork"
    )
    actions = np.array([[0.1], [0.2]])  # float64 under a float32 space
    for venv in (sync, envs):
        venv.reset(seed=0)
        venv.step(actions)
    seen_async = envs.get_attr("last_action")
    seen_sync = sync.get_attr("last_action")
    assert [a.dtype for a in seen_async] == [a.dtype for a in seen_sync] == [np.float64] * 2
    np.testing.assert_array_equal(np.stack(seen_async), np.stack(seen_sync))
    envs.close()


class _TypeErrorEnv(gym.Env):
    observation_space = spaces.Box(-1, 1, (2,), np.float32)
    action_space = spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        return np.zeros(2, np.float32), {}

    def step(self, action):
        raise TypeError("bad step")


@pytest.mark.parametrize("shared_memory", [True, False])
def test_worker_type_error_surfaces_the_same_with_and_without_shared_memory(shared_memory):
    envs = AsyncVectorEnv([_TypeErrorEnv] * 2, shared_memory=shared_memory, context="fork")
    envs.reset()
    envs.step_async(np.array([0, 1]))
    with pytest.raises(TypeError, match="bad step"):
        envs.step_wait(timeout=5)
    envs.close()


def test_wrong_number_of_actions_is_a_value_error():
    envs = SyncVectorEnv([lambda: gym.make("CartPole-v1")] * 2)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        envs.step(np.array([0, 1, 1]))
    assert issubclass(error.InvalidAction, error.Error)  # palaestra's class stays


@pytest.mark.parametrize(
    ("ours", "theirs"),
    [
        (
            spaces.Sequence(spaces.Discrete(2)),
            gymnasium.spaces.Sequence(gymnasium.spaces.Discrete(2)),
        ),
        (
            spaces.Graph(spaces.Box(0, 1, (2,)), spaces.Discrete(2)),
            gymnasium.spaces.Graph(gymnasium.spaces.Box(0, 1, (2,)), gymnasium.spaces.Discrete(2)),
        ),
    ],
)
def test_dynamic_shape_shared_memory_is_a_type_error_as_gymnasium(ours, theirs):
    from gymnasium.vector.utils import create_shared_memory as gym_create

    with pytest.raises(TypeError, match="dynamic shape"):
        gym_create(theirs, n=2)
    with pytest.raises(TypeError, match="dynamic shape"):
        create_shared_memory(ours, n=2)
    with pytest.raises(error.CustomSpaceError):  # and still palaestra's class
        create_shared_memory(ours, n=2)


class _SequenceEnv(gym.Env):
    observation_space = spaces.Sequence(spaces.Discrete(2))
    action_space = spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        return (0, 1), {}

    def step(self, action):
        return (1,), 0.0, False, False, {}


def test_async_shared_memory_on_an_unsupported_space_is_a_value_error_with_the_fallback():
    with pytest.raises(ValueError, match="shared_memory=False"):
        AsyncVectorEnv([_SequenceEnv] * 2, context="fork")
    envs = AsyncVectorEnv([_SequenceEnv] * 2, context="fork", shared_memory=False)
    obs, _ = envs.reset()
    assert obs == ((0, 1), (0, 1))
    envs.close()


def test_subproc_vec_env_falls_back_to_pickled_observations_as_sb3():
    from palaestra.vec_env import SubprocVecEnv

    venv = SubprocVecEnv([_SequenceEnv] * 2, start_method="fork")
    assert venv.reset() == ((0, 1), (0, 1))
    venv.close()
