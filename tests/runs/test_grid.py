"""Grids of runs: locally and as Ray tasks (a local Ray with two CPUs), with the same bits."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from palaestra.runs import RunError, RunSpec
from palaestra.runs.grid import GridRun, connect_ray, run_grid

ray = pytest.importorskip("ray")

# Imported by the Ray workers from the folder the fixture puts on their PYTHONPATH.
FAULTS = '''
import os, signal
import palaestra as gym

MARKER = {marker!r}


class KillOnce(gym.Wrapper):
    """Kills its worker process at the first reset of the first attempt."""

    def reset(self, **kwargs):
        if not os.path.exists(MARKER):
            open(MARKER, "w").close()
            os.kill(os.getpid(), signal.SIGKILL)
        return self.env.reset(**kwargs)


class Boom(gym.Wrapper):
    def reset(self, **kwargs):
        raise RuntimeError("boom at reset")
'''


@pytest.fixture(scope="module")
def local_ray(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A local Ray with two CPUs (what CI has); the workers can import ``faults_mod``."""
    folder = tmp_path_factory.mktemp("mods")
    (folder / "faults_mod.py").write_text(FAULTS.format(marker=str(folder / "killed")))
    old = os.environ.get("PYTHONPATH")
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(folder), old) if p)
    sys.path.insert(0, str(folder))
    if ray.is_initialized():
        ray.shutdown()
    connect_ray(None, num_cpus=2)
    yield folder
    ray.shutdown()
    sys.path.remove(str(folder))
    if old is None:
        os.environ.pop("PYTHONPATH", None)
    else:
        os.environ["PYTHONPATH"] = old


def _grid(root: Path) -> list[GridRun]:
    runs = []
    for algo, steps in (("ppo", 512), ("a2c", 480)):
        for seed in (0, 1):
            spec = RunSpec.from_preset(algo, "CartPole-v1", seed=seed, n_timesteps=steps)
            runs.append(GridRun(algo, spec, root / algo / f"seed{seed}"))
    return runs


def _weights(run_dir: Path) -> dict[str, np.ndarray]:
    from palaestra.runs import load_model

    model = load_model(run_dir / "model.zip")
    return {k: v.detach().numpy().copy() for k, v in model.policy.state_dict().items()}


def test_ray_grid_trains_the_same_bits_as_the_local_one(local_ray: Path, tmp_path: Path) -> None:
    local = run_grid(_grid(tmp_path / "local"), "local")
    remote = run_grid(_grid(tmp_path / "ray"), "ray")
    assert [o.status for o in local] == [o.status for o in remote] == ["trained"] * 4
    for a, b in zip(local, remote):
        assert a.run.run_dir.name == b.run.run_dir.name
        weights = _weights(b.run.run_dir)
        for name, value in _weights(a.run.run_dir).items():
            np.testing.assert_array_equal(value, weights[name])
        episodes = [
            (r / "episodes.csv").read_text().splitlines() for r in (a.run.run_dir, b.run.run_dir)
        ]
        # steps, return, length, terminated are equal; the last column is wall-clock time
        assert [row.rsplit(",", 1)[0] for row in episodes[0]] == [
            row.rsplit(",", 1)[0] for row in episodes[1]
        ]
    again = run_grid(_grid(tmp_path / "ray"), "ray")
    assert [o.status for o in again] == ["reused"] * 4


def test_a_killed_worker_is_retried_and_a_raising_run_is_reported(
    local_ray: Path, tmp_path: Path
) -> None:
    base = {"n_envs": 1}
    runs = [
        GridRun("killed", RunSpec.from_preset("a2c", "CartPole-v1", seed=0, n_timesteps=200,
                overrides={**base, "env_wrapper": "faults_mod:KillOnce"}), tmp_path / "k"),
        GridRun("boom", RunSpec.from_preset("a2c", "CartPole-v1", seed=0, n_timesteps=200,
                overrides={**base, "env_wrapper": "faults_mod:Boom"}), tmp_path / "b"),
        GridRun("fine", RunSpec.from_preset("a2c", "CartPole-v1", seed=0, n_timesteps=200,
                overrides=base), tmp_path / "f"),
    ]  # fmt: skip
    killed, boom, fine = run_grid(runs, "ray")
    assert (local_ray / "killed").exists()  # the first attempt did die
    assert killed.status == "trained" and (tmp_path / "k" / "model.zip").is_file()
    assert boom.status == "failed" and "RuntimeError: boom at reset" in (boom.error or "")
    assert not (tmp_path / "b").exists()  # nothing half-written
    assert fine.status == "trained"
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]
    assert leftovers == []  # the killed attempt's scratch folder went with the retry


def test_compare_runs_on_ray_from_the_command_line(local_ray: Path, tmp_path: Path) -> None:
    from tests.cli.conftest import run_cli

    r = run_cli("compare", "algos", "--env", "CartPole-v1", "--algos", "a2c", "--seeds", 0, 1,
                "--timesteps", 320, "--runs-dir", tmp_path / "runs", "--out", tmp_path / "c.png",
                "--backend", "ray")  # fmt: skip
    assert r.code == 0, r.err
    assert "a2c seed 1: training -> " in r.out
    table = [line.split() for line in r.out.splitlines()]
    assert ["a2c", "2"] in [row[:2] for row in table]


def test_bad_backend_and_address_are_one_line_errors(tmp_path: Path) -> None:
    runs = _grid(tmp_path)[:1]
    with pytest.raises(RunError, match="unknown backend 'dask'"):
        run_grid(runs, "dask")
    with pytest.raises(RunError, match="--address applies to the ray backend"):
        run_grid(runs, "local", address="auto")
    from palaestra.runs.grid import _probe

    with pytest.raises(RunError, match=r"cannot reach a Ray cluster at '127\.0\.0\.1:1'"):
        _probe("127.0.0.1:1")
    with pytest.raises(RunError, match="cannot read the Ray address 'nowhere'"):
        _probe("nowhere")


def test_an_unfinished_run_folder_stops_the_grid_before_training(tmp_path: Path) -> None:
    runs = _grid(tmp_path)
    runs[1].run_dir.mkdir(parents=True)
    (runs[1].run_dir / "config.json").write_text("{}")
    with pytest.raises(RunError, match="holds an unfinished run"):
        run_grid(runs, "local")
    assert not runs[0].run_dir.exists()


def test_a_sweep_runs_its_trials_as_ray_tasks(local_ray: Path, tmp_path: Path) -> None:
    """Trials report their evaluations to the study through the SQLite file while they run
    in Ray workers; the driver tells the study how each ended."""
    pytest.importorskip("optuna")
    from palaestra.runs.space import space_from_mapping
    from palaestra.runs.sweep import run_sweep

    space = space_from_mapping({"n_steps": [8, 16], "gamma": {"low": 0.9, "high": 0.99}}, "a2c")
    result = run_sweep(space, "a2c", "CartPole-v1", trials=4, seeds=2, out=tmp_path,
                       n_timesteps=320, backend="ray", evaluations=2, eval_episodes=2)  # fmt: skip
    assert result.ran == 4 and len(result.trials) == 4
    assert {row["state"] for row in result.trials} <= {"complete", "pruned"}
    import optuna

    study = optuna.load_study(
        study_name="a2c-CartPole-v1", storage=f"sqlite:///{tmp_path}/study.db"
    )
    reported = [t for t in study.get_trials() if t.intermediate_values]
    assert reported  # the workers' evaluations reached the study
    assert result.best_file is not None and result.best_file.is_file()


def test_a_grid_folder_another_process_writes_is_refused(tmp_path: Path) -> None:
    from tests.runs.test_lock import holder

    runs = _grid(tmp_path)
    proc = holder(tmp_path / "a2c")  # e.g. a second `compare` with the same --runs-dir
    try:
        with pytest.raises(RunError, match=f"^{tmp_path / 'a2c'} is in use by process {proc.pid} "):
            run_grid(runs, "local")
        assert not (tmp_path / "ppo").exists() or not any((tmp_path / "ppo").iterdir())
    finally:
        proc.kill()
        proc.wait()


def test_a_sweep_folder_another_process_writes_is_refused(tmp_path: Path) -> None:
    pytest.importorskip("optuna")
    from tests.runs.test_lock import holder

    from palaestra.runs.space import space_from_mapping
    from palaestra.runs.sweep import run_sweep

    proc = holder(tmp_path / "sw")
    try:
        space = space_from_mapping({"n_steps": [8, 16]}, "a2c")
        with pytest.raises(RunError, match=f"in use by process {proc.pid} .*this sweep folder"):
            run_sweep(space, "a2c", "CartPole-v1", 1, 1, tmp_path / "sw", 64)
        assert sorted(p.name for p in (tmp_path / "sw").iterdir()) == [".palaestra.lock"]
    finally:
        proc.kill()
        proc.wait()


def test_a_stopped_ray_sweep_cancels_its_trials_and_says_why(
    local_ray: Path, tmp_path: Path
) -> None:
    pytest.importorskip("optuna")
    from palaestra.runs.space import space_from_mapping
    from palaestra.runs.sweep import run_sweep

    told: list[dict] = []

    def stop() -> str | None:  # a SIGTERM once the first trial is in
        return "interrupted by SIGTERM" if told else None

    space = space_from_mapping({"n_steps": [8, 16]}, "a2c")
    result = run_sweep(space, "a2c", "CartPole-v1", trials=6, seeds=1, out=tmp_path,
                       n_timesteps=2000, backend="ray", evaluations=0, eval_episodes=1,
                       on_trial=told.append, stop_requested=stop)  # fmt: skip
    assert result.stopped == "interrupted by SIGTERM"
    assert told[0]["state"] == "complete"
    cancelled = told[1:]
    assert cancelled and all(row["state"] == "interrupted" for row in cancelled)
    assert {row["reason"] for row in cancelled} == {
        "interrupted by SIGTERM: cancelled while it ran on Ray"
    }
    assert result.ran == 1 and len(result.trials) == 1 + len(cancelled)
