"""Worker processes from a user's script, run as a script (``python script.py``).

The "spawn" and "forkserver" start methods run the script again in every worker; these tests
write real script files and run them in a fresh interpreter, as a user would.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

import palaestra

SRC = Path(palaestra.__file__).resolve().parents[1]
pytestmark = pytest.mark.timeout(120)

# The tutorial's SubprocVecEnv block as a user pastes it into a file, imports made palaestra's.
TUTORIAL_NO_GUARD = """
from palaestra.vec_env import SubprocVecEnv
import palaestra as gym
def make_env():
    return gym.make('MountainCar-v0')
# Create 4 environments in separate processes
envs = [make_env for _ in range(4)]
vec_env = SubprocVecEnv(envs)
print("made", vec_env.reset().shape)
"""

ASYNC_NO_GUARD = """
import sys
import palaestra as gym
from palaestra.vector import AsyncVectorEnv
def make_env():
    return gym.make('MountainCar-v0')
context = None if sys.argv[1] == "default" else sys.argv[1]
envs = AsyncVectorEnv([make_env for _ in range(2)], context=context)
print("made", envs.reset()[0].shape)
envs.close()
"""

BOOM = """
import json
import numpy as np
import palaestra as gym
from palaestra import spaces
from palaestra.vec_env import SubprocVecEnv
from palaestra.vector import AsyncVectorEnv

class BoomError(Exception):
    pass

class Boomy(gym.Env):
    def __init__(self):
        self.observation_space = spaces.Box(-1, 1, (1,), np.float32)
        self.action_space = spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(1, np.float32), {}

    def step(self, action):
        if action == 1:
            raise BoomError(f"boom at action {int(action)}")
        return np.zeros(1, np.float32), 0.0, False, False, {}

gym.register("Boomy-v0", entry_point=Boomy)

def make_env():
    return Boomy()

if __name__ == "__main__":
    faces = {
        "SubprocVecEnv": lambda m: SubprocVecEnv([make_env] * 2, start_method=m),
        "SubprocVecEnv/registry": lambda m: SubprocVecEnv(
            [lambda: gym.make("Boomy-v0")] * 2, start_method=m
        ),
        "AsyncVectorEnv": lambda m: AsyncVectorEnv([make_env] * 2, context=m),
    }
    cases = [  # None: each face's default start method ("forkserver"; the platform's)
        ("SubprocVecEnv", None), ("SubprocVecEnv", "spawn"), ("SubprocVecEnv", "fork"),
        ("SubprocVecEnv/registry", None), ("AsyncVectorEnv", None),
        ("AsyncVectorEnv", "forkserver"),
    ]
    caught = {}
    for face, method in cases:
        venv = faces[face](method)
        venv.reset()
        try:
            venv.step(np.array([0, 1]))
        except BoomError as e:
            caught[f"{face} {method}"] = ["BoomError", type(e) is BoomError, str(e)]
        except Exception as e:
            caught[f"{face} {method}"] = [type(e).__name__, False, str(e)]
        venv.close()
    print(json.dumps(caught))
"""


def run_script(tmp_path: Path, text: str, *args: str) -> tuple[subprocess.CompletedProcess, float]:
    """``python script.py *args`` in a fresh interpreter importing this palaestra."""
    script = tmp_path / "script.py"
    script.write_text(text, encoding="utf-8")
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
    }
    start = time.monotonic()
    proc = subprocess.run(
        [sys.executable, str(script), *args],
        capture_output=True,
        text=True,
        timeout=90,
        cwd=tmp_path,
        env=env,
    )
    return proc, time.monotonic() - start


def assert_one_line_guard_error(proc: subprocess.CompletedProcess, who: str, method: str) -> None:
    err = proc.stderr
    assert proc.returncode == 1, err
    assert "made" not in proc.stdout
    # One short traceback from the user's own line, not a page from every worker.
    assert err.count("Traceback") == 1, err
    assert "bootstrapping phase" not in err and "spawn.py" not in err, err
    assert len(err.splitlines()) <= 12, err
    last = err.splitlines()[-1]
    assert last.startswith("palaestra.vector.process_engine.MissingMainGuardError: "), last
    assert f"each worker process runs {proc.args[1]} again (start method '{method}')" in last
    assert f"reached this {who} at its top level" in last
    assert last.endswith('under `if __name__ == "__main__":`'), last


def test_tutorial_subproc_block_without_main_guard_fails_with_one_line(tmp_path):
    proc, seconds = run_script(tmp_path, TUTORIAL_NO_GUARD)
    assert_one_line_guard_error(proc, "SubprocVecEnv", "forkserver")
    assert seconds < 10


@pytest.mark.parametrize("method", ["spawn", "forkserver"])
def test_async_without_main_guard_fails_with_one_line(tmp_path, method):
    proc, _ = run_script(tmp_path, ASYNC_NO_GUARD, method)
    assert_one_line_guard_error(proc, "AsyncVectorEnv", method)


def test_async_without_main_guard_runs_where_the_workers_fork(tmp_path):
    # AsyncVectorEnv keeps Gymnasium's default, the platform's start method: "fork" on Linux
    # before Python 3.14, where workers are copies of the parent and nothing runs twice.
    import multiprocessing as mp

    if mp.get_start_method() != "fork":
        pytest.skip("the platform's default start method is not fork")
    proc, _ = run_script(tmp_path, ASYNC_NO_GUARD, "default")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "made (2, 2)\n"


def test_exception_class_of_the_script_reaches_the_parent_by_every_start_method(tmp_path):
    proc, _ = run_script(tmp_path, BOOM)
    assert proc.returncode == 0, proc.stderr
    caught = json.loads(proc.stdout.strip().splitlines()[-1])
    assert len(caught) == 6
    for case, (name, same_class, message) in caught.items():
        assert (name, same_class, message) == ("BoomError", True, "boom at action 1"), case
