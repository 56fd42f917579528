"""The run API called directly: what ``tests/cli`` checks through ``palaestra train / eval /
compare``, here as calls (results, the files written, the errors and their messages)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from palaestra.runs import (
    RunError,
    RunSpec,
    evaluate_run,
    open_resume,
    open_run,
    resolve_spec,
    train_run,
)
from palaestra.runs.compare import (
    default_labels,
    group_runs,
    profiles,
    summarize,
    write_curves,
    write_summary,
)
from palaestra.runs.curves import variant_band
from palaestra.runs.grid import GridRun, Outcome, run_grid

TINY = 256  # one PPO rollout of the CartPole preset (8 envs x 32 steps)


def _tiny(seed: int = 0, **top: Any) -> RunSpec:
    return RunSpec.from_preset("ppo", "CartPole-v1", seed=seed, n_timesteps=TINY, **top)


def _status(run_dir: Path) -> dict[str, Any]:
    return dict(json.loads((run_dir / "status.json").read_text()))


# -- resolve_spec -------------------------------------------------------------------------------
def test_resolve_spec_applies_assignments_as_set_does() -> None:
    spec, notes = resolve_spec(
        "ppo", "CartPole-v1", assignments=["gamma=0.9", "policy_kwargs.net_arch=[16]"], seed=4
    )
    assert spec.hyperparams["gamma"] == 0.9 and spec.hyperparams["policy_kwargs"]["net_arch"] == [
        16
    ]
    assert spec.seed == 4 and spec.preset == "default" and notes == []
    assert RunSpec.from_json(spec.to_json()) == spec


def test_resolve_spec_without_a_preset_says_so() -> None:
    spec, notes = resolve_spec("a2c", "FrozenLake-v1")
    assert spec.preset is None
    assert notes == [
        "no preset for a2c on FrozenLake-v1: using the A2C defaults (SB3's) with MlpPolicy, "
        "chosen for its Discrete observations"
    ]


@pytest.mark.parametrize(
    ("kwargs", "error", "line"),
    [
        ({"assignments": ["gamma"]}, RunError,
         "--set 'gamma' is not key=value (e.g. --set learning_rate=0.001)"),
        ({"n_envs": 10**6}, RunError, "settings: n_envs must be an integer from 1 to 4096, "
         "got 1000000 (check --set, --n-envs, --timesteps and the config file)"),
        ({"bogus": 1}, TypeError, "unexpected keyword argument(s) ['bogus']"),
    ],
)  # fmt: skip
def test_resolve_spec_errors_name_the_value(
    kwargs: dict[str, Any], error: type[Exception], line: str
) -> None:
    with pytest.raises(error) as info:
        resolve_spec("ppo", "CartPole-v1", **kwargs)
    assert (info.value.line() if isinstance(info.value, RunError) else str(info.value)) == line


# -- open_run / train_run ------------------------------------------------------------------------
def test_train_run_writes_the_run_folder(tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    result = train_run(_tiny(), run_dir, eval_freq=128, eval_episodes=2)
    assert (result.status, result.num_timesteps, result.session_steps) == ("finished", TINY, TINY)
    assert result.run_dir == run_dir and result.spec == _tiny()
    for name in ("config.json", "status.json", "episodes.csv", "progress.csv", "model.zip",
                 "evaluations.csv", "best_model.zip"):  # fmt: skip
        assert (run_dir / name).is_file(), name
    config = json.loads((run_dir / "config.json").read_text())
    assert config["evaluation"] == {"every": 128, "episodes": 2}
    assert RunSpec.from_config(config) == _tiny()
    status = _status(run_dir)
    assert status["status"] == "finished" and status["num_timesteps"] == TINY
    with open(run_dir / "evaluations.csv", newline="") as f:
        assert [int(r["timesteps"]) for r in csv.DictReader(f)] == [128, 256]
    assert not list(run_dir.glob(".*"))  # no lock or temporary file left behind


def test_open_run_refuses_a_folder_that_holds_a_run(tmp_path: Path) -> None:
    with open_run(_tiny(), tmp_path / "run") as run:
        assert run.final_timesteps == TINY and not run.resumed
    with pytest.raises(RunError) as info:  # the lock is released: the refusal is the run's
        open_run(_tiny(), tmp_path / "run")
    assert info.value.line() == (
        f"{tmp_path / 'run'} already holds a run "
        f"(choose another --out, or --resume {tmp_path / 'run'})"
    )


def test_open_run_with_settings_the_algorithm_refuses_leaves_no_folder(tmp_path: Path) -> None:
    spec = RunSpec("dqn", "Pendulum-v1", n_timesteps=100)
    with pytest.raises(RunError, match=r"^cannot train dqn on Pendulum-v1: DQN does not support"):
        open_run(spec, tmp_path / "run")
    assert not (tmp_path / "run").exists()


def test_train_refuses_a_negative_checkpoint_interval(tmp_path: Path) -> None:
    with pytest.raises(RunError) as info:
        train_run(_tiny(), tmp_path / "run", checkpoint_every=-1)
    assert info.value.line() == "checkpoint_every must be >= 0, got -1 (e.g. 10000)"
    with pytest.raises(RunError, match="already holds a run"):  # config.json was written
        open_run(_tiny(), tmp_path / "run")


# -- open_resume ----------------------------------------------------------------------------------
def test_open_resume_extends_the_budget_and_says_how(tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    train_run(_tiny(), run_dir)
    with open_resume(run_dir, n_timesteps=2 * TINY) as run:
        assert run.resumed and run.model.num_timesteps == TINY and run.spec.n_timesteps == 2 * TINY
        assert any(
            n.startswith(f"extending the run from {TINY} to {2 * TINY} steps") for n in run.notes
        )
        result = run.train()
    assert (result.status, result.num_timesteps, result.session_steps) == (
        "finished", 2 * TINY, TINY
    )  # fmt: skip
    assert json.loads((run_dir / "config.json").read_text())["n_timesteps"] == 2 * TINY


def test_open_resume_errors(tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    with pytest.raises(RunError) as info:
        open_resume(run_dir)
    assert info.value.line() == f"no run config at '{run_dir / 'config.json'}' (check the path)"
    train_run(_tiny(), run_dir)
    with pytest.raises(RunError) as info:
        open_resume(run_dir, expect={"algo": "dqn"})
    assert info.value.line() == (
        f"{run_dir} is a run of ppo, not dqn (palaestra train --resume {run_dir})"
    )
    with pytest.raises(RunError) as info:
        open_resume(run_dir)
    assert info.value.line() == (
        f"{run_dir} already trained {TINY} of its {TINY} steps "
        f"(pass --timesteps larger than {TINY} to train further)"
    )
    with open_resume(run_dir, n_timesteps=TINY + 1):  # each failure released the lock
        pass


# -- evaluate_run ---------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    run_dir = tmp_path_factory.mktemp("eval") / "run"
    train_run(_tiny(), run_dir)
    return run_dir


def test_evaluate_run_is_deterministic_per_seed(trained: Path) -> None:
    first = evaluate_run(trained, episodes=3, seed=7)
    again = evaluate_run(trained / "model.zip", episodes=3, seed=7)
    assert first.returns == again.returns and len(first.returns) == 3
    assert first.lengths == [int(r) for r in first.returns]  # CartPole: +1 per step
    assert first.env_id == "CartPole-v1" and first.path == trained / "model.zip"
    assert first.mean_return == pytest.approx(np.mean(first.returns))
    assert first.success_rate is None  # CartPole has no goal
    assert first.frames == []


def test_evaluate_run_records_a_frame_per_step_and_reset(trained: Path) -> None:
    played = evaluate_run(trained, episodes=2, seed=1, record=True)
    assert len(played.frames) == sum(played.lengths) + 2
    assert played.frames[0].shape == (400, 600, 3) and played.fps == 50


@pytest.mark.parametrize(
    ("kwargs", "line"),
    [
        ({"episodes": 0}, "episodes must be at least 1, got 0 (e.g. --episodes 10)"),
        ({"env_id": "Pendulum-v1"}, None),
    ],
)
def test_evaluate_run_errors(trained: Path, kwargs: dict[str, Any], line: str | None) -> None:
    with pytest.raises(RunError) as info:
        evaluate_run(trained, **kwargs)
    if line is not None:
        assert info.value.line() == line
    else:  # a model for Discrete(2) actions on a Box action space
        assert "Pendulum-v1" in info.value.line()


def test_evaluate_run_needs_an_env_for_a_lone_model_file(trained: Path, tmp_path: Path) -> None:
    lone = tmp_path / "model.zip"
    lone.write_bytes((trained / "model.zip").read_bytes())
    with pytest.raises(RunError) as info:
        evaluate_run(lone, episodes=1)
    assert info.value.line() == (
        f"cannot tell which env {str(lone)!r} was trained on (no config.json beside it) "
        "(pass --env ID)"
    )
    assert len(evaluate_run(lone, episodes=1, env_id="CartPole-v1").returns) == 1


# -- run_grid (local) -----------------------------------------------------------------------------
def test_local_grid_trains_reuses_and_reports_failures(tmp_path: Path) -> None:
    good = GridRun("ppo", _tiny(), tmp_path / "ppo" / "seed0")
    bad = GridRun("dqn", RunSpec("dqn", "Pendulum-v1", n_timesteps=100), tmp_path / "dqn" / "s")
    events: list[tuple[str, str, str | None]] = []

    def hear(kind: str, run: GridRun, outcome: Outcome | None) -> None:
        events.append((kind, run.label, None if outcome is None else outcome.status))

    first = run_grid([good, bad], on_event=hear)
    assert [o.status for o in first] == ["trained", "failed"]
    assert first[0].seconds > 0 and first[0].error is None
    assert first[1].error == (
        "cannot train dqn on Pendulum-v1: DQN does not support Box(-2.0, 2.0, (1,), float32) "
        "action spaces; supported: Discrete (use ppo)"
    )
    assert events == [("start", "ppo", None), ("done", "ppo", "trained"),
                      ("start", "dqn", None), ("done", "dqn", "failed")]  # fmt: skip
    assert _status(good.run_dir)["status"] == "finished"
    assert not bad.run_dir.exists() and not list(tmp_path.glob("*/.*partial"))
    again = run_grid([good])
    assert [o.status for o in again] == ["reused"]


# -- compare --------------------------------------------------------------------------------------
def _fake_run(folder: Path, gamma: float, seed: int, returns: list[float], wall: float) -> Path:
    """A run folder as ``train`` leaves it, as far as ``compare`` reads it."""
    folder.mkdir(parents=True)
    config = {"algo": "ppo", "env_id": "CartPole-v1", "hyperparams": {"gamma": gamma},
              "seed": seed, "device": "auto", "palaestra_version": "0"}  # fmt: skip
    (folder / "config.json").write_text(json.dumps(config))
    (folder / "status.json").write_text(json.dumps({"status": "finished", "wall_time_s": wall}))
    rows = ["steps,return,length,terminated,time_s"]
    rows += [f"{10 * (i + 1)},{r},10,1,{i}" for i, r in enumerate(returns)]
    (folder / "episodes.csv").write_text("\n".join(rows) + "\n")
    return folder


def test_compare_groups_seeds_into_variants_and_summarizes(tmp_path: Path) -> None:
    runs = [
        _fake_run(tmp_path / "a0", 0.9, 0, [1.0, 3.0], 2.0),
        _fake_run(tmp_path / "b0", 0.99, 0, [5.0], 1.0),
        _fake_run(tmp_path / "a1", 0.9, 1, [2.0, 4.0], 4.0),
        _fake_run(tmp_path / "a2", 0.9, 2, [0.0, 6.0], 3.0),
        _fake_run(tmp_path / "a3", 0.9, 3, [9.0, 9.0], 3.0),
    ]
    variants = group_runs(runs)
    assert [v.runs for v in variants] == [[runs[0], runs[2], runs[3], runs[4]], [runs[1]]]
    labels = default_labels(variants)
    assert labels == ["gamma=0.9", "gamma=0.99"]
    rows = summarize(variants, labels, last=1)
    assert [r.finals for r in rows] == [[3.0, 4.0, 6.0, 9.0], [5.0]]
    assert rows[0].value == pytest.approx(5.0)  # IQM: the mean of the middle two
    low, high = rows[0].low, rows[0].high
    assert low is not None and high is not None and low <= 5.0 <= high
    assert (rows[1].value, rows[1].low, rows[1].high) == (5.0, None, None)  # one seed
    assert rows[0].wall_time_s == 3.0 and rows[0].seeds == 4 and rows[0].success is None
    assert summarize(variants, labels, last=2)[0].finals == [2.0, 3.0, 3.0, 9.0]
    found = profiles(rows)
    assert found[0] is not None and found[1] is not None
    assert np.array_equal(found[0].thresholds, found[1].thresholds)

    bands = [b for r in rows if (b := variant_band(r.label, r.episodes, window=1)) is not None]
    curves = tmp_path / "out" / "curves.csv"
    curves.parent.mkdir()
    write_curves(curves, {"env_steps": bands})
    with open(curves, newline="") as f:
        table = list(csv.DictReader(f))
    assert {row["variant"] for row in table} == {"gamma=0.9", "gamma=0.99"}
    assert all(row["axis"] == "env_steps" for row in table)
    assert all(row["low"] == "" for row in table if row["variant"] == "gamma=0.99")
    summary = tmp_path / "out" / "summary.json"
    write_summary(summary, rows, {"title": "t"}, {"plot": "p.png"}, found)
    written = json.loads(summary.read_text())
    assert written["files"] == {"plot": "p.png"} and written["figure"] == {"title": "t"}
    assert [v["label"] for v in written["variants"]] == labels


@pytest.mark.parametrize(
    ("call", "line"),
    [
        (lambda p: group_runs([p / "missing"]), "no run folder at '{p}/missing' "
         "(pass folders written by train)"),
        (lambda p: summarize([], [], last=0), "--last must be at least 1, got 0 (e.g. --last 100)"),
    ],
)  # fmt: skip
def test_compare_errors(tmp_path: Path, call: Any, line: str) -> None:
    with pytest.raises(RunError) as info:
        call(tmp_path)
    assert info.value.line() == line.format(p=tmp_path)
