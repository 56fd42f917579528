"""``palaestra sweep``: the search space, a study that continues, and its bad input."""

from __future__ import annotations

import csv
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from tests.cli.conftest import run_cli

from palaestra.runs import RunError
from palaestra.runs.space import Choice, Range, distributions, space_from_mapping
from palaestra.runs.sweep import run_sweep

optuna = pytest.importorskip("optuna")

SPACE = "learning_rate: {low: 1.0e-4, high: 3.0e-3, log: true}\nn_steps: [8, 16]\n"


def test_space_forms() -> None:
    space = space_from_mapping(
        {
            "learning_rate": {"low": 1e-4, "high": 1e-2, "log": True},
            "n_steps": {"low": 8, "high": 64, "step": 8},
            "gamma": {"low": 0.9, "high": 0.999},
            "policy_kwargs.net_arch": [[64, 64], [128]],
            "n_envs": [1, 4],
        },
        "a2c",
    )
    assert space["learning_rate"] == Range(1e-4, 1e-2, log=True)
    assert space["n_steps"] == Range(8, 64, step=8, integer=True)
    assert space["gamma"] == Range(0.9, 0.999)
    assert space["policy_kwargs.net_arch"] == Choice(([64, 64], [128]))


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"learning_rat": [0.1]}, "unknown a2c hyperparameter 'learning_rat'"),
        (
            {"gamma": {"low": 0.99, "high": 0.9}},
            "impossible range for gamma: low 0.99 is not below",
        ),
        ({"learning_rate": {"low": 0, "high": 1, "log": True}}, "a log range needs low > 0"),
        ({"gamma": []}, "gamma has no choices"),
        ({"gamma": 0.9}, "gamma must be a list of choices or a range"),
        ({"gamma": {"low": 0.9}}, "must have low and high"),
        ({"gamma": {"low": "a", "high": 1}}, "bounds must be numbers"),
        ({}, "must map hyperparameter names"),
    ],
)
def test_bad_spaces_name_what_is_wrong(data: dict, message: str) -> None:
    with pytest.raises(RunError, match=message.replace("(", r"\(")):
        space_from_mapping(data, "a2c")


def _sweep_args(space: Path, out: Path, trials: int, *extra: object) -> list[object]:
    return ["sweep", space, "--algo", "a2c", "--env", "CartPole-v1", "--trials", trials,
            "--seeds", 2, "--timesteps", 320, "--evaluations", 2, "--eval-episodes", 2,
            "--out", out, *extra]  # fmt: skip


def test_a_local_sweep_writes_a_ranked_table_and_usable_best_settings(tmp_path: Path) -> None:
    space = tmp_path / "space.yaml"
    space.write_text(SPACE)
    r = run_cli(*_sweep_args(space, tmp_path / "sw", 3))
    assert r.code == 0, r.err
    with open(tmp_path / "sw" / "trials.csv", newline="") as file:
        rows = list(csv.DictReader(file))
    assert len(rows) == 3 and [row["rank"] for row in rows] == ["1", "2", "3"]
    complete = [float(row["value"]) for row in rows if row["state"] == "complete"]
    assert complete == sorted(complete, reverse=True) and complete
    assert (tmp_path / "sw" / "history.png").read_bytes()[:4] == b"\x89PNG"
    for trial in (tmp_path / "sw" / "trials").iterdir():  # each seed is a run folder
        assert (trial / "seed0" / "config.json").is_file()
    best = tmp_path / "sw" / "best.yaml"
    params = json.loads(rows[0]["params"])
    assert f"n_steps: {params['n_steps']}" in best.read_text()
    t = run_cli("train", "a2c", "CartPole-v1", "--config", best, "--timesteps", 64,
                "--out", tmp_path / "t", "--progress", "none", "--eval-episodes", 0)  # fmt: skip
    assert t.code == 0, t.err
    config = json.loads((tmp_path / "t" / "config.json").read_text())
    assert config["hyperparams"]["n_steps"] == params["n_steps"]
    again = run_cli(*_sweep_args(space, tmp_path / "sw", 3))
    assert again.code == 0 and "3 trials in" in again.out and "(0 run now)" in again.out


def test_a_killed_sweep_continues_losing_only_the_trial_in_flight(tmp_path: Path) -> None:
    space = tmp_path / "space.yaml"
    space.write_text(SPACE)
    out = tmp_path / "sw"
    argv = [str(a) for a in _sweep_args(space, out, 4)]
    argv[argv.index("--timesteps") + 1] = "2000"  # long enough to be killed inside a trial
    cmd = [sys.executable, "-m", "palaestra", *argv]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    storage = f"sqlite:///{out / 'study.db'}"
    deadline = time.monotonic() + 120
    states: list[str] = []
    while time.monotonic() < deadline:
        time.sleep(0.2)
        try:
            study = optuna.load_study(study_name="a2c-CartPole-v1", storage=storage)
            states = [t.state.name for t in study.get_trials()]
        except Exception:  # the study is not created yet
            continue
        if states.count("COMPLETE") + states.count("PRUNED") >= 1 and "RUNNING" in states:
            break
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate()
    assert "RUNNING" in states, states
    done_before = states.count("COMPLETE") + states.count("PRUNED")
    r = run_cli(*[str(a) for a in argv])
    assert r.code == 0, r.err
    study = optuna.load_study(study_name="a2c-CartPole-v1", storage=storage)
    trials = study.get_trials()
    finished = [t for t in trials if t.state.name in ("COMPLETE", "PRUNED")]
    lost = [t for t in trials if t.user_attrs.get("interrupted")]
    assert len(finished) == 4 and len(lost) == 1
    assert lost[0].user_attrs["reason"] == "interrupted: the sweep was killed while it ran"
    assert f"({4 - done_before} run now)" in r.out


@pytest.mark.parametrize(
    ("space", "extra", "message", "code"),
    [
        ("learning_rat: [0.1]\n", (), "unknown a2c hyperparameter 'learning_rat'", 2),
        ("gamma: {low: 0.99, high: 0.9}\n", (), "impossible range for gamma", 2),
        (
            SPACE,
            ("--storage", "sqlite:////no/such/folder/s.db"),
            "cannot open the study storage",
            1,
        ),
        (SPACE, ("--storage", "nosuchdb://x"), "cannot open the study storage 'nosuchdb://x'", 1),
        (SPACE, ("--address", "auto"), "--address applies to the ray backend", 2),
        (SPACE, ("--backend", "ray", "--address", "127.0.0.1:1"), "cannot reach a Ray cluster", 1),
    ],
)
def test_bad_sweep_input_is_one_line_and_non_zero(
    tmp_path: Path, space: str, extra: tuple[str, ...], message: str, code: int
) -> None:
    path = tmp_path / "space.yaml"
    path.write_text(space)
    r = run_cli(*_sweep_args(path, tmp_path / "sw", 2, *extra))
    assert r.code == code and r.err.count("\n") == 1 and message in r.err, r.err
    assert "Traceback" not in r.err


def test_run_sweep_refuses_another_space_in_the_same_study(tmp_path: Path) -> None:
    first = space_from_mapping({"n_steps": [8, 16]}, "a2c")
    run_sweep(first, "a2c", "CartPole-v1", 1, 1, tmp_path, 160, evaluations=0, eval_episodes=1)
    other = space_from_mapping({"gamma": [0.9, 0.99]}, "a2c")
    with pytest.raises(RunError, match="searched \\['n_steps'\\]"):
        run_sweep(other, "a2c", "CartPole-v1", 2, 1, tmp_path, 160, evaluations=0)


def test_without_ray_or_optuna_the_commands_name_the_extra(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    space = tmp_path / "space.yaml"
    space.write_text(SPACE)
    monkeypatch.setitem(sys.modules, "optuna", None)  # import optuna -> ImportError
    r = run_cli(*_sweep_args(space, tmp_path / "sw", 2))
    assert r.code == 1 and r.err.count("\n") == 1
    assert 'optuna is not installed, run `pip install "palaestra[sweep]"`' in r.err
    monkeypatch.setitem(sys.modules, "ray", None)
    c = run_cli("compare", "algos", "--env", "CartPole-v1", "--algos", "a2c", "--seeds", 0,
                "--timesteps", 64, "--runs-dir", tmp_path / "c", "--backend", "ray")  # fmt: skip
    assert c.code == 1 and c.err.count("\n") == 1
    assert 'ray is not installed, run `pip install "palaestra[ray]"`' in c.err


def test_sigterm_stops_a_sweep_like_train_with_the_study_intact(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from palaestra.runs import sweep

    evaluate = sweep._evaluate

    def sigterm_in_trial_1(run: Any, episodes: int) -> float:
        if "trials/1/" in str(run.run_dir) and not sent:
            sent.append(True)
            os.kill(os.getpid(), signal.SIGTERM)  # as `timeout` or a scheduler sends it
        return evaluate(run, episodes)

    sent: list[bool] = []
    monkeypatch.setattr(sweep, "_evaluate", sigterm_in_trial_1)
    space = tmp_path / "space.yaml"
    space.write_text(SPACE)
    out = tmp_path / "sw"
    previous = signal.getsignal(signal.SIGTERM)
    r = run_cli(*_sweep_args(space, out, 3))
    assert r.code == 143, r.err
    assert "SIGTERM received: stopping at the next step" in r.err
    assert r.err.splitlines()[-1] == (
        f"palaestra: sweep interrupted by SIGTERM; the study in {out / 'study.db'} keeps every "
        "finished trial (run the same command again to continue it)"
    )
    assert signal.getsignal(signal.SIGTERM) is previous
    line = next(x for x in r.out.splitlines() if x.startswith("trial 1: "))
    assert line.startswith("trial 1: interrupted {")
    why = r"interrupted by SIGTERM: stopped at step \d+ of 320 \(seed 0\)"
    assert re.search(f": {why}$", line), line
    with open(out / "trials.csv", newline="") as file:
        rows = {row["trial"]: row for row in csv.DictReader(file)}
    assert rows["1"]["state"] == "interrupted"
    assert re.fullmatch(why, rows["1"]["reason"])
    study = optuna.load_study(study_name="a2c-CartPole-v1", storage=f"sqlite:///{out}/study.db")
    assert [t.state.name for t in study.get_trials()] == ["COMPLETE", "FAIL"]
    monkeypatch.setattr(sweep, "_evaluate", evaluate)
    again = run_cli(*_sweep_args(space, out, 3))  # continues: trial 1's settings run again
    assert again.code == 0, again.err
    assert "(2 run now)" in again.out
    study = optuna.load_study(study_name="a2c-CartPole-v1", storage=f"sqlite:///{out}/study.db")
    states = [t.state.name for t in study.get_trials()]
    assert states.count("FAIL") == 1 and len(states) == 4


def test_trials_csv_says_why_each_trial_ended_and_history_draws_pruned_trials(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from optuna.trial import TrialState, create_trial

    from palaestra.runs import curves
    from palaestra.runs.spec import RunSpec
    from palaestra.runs.sweep_report import write_outputs

    space = space_from_mapping({"n_steps": [8, 16]}, "a2c")
    dist = distributions(space)
    study = optuna.create_study(study_name="a2c-CartPole-v1", direction="maximize")
    for value in (20.0, 35.0):
        study.add_trial(create_trial(value=value, params={"n_steps": "8"}, distributions=dist))
    reason = "pruned at step 96 of 320: seed 0's evaluation 9.50 was behind the other trials'"
    study.add_trial(create_trial(state=TrialState.PRUNED, params={"n_steps": "16"},
                                 distributions=dist, intermediate_values={64: 12.0, 96: 9.5},
                                 user_attrs={"reason": reason}))  # fmt: skip
    study.add_trial(create_trial(state=TrialState.FAIL, params={"n_steps": "16"},
                                 distributions=dist,
                                 user_attrs={"reason": "RuntimeError: boom"}))  # fmt: skip
    figures: dict[str, object] = {}
    save = curves.save_figure

    def keep(fig: object, path: Path) -> None:
        figures[path.name] = fig
        save(fig, path)

    monkeypatch.setattr(curves, "save_figure", keep)
    base = RunSpec.from_preset("a2c", "CartPole-v1", n_timesteps=320)
    rows, _, _ = write_outputs(study, space, tmp_path, base, None)
    assert [(r["number"], r["state"], r["reason"]) for r in rows] == [
        (1, "complete", None), (0, "complete", None), (2, "pruned", reason),
        (3, "failed", "RuntimeError: boom"),
    ]  # fmt: skip
    with open(tmp_path / "trials.csv", newline="") as file:
        assert [row["reason"] for row in csv.DictReader(file)] == [
            "",
            "",
            reason,
            "RuntimeError: boom",
        ]
    ax = figures["history.png"].axes[0]  # type: ignore[attr-defined]
    labels = ax.get_legend_handles_labels()[1]
    assert sorted(labels) == ["best so far", "complete: mean return over seeds",
                              "pruned: its last evaluation (first seed)"]  # fmt: skip
    pruned = next(c for c in ax.collections if c.get_label().startswith("pruned"))
    assert pruned.get_offsets().tolist() == [[2.0, 9.5]]  # trial 2 at its last evaluation
    assert (
        ax.get_title()
        == "a2c-CartPole-v1: 2 complete, 1 pruned, 1 failed or interrupted (not drawn)"
    )
    assert (tmp_path / "history.png").read_bytes()[:4] == b"\x89PNG"
