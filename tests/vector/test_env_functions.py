"""Lambdas, closures and local env classes reach worker processes under every start method.

Users of SB3 and Gymnasium hand ``SubprocVecEnv``/``AsyncVectorEnv`` (and ``make_vec``'s
wrappers) functions that plain pickle cannot send; "fork" hides that, "spawn" and "forkserver"
(Python 3.14's Linux default) do not. Every multi-process face is checked under all three, and
once in a child interpreter where gymnasium and stable_baselines3 cannot be imported at all
(parent and workers), so nothing they pull in (cloudpickle) helps by accident.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import palaestra as pal
from palaestra import spaces
from palaestra.envs import registration
from palaestra.vec_env import SubprocVecEnv, make_vec_env
from palaestra.vector import AsyncVectorEnv
from palaestra.wrappers import TransformObservation

pytestmark = pytest.mark.timeout(120)

METHODS = ["fork", "spawn", "forkserver"]
START, OFFSET = 7.0, 100.0


def _kit() -> dict[str, Any]:
    """A lambda, a closure and a local env class, all defined here so none is importable."""
    start, offset = START, OFFSET  # captured: the workers must receive the values

    class Local(pal.Env):
        metadata = {"render_modes": []}

        def __init__(self) -> None:
            self.observation_space = spaces.Box(-1e3, 1e3, (2,), np.float32)
            self.action_space = spaces.Discrete(2)
            self.t = 0

        def reset(self, *, seed: int | None = None, options: dict | None = None) -> Any:
            super().reset(seed=seed)
            self.t = 0
            return np.array([start, 0.0], np.float32), {}

        def step(self, action: Any) -> Any:
            self.t += 1
            return np.array([start, self.t], np.float32), 1.0, self.t >= 5, False, {}

    def closure() -> Local:
        return Local()

    class LocalWrapper(pal.ObservationWrapper):
        def observation(self, obs: Any) -> Any:
            return obs * 2

    def shifted(env: Any) -> Any:
        return TransformObservation(env, lambda o: o + offset, env.observation_space)

    return {
        "Local": Local,
        "closure": closure,
        "lambda": lambda: shifted(Local()),
        "shift_wrapper": lambda env: shifted(env),
        "LocalWrapper": LocalWrapper,
    }


def _steps(reset: Any, step: Any, n: int = 3) -> np.ndarray:
    reset()
    obs = None
    for _ in range(n):
        obs = step()
    return np.asarray(obs)


@pytest.mark.parametrize("method", METHODS)
def test_async_vector_env(method: str) -> None:
    kit = _kit()
    with AsyncVectorEnv([kit["lambda"], kit["closure"], kit["Local"]], context=method) as envs:
        assert envs.engine.start_method == method
        obs = _steps(lambda: envs.reset(seed=0), lambda: envs.step(np.zeros(3, np.int64))[0])
    np.testing.assert_array_equal(obs, [[START + OFFSET, 3 + OFFSET], [START, 3], [START, 3]])


@pytest.mark.parametrize("method", METHODS)
def test_subproc_vec_env(method: str) -> None:
    kit = _kit()
    envs = SubprocVecEnv([kit["lambda"], kit["closure"], kit["Local"]], start_method=method)
    try:
        assert envs.engine.start_method == method
        envs.reset()
        for _ in range(3):
            envs.step_async(np.zeros(3, np.int64))
            obs = envs.step_wait()[0]
        np.testing.assert_array_equal(obs, [[START + OFFSET, 3 + OFFSET], [START, 3], [START, 3]])
    finally:
        envs.close()


@pytest.mark.parametrize("method", METHODS)
def test_make_vec_env_with_subproc(method: str) -> None:
    kit = _kit()
    # env_id a closure over a local class, wrapper_class a lambda: all three kinds at once
    envs = make_vec_env(
        kit["closure"],
        n_envs=2,
        wrapper_class=kit["shift_wrapper"],
        vec_env_cls=SubprocVecEnv,
        vec_env_kwargs={"start_method": method},
    )
    try:
        envs.reset()
        for _ in range(3):
            obs = envs.step(np.zeros(2, np.int64))[0]
        np.testing.assert_array_equal(obs, [[START + OFFSET, 3 + OFFSET]] * 2)
    finally:
        envs.close()
    # the report: palaestra's own env function for an id, on a plain install
    envs = make_vec_env("CartPole-v1", n_envs=2, seed=0, vec_env_cls=SubprocVecEnv,
                        vec_env_kwargs={"start_method": method})  # fmt: skip
    try:
        first = envs.reset()
        np.testing.assert_array_equal(first[1], pal.make("CartPole-v1").reset(seed=1)[0])
    finally:
        envs.close()


@pytest.fixture
def local_id() -> Any:
    env_id = "EnvFunctionsLocal-v0"
    kit = _kit()
    registration.register(env_id, entry_point=kit["Local"])
    try:
        yield env_id, kit
    finally:
        registration.registry.pop(env_id, None)


@pytest.mark.parametrize("method", METHODS)
def test_make_vec_async(method: str, local_id: Any) -> None:
    env_id, kit = local_id
    with pal.make_vec(
        env_id,
        num_envs=2,
        vectorization_mode="async",
        vector_kwargs={"context": method},
        wrappers=[kit["shift_wrapper"], kit["LocalWrapper"]],
    ) as envs:
        assert envs.engine.start_method == method
        obs = _steps(lambda: envs.reset(seed=0), lambda: envs.step(np.zeros(2, np.int64))[0])
    np.testing.assert_array_equal(obs, [[2 * (START + OFFSET), 2 * (3 + OFFSET)]] * 2)


_BLOCKED = ("gymnasium", "stable_baselines3")


def test_workers_need_neither_gymnasium_nor_sb3(tmp_path: Path) -> None:
    """A child interpreter where gymnasium and SB3 raise ImportError, in it and in its "spawn"
    workers (a stub package first on PYTHONPATH, which workers inherit): lambdas, closures and
    local classes still travel."""
    for name in _BLOCKED:
        stub = tmp_path / "blocked" / name
        stub.mkdir(parents=True)
        (stub / "__init__.py").write_text(f"raise ImportError('{name} is blocked by the test')\n")
    script = tmp_path / "user_script.py"
    script.write_text(
        textwrap.dedent(f"""
        import numpy as np
        import palaestra as pal
        from palaestra.vec_env import SubprocVecEnv, make_vec_env
        from palaestra.vector import AsyncVectorEnv

        def check_blocked():
            import importlib
            for name in {_BLOCKED!r}:
                try:
                    importlib.import_module(name)
                except ImportError:
                    continue
                raise AssertionError(name + " was importable")
            return pal.make("CartPole-v1")

        if __name__ == "__main__":
            check_blocked()
            offset = 5.0
            with AsyncVectorEnv([check_blocked, lambda: check_blocked()], context="spawn") as e:
                e.reset(seed=0)
            def closure():
                from palaestra.wrappers import TransformObservation
                env = check_blocked()
                return TransformObservation(env, lambda o: o + offset, None)
            v = make_vec_env(closure, n_envs=2, vec_env_cls=SubprocVecEnv,
                             vec_env_kwargs={{"start_method": "spawn"}})
            obs = v.reset()
            v.close()
            v = make_vec_env("CartPole-v1", n_envs=2, vec_env_cls=SubprocVecEnv,
                             vec_env_kwargs={{"start_method": "forkserver"}})
            v.reset()
            v.close()
            print("ok", obs.shape, bool(np.all(np.abs(obs - offset) < 0.06)))
        """)
    )
    env = dict(os.environ)
    paths = [str(tmp_path / "blocked")] + [p for p in sys.path if p]
    env["PYTHONPATH"] = os.pathsep.join(paths)
    out = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, env=env, timeout=100
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok (2, 4) True", out.stdout + out.stderr
