"""AsyncVectorEnv: same results as SyncVectorEnv, and reliability of the worker processes.

A worker exception re-raises in the parent with its type and the worker's traceback text; a
SIGKILLed worker gives ``WorkerDiedError`` promptly; ``close()`` is idempotent and leaves no
child process behind. Workers use "fork" (fast to start); one test covers "spawn".
"""

from __future__ import annotations

import os
import signal
import time
from functools import partial

import numpy as np
import psutil
import pytest

import palaestra as gym
from palaestra.error import AlreadyPendingCallError, ClosedEnvironmentError, NoAsyncCallError
from palaestra.vector import AsyncVectorEnv, SyncVectorEnv, WorkerDiedError

from .toys import assert_infos_equal, pal_counter

pytestmark = pytest.mark.timeout(60)


def _children() -> set[int]:
    return {p.pid for p in psutil.Process().children(recursive=True) if p.is_running()}


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_async_matches_sync(mode):
    fns = [partial(pal_counter, n) for n in (2, 3, 4)]
    sync = SyncVectorEnv(fns, autoreset_mode=mode)
    with AsyncVectorEnv(fns, context="fork", autoreset_mode=mode) as envs:
        a, b = envs.reset(seed=1), sync.reset(seed=1)
        np.testing.assert_array_equal(a[0], b[0])
        assert_infos_equal(a[1], b[1])
        rng = np.random.default_rng(0)
        for _ in range(12):
            actions = rng.integers(0, 3, size=3)
            got, ref = envs.step(actions), sync.step(actions)
            for x, y in zip(got[:4], ref[:4]):
                np.testing.assert_array_equal(x, y)
            assert_infos_equal(got[4], ref[4])
        assert envs.get_attr("length") == (2, 3, 4)
        envs.set_attr("length", [5, 6, 7])
        assert envs.call("length") == (5, 6, 7)


def test_async_without_shared_memory_and_make_vec():
    envs = gym.make_vec(
        "CartPole-v1",
        2,
        vectorization_mode="async",
        vector_kwargs={"shared_memory": False, "context": "fork"},
    )
    sync = gym.make_vec("CartPole-v1", 2, vectorization_mode="sync")
    np.testing.assert_array_equal(envs.reset(seed=3)[0], sync.reset(seed=3)[0])
    for _ in range(30):
        got, ref = envs.step(np.array([1, 1])), sync.step(np.array([1, 1]))
        np.testing.assert_array_equal(got[0], ref[0])
        np.testing.assert_array_equal(got[2], ref[2])
    assert repr(envs) == "AsyncVectorEnv(CartPole-v1, num_envs=2)"
    envs.close()


def test_worker_exception_keeps_type_and_traceback():
    envs = AsyncVectorEnv([partial(pal_counter, 5, fail_on=2)] * 2, context="fork")
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="boom: action 2 is forbidden") as info:
        envs.step(np.array([0, 2]))
    text = "\n".join(getattr(info.value, "__notes__", []))
    assert "worker 1" in text and "Traceback" in text and "in step" in text
    assert "Traceback" in str(info.value.__cause__)
    # The failing env raised; the others stepped: the vector env stays usable.
    envs.step(np.array([0, 1]))
    envs.close()


def test_worker_exception_at_construction_surfaces():
    def broken():
        raise KeyError("no such env")

    before = _children()
    with pytest.raises(KeyError, match="no such env"):
        AsyncVectorEnv([broken, broken], context="fork")
    time.sleep(0.1)
    assert _children() <= before


def test_killed_worker_gives_a_clear_error_quickly_and_no_orphans():
    before = _children()
    envs = AsyncVectorEnv([partial(pal_counter, 50)] * 3, context="fork")
    envs.reset(seed=0)
    pid = envs.engine.processes[1].pid
    os.kill(pid, signal.SIGKILL)
    start = time.monotonic()
    with pytest.raises(WorkerDiedError, match=r"worker 1 \(pid \d+\) was killed by SIGKILL"):
        envs.step(np.array([1, 1, 1]))
    assert time.monotonic() - start < 5
    with pytest.raises(ClosedEnvironmentError):
        envs.step(np.array([1, 1, 1]))
    envs.close()
    assert _children() <= before


def test_close_is_idempotent_and_reaps_children():
    before = _children()
    envs = AsyncVectorEnv([partial(pal_counter, 3)] * 3, context="fork")
    assert len(_children() - before) == 3
    envs.close()
    envs.close()
    assert _children() <= before
    with pytest.raises(ClosedEnvironmentError, match="after a call to `close\\(\\)`"):
        envs.reset()


def test_async_call_protocol_errors():
    with AsyncVectorEnv([partial(pal_counter, 3)] * 2, context="fork") as envs:
        envs.reset(seed=0)
        with pytest.raises(NoAsyncCallError, match="without any prior call to `step_async`"):
            envs.step_wait()
        envs.step_async(np.array([1, 1]))
        with pytest.raises(AlreadyPendingCallError, match="pending call to `step`"):
            envs.reset_async()
        envs.step_wait(timeout=10)
        envs.call_async("length")
        assert envs.call_wait() == (3, 3)


def test_spawn_context_with_a_lambda():
    with AsyncVectorEnv([lambda: gym.make("MountainCar-v0")] * 2, context="spawn") as envs:
        obs, _ = envs.reset(seed=0)
        single = gym.make("MountainCar-v0").reset(seed=1)[0]
        np.testing.assert_array_equal(obs[1], single)


def test_mismatched_sub_env_spaces_are_refused():
    fns = [lambda: gym.make("CartPole-v1"), lambda: gym.make("MountainCar-v0")]
    with pytest.raises(RuntimeError, match="observation spaces are not equivalent"):
        SyncVectorEnv(fns)
    before = _children()
    with pytest.raises(RuntimeError, match="observation spaces are not equivalent"):
        AsyncVectorEnv(fns, context="fork")
    assert _children() <= before


class _Slow(gym.Env):
    def __init__(self):
        from palaestra import spaces

        self.observation_space = spaces.Box(-1, 1, (1,), np.float32)
        self.action_space = spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(1, np.float32), {}

    def step(self, action):
        time.sleep(30 if action else 0)
        return np.zeros(1, np.float32), 0.0, False, False, {}


def test_step_wait_timeout_closes_instead_of_desynchronising():
    import multiprocessing as mp

    before = _children()
    envs = AsyncVectorEnv([_Slow] * 2, context="fork")
    envs.reset(seed=0)
    envs.step_async(np.array([0, 1]))
    start = time.monotonic()
    with pytest.raises(mp.TimeoutError, match="worker 1 did not answer 'step' in time"):
        envs.step_wait(timeout=0.3)
    assert time.monotonic() - start < 5
    with pytest.raises(ClosedEnvironmentError):
        envs.step(np.array([0, 0]))
    assert _children() <= before
