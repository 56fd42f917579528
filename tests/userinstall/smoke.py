"""The user-install smoke run: what a user does right after ``pip install ".[extras]"``, run in
a virtualenv that holds palaestra and its declared dependencies only (no gymnasium, no
stable-baselines3, no pytest): ``tests/userinstall/check.sh`` builds that venv from a clone of
the commit under test and runs this file with it.

Each check is a plain function; the run prints one line per check and ends with
``N passed, N failed`` (exit 1 on any failure). It runs in a scratch folder given as the first
argument (the user's working folder: their ``mygrid.py`` lands there).

Run::

    bash tests/userinstall/check.sh          # builds the venv, then runs this file in it
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import textwrap
import time
import traceback
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]  # the clone: examples/ come from here
CHECKS: list[Callable[[Path], None]] = []
BIN = Path(sys.executable).parent


def check(fn: Callable[[Path], None]) -> Callable[[Path], None]:
    CHECKS.append(fn)
    return fn


def palaestra(cwd: Path, *args: str, ok: bool = True, timeout: float = 300) -> str:
    """The installed ``palaestra`` console script; its stdout + stderr. ``ok``: rc must be 0
    (else rc must be non-zero)."""
    proc = subprocess.run(
        [str(BIN / "palaestra"), *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, "PYTHONPATH": ""},
    )
    out = proc.stdout + proc.stderr
    if ok and proc.returncode != 0:
        raise AssertionError(f"palaestra {' '.join(args)} -> rc {proc.returncode}\n{out[-3000:]}")
    if not ok and proc.returncode == 0:
        raise AssertionError(f"palaestra {' '.join(args)} succeeded, expected a refusal\n{out}")
    return out


def python(cwd: Path, code: str, timeout: float = 300) -> str:
    """``code`` run as a script file (so spawn/forkserver workers can re-import its main)."""
    script = cwd / f"user_script_{abs(hash(code)) % 10**8}.py"
    script.write_text(textwrap.dedent(code), encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, str(script)], cwd=cwd, capture_output=True, text=True, timeout=timeout
    )
    if proc.returncode != 0:
        raise AssertionError(f"{script.name} -> rc {proc.returncode}\n{proc.stderr[-3000:]}")
    return proc.stdout


# -- the install itself ---------------------------------------------------------------------------
@check
def no_reference_libraries(cwd: Path) -> None:
    """The proof is void if the reference stacks (or the dev tools) crept in."""
    present = [
        name
        for name in ("gymnasium", "stable_baselines3", "pytest", "hypothesis", "shimmy")
        if importlib.util.find_spec(name) is not None
    ]
    assert not present, f"the user venv holds {present}"
    import palaestra

    assert "site-packages" in palaestra.__file__, palaestra.__file__


@check
def import_is_light(cwd: Path) -> None:
    out = python(
        cwd,
        """
        import sys, palaestra
        print(sorted(m for m in ("torch", "ray", "optuna", "Box2D", "pygame", "matplotlib")
                     if m in sys.modules))
        """,
    )
    assert out.strip() == "[]", out


# -- vector envs with the functions users write ---------------------------------------------------
@check
def vector_envs_take_lambdas_and_closures(cwd: Path) -> None:
    out = python(
        cwd,
        """
        import multiprocessing as mp
        import numpy as np
        import palaestra as gym
        from palaestra.vec_env import SubprocVecEnv, make_vec_env
        from palaestra.vector import AsyncVectorEnv

        def closure_maker(length):
            def make():
                return gym.make("CartPole-v1", max_episode_steps=length)
            return make

        class LocalEnv(gym.Env):
            observation_space = gym.spaces.Box(-1, 1, (2,), np.float32)
            action_space = gym.spaces.Discrete(2)
            def reset(self, *, seed=None, options=None):
                super().reset(seed=seed)
                return np.zeros(2, np.float32), {}
            def step(self, action):
                return np.full(2, action, np.float32), 1.0, False, False, {}

        if __name__ == "__main__":
            for method in mp.get_all_start_methods():  # fork, spawn, forkserver on Linux
                fns = [lambda: gym.make("CartPole-v1"), closure_maker(20)]
                venv = SubprocVecEnv(fns, start_method=method)
                venv.seed(0)
                venv.reset()
                obs, rewards, dones, infos = venv.step(np.array([1, 0]))
                assert obs.shape == (2, 4) and rewards.shape == (2,), (obs.shape, rewards.shape)
                venv.close()
                venv = SubprocVecEnv([lambda: LocalEnv(), lambda: LocalEnv()], start_method=method)
                venv.reset()
                obs, rewards, dones, infos = venv.step(np.array([1, 0]))
                assert obs.tolist() == [[1, 1], [0, 0]], obs
                venv.close()
                envs = AsyncVectorEnv(fns[:2], context=method)
                obs, infos = envs.reset(seed=0)
                obs, r, term, trunc, infos = envs.step(np.array([1, 0]))
                assert obs.shape == (2, 4), obs.shape
                envs.close()
                venv = make_vec_env("CartPole-v1", n_envs=2, seed=0, vec_env_cls=SubprocVecEnv,
                                    vec_env_kwargs={"start_method": method})
                venv.reset()
                venv.step(np.array([0, 1]))
                venv.close()
                print("ok", method)
            envs = gym.make_vec("CartPole-v1", num_envs=2, vectorization_mode="async")
            envs.reset(seed=0)
            envs.close()
        """,
    )
    assert out.split() == ["ok", "fork", "ok", "spawn", "ok", "forkserver"], out


# -- the command line on a built-in env -----------------------------------------------------------
@check
def cli_on_a_builtin_env(cwd: Path) -> None:
    run = cwd / "runs" / "ppo-cartpole"
    out = palaestra(
        cwd, "train", "ppo", "CartPole-v1", "--seed", "0", "--timesteps", "2048",
        "--out", str(run), "--progress", "none", "--eval-episodes", "2", "--eval-freq", "1024",
    )  # fmt: skip
    assert "trained ppo on CartPole-v1" in out, out
    rows = (run / "evaluations.csv").read_text().splitlines()
    assert [row.split(",")[0] for row in rows[1:]] == ["1024", "2048"], rows
    for name in ("config.json", "model.zip", "episodes.csv", "progress.csv", "best_model.zip"):
        assert (run / name).is_file(), name
    out = palaestra(cwd, "eval", str(run), "--episodes", "3")
    assert "mean return" in out, out
    palaestra(cwd, "record", str(run), "--out", str(cwd / "cartpole.gif"))
    assert (cwd / "cartpole.gif").stat().st_size > 1000
    out = palaestra(cwd, "train", "--resume", str(run), "--timesteps", "4096", "--progress", "none")
    assert json.loads((run / "status.json").read_text())["num_timesteps"] >= 4096, out


@check
def mujoco_env_trains_records_and_runs_in_workers(cwd: Path) -> None:
    run = cwd / "runs" / "sac-inverted-pendulum"
    out = palaestra(
        cwd, "train", "sac", "InvertedPendulum-v5", "--seed", "0", "--timesteps", "300",
        "--out", str(run), "--progress", "none", "--eval-episodes", "1",
    )  # fmt: skip
    assert "trained sac on InvertedPendulum-v5" in out, out
    palaestra(cwd, "record", str(run), "--out", str(cwd / "pendulum.gif"))
    assert (cwd / "pendulum.gif").stat().st_size > 1000
    # the models are package data, found from worker processes started by spawn
    out = python(
        cwd,
        """
        import palaestra as gym

        if __name__ == "__main__":
            envs = gym.make_vec("HalfCheetah-v5", num_envs=2, vectorization_mode="async",
                                vector_kwargs={"context": "spawn"})
            obs, _ = envs.reset(seed=0)
            obs, reward, *_ = envs.step(envs.action_space.sample())
            envs.close()
            print(obs.shape, reward.shape)
    """,
    )
    assert "(2, 17) (2,)" in out, out


@check
def cli_compare_and_sweep(cwd: Path) -> None:
    out = palaestra(
        cwd, "compare", "algos", "--env", "CartPole-v1", "--algos", "a2c", "ppo",
        "--seeds", "0", "1", "--timesteps", "1024", "--runs-dir", str(cwd / "cmp"),
        "--out", str(cwd / "cmp" / "compare.png"),
    )  # fmt: skip
    assert (cwd / "cmp" / "compare.png").stat().st_size > 1000, out
    summary = json.loads((cwd / "cmp" / "summary.json").read_text())
    for variant in summary["variants"]:
        low, high = variant["interval"]
        values = variant["per_seed_values"]
        assert min(values) <= low <= high <= max(values), variant
    assert (cwd / "cmp" / "curves.csv").is_file()
    (cwd / "space.yaml").write_text("learning_rate: {low: 1.0e-4, high: 1.0e-3, log: true}\n")
    out = palaestra(
        cwd, "sweep", str(cwd / "space.yaml"), "--algo", "ppo", "--env", "CartPole-v1",
        "--trials", "2", "--timesteps", "512", "--out", str(cwd / "sweep"),
    )  # fmt: skip
    for name in ("study.db", "trials.csv", "best.yaml"):
        assert (cwd / "sweep" / name).is_file(), f"{name}\n{out}"
    palaestra(
        cwd, "train", "ppo", "CartPole-v1", "--config", str(cwd / "sweep" / "best.yaml"),
        "--timesteps", "512", "--out", str(cwd / "from-best"), "--progress", "none",
        "--eval-episodes", "0",
    )  # fmt: skip


# -- the command line on the user's own env module ------------------------------------------------
MYGRID = '''
"""A user's env module: a 1-D corridor, registered on import."""
import numpy as np
import palaestra as gym


class GridWorld(gym.Env):
    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, size=5, render_mode=None):
        self.size, self.render_mode = size, render_mode
        self.observation_space = gym.spaces.Box(0, size, (1,), np.float32)
        self.action_space = gym.spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.pos = 0
        return np.array([self.pos], np.float32), {}

    def step(self, action):
        self.pos = max(0, self.pos + (1 if action == 1 else -1))
        done = self.pos >= self.size
        return np.array([self.pos], np.float32), float(done) - 0.01, done, False, {}

    def render(self):
        frame = np.zeros((16, 16 * (self.size + 1), 3), np.uint8)
        frame[:, 16 * self.pos : 16 * (self.pos + 1)] = 255
        return frame


gym.register("GridWorld-v0", entry_point=GridWorld, max_episode_steps=50)
'''


@check
def cli_on_a_user_env_module(cwd: Path) -> None:
    user = cwd / "project"
    user.mkdir()
    (user / "mygrid.py").write_text(MYGRID, encoding="utf-8")
    run = user / "runs" / "grid"
    out = palaestra(
        user, "train", "ppo", "mygrid:GridWorld-v0", "--seed", "0", "--timesteps", "1024",
        "--out", str(run), "--progress", "none", "--eval-episodes", "2",
        "--env-kwargs", "size:4",
    )  # fmt: skip
    assert "MlpPolicy" in out, out  # no preset: the policy chosen from the space is printed
    assert json.loads((run / "config.json").read_text())["env_kwargs"] == {"size": 4}
    refused = palaestra(user, "eval", str(run), ok=False)
    assert "--allow-import mygrid" in refused, refused
    out = palaestra(user, "eval", str(run), "--episodes", "2", "--allow-import", "mygrid")
    assert "mean return" in out, out
    palaestra(user, "record", str(run), "--out", str(user / "grid.gif"), "--allow-import", "mygrid")
    (user / "shaping.py").write_text(
        "import palaestra as gym\n\n"
        "class Shaped(gym.RewardWrapper):\n"
        "    def reward(self, reward):\n"
        "        return 2 * reward\n",
        encoding="utf-8",
    )
    (user / "shaped.yaml").write_text("env_wrapper: shaping:Shaped\n", encoding="utf-8")
    train = ["train", "ppo", "CartPole-v1", "--config", "shaped.yaml", "--timesteps", "256",
             "--progress", "none", "--eval-episodes", "0"]  # fmt: skip
    refused = palaestra(user, *train, "--out", "runs/shaped", ok=False)
    assert "--allow-import shaping" in refused and not (user / "runs" / "shaped").exists(), refused
    palaestra(user, *train, "--out", "runs/shaped", "--allow-import", "shaping")
    elsewhere = cwd / "elsewhere"
    elsewhere.mkdir()
    missing = palaestra(elsewhere, "eval", str(run), "--allow-import", "mygrid", ok=False)
    assert "mygrid" in missing and "--allow-import" in missing, missing


# -- the examples, as a user runs them ------------------------------------------------------------
@check
def examples_quick(cwd: Path) -> None:
    for example in sorted((ROOT / "examples").glob("*.py")):
        proc = subprocess.run(
            [sys.executable, str(example), "--quick", "--out", str(cwd / example.stem)],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=300,
        )
        if proc.returncode != 0 and "unrecognized arguments: --out" in proc.stderr:
            proc = subprocess.run(
                [sys.executable, str(example), "--quick"],
                cwd=cwd,
                capture_output=True,
                text=True,
                timeout=300,
            )
        assert proc.returncode == 0, f"{example.name}: rc {proc.returncode}\n{proc.stderr[-3000:]}"


def main() -> int:
    cwd = Path(sys.argv[1]).resolve()
    cwd.mkdir(parents=True, exist_ok=True)
    passed = failed = 0
    start = time.perf_counter()
    for fn in CHECKS:
        t0 = time.perf_counter()
        try:
            fn(cwd)
        except Exception:
            failed += 1
            print(f"FAIL {fn.__name__} ({time.perf_counter() - t0:.1f} s)", flush=True)
            print(textwrap.indent(traceback.format_exc(), "    "), flush=True)
        else:
            passed += 1
            print(f"ok   {fn.__name__} ({time.perf_counter() - t0:.1f} s)", flush=True)
    print(f"user-install smoke run: {time.perf_counter() - start:.0f} s")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
