"""``palaestra compare algos``: each algorithm's preset trained per seed into a run folder
(finished runs reused), a table with wall times, curves against env steps and wall-clock
seconds; the algorithm registry behind ``train``, ``eval`` and ``compare``."""

from __future__ import annotations

import csv
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.cli.conftest import Result

from palaestra.runs.algorithms import REGISTRY
from palaestra.runs.curves import Episodes, variant_band
from palaestra.runs.settings import (
    ALGO_CLASSES,
    ALGOS,
    REPLAY_ALGOS,
    algo_class,
    hyperparameter_names,
)


def test_registry_is_one_list() -> None:
    """Every CLI algorithm resolves to the class of that name in palaestra.algos and has
    hyperparameters; the CLI's list is the registry's."""
    import palaestra.algos

    assert ALGOS == tuple(ALGO_CLASSES) and {"dqn", "ppo", "a2c"} <= set(ALGOS)
    for name, cls_name in ALGO_CLASSES.items():
        cls = algo_class(name.upper())
        assert cls is getattr(palaestra.algos, cls_name) and cls.__name__ == cls_name
        assert "learning_rate" in hyperparameter_names(name)
    assert {"n_steps", "rms_prop_eps", "use_rms_prop"} <= set(hyperparameter_names("a2c"))


@pytest.mark.parametrize("entry", REGISTRY, ids=lambda entry: entry.name)
def test_declared_replay_kind_is_the_classes(entry: Any) -> None:
    """A registration line's ``replay`` says what its class is: an off-policy algorithm (its
    replay buffer saved with each checkpoint) or an on-policy one (rollouts)."""
    from palaestra.algos.common.off_policy import OffPolicyAlgorithm
    from palaestra.algos.common.on_policy import OnPolicyAlgorithm

    cls = algo_class(entry.name)
    assert entry.replay == issubclass(cls, OffPolicyAlgorithm)
    assert entry.replay != issubclass(cls, OnPolicyAlgorithm)
    assert (entry.name in REPLAY_ALGOS) == entry.replay


def _png_width(path: Path) -> int:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return int.from_bytes(data[16:20], "big")


def test_train_and_eval_a2c(
    cli: Callable[..., Result], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "a2c"
    r = cli("train", "a2c", "CartPole-v1", "--timesteps", 400, "--seed", 0, "--out", out,
            "--progress", "none", "--eval-episodes", 0)  # fmt: skip
    assert r.code == 0, r.err
    config = json.loads((out / "config.json").read_text())
    assert config["algo"] == "a2c" and config["preset"] == "default"
    assert config["n_envs"] == 8
    with open(out / "episodes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    times = [float(row["time_s"]) for row in rows]
    assert rows and times == sorted(times) and 0 <= times[0]
    status = json.loads((out / "status.json").read_text())
    assert times[-1] <= status["wall_time_s"]
    r = cli("eval", out, "--episodes", 2)
    assert r.code == 0, r.err


@pytest.mark.slow  # four training runs and two plots: ~6 s on an idle 2-core machine
def test_compare_algos_trains_each_preset_then_reuses(
    cli: Callable[..., Result], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    args = ("compare", "algos", "--env", "CartPole-v1", "--algos", "a2c", "PPO",
            "--seeds", 0, 1, "--timesteps", 320, "--out", "cmp.png")  # fmt: skip
    r = cli(*args)
    assert r.code == 0, r.err
    root = Path("runs") / "compare-algos-CartPole-v1"
    for algo in ("a2c", "ppo"):
        for seed in (0, 1):
            assert f"{algo} seed {seed}: training -> {root / algo / f'seed{seed}'}" in r.out
            config = json.loads((root / algo / f"seed{seed}" / "config.json").read_text())
            assert (config["algo"], config["seed"], config["preset"]) == (algo, seed, "default")
    rows = {line.split()[0]: line.split() for line in r.out.splitlines() if line.strip()}
    for algo in ("a2c", "ppo"):
        row = rows[algo]
        assert row[1] == "2" and row[-1] == "s" and float(row[-2]) > 0, row
        walls = [
            json.loads((root / algo / f"seed{s}" / "status.json").read_text())["wall_time_s"]
            for s in (0, 1)
        ]
        assert float(row[-2]) == pytest.approx(np.mean(walls), abs=0.051)
    assert "wall time" in r.out
    # two plots side by side: returns against env steps and against wall-clock seconds
    assert _png_width(tmp_path / "cmp.png") == 1600
    again = cli(*args)
    assert again.code == 0, again.err
    assert "ppo seed 1: reusing" in again.out and "training ->" not in again.out


def test_compare_trains_tiny_runs_and_records_what_it_shows(
    cli: Callable[..., Result], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """End to end: two seeds of A2C trained for 200 steps, then summary.json, curves.csv and
    the printed table agree: the per-seed values are the runs' own episodes, the interval lies
    inside them, the curves' last points are the table's figure."""
    monkeypatch.chdir(tmp_path)
    r = cli("compare", "algos", "--env", "CartPole-v1", "--algos", "a2c", "--seeds", 0, 1,
            "--timesteps", 200, "--out", "out/cmp.png")  # fmt: skip
    assert r.code == 0, r.err
    summary = json.loads(Path("out/summary.json").read_text())
    (variant,) = summary["variants"]
    runs = [Path("runs/compare-algos-CartPole-v1/a2c/seed0"), Path(str(variant["runs"][1]))]
    assert variant["runs"] == [str(run) for run in runs] and variant["seeds"] == [0, 1]
    for run, value in zip(runs, variant["per_seed_values"]):
        with open(run / "episodes.csv", newline="") as f:
            returns = [float(row["return"]) for row in csv.DictReader(f)]
        assert value == pytest.approx(np.mean(returns[-100:]), abs=1e-9)
    finals = variant["per_seed_values"]
    assert variant["interval"] == [min(finals), max(finals)]  # 2 seeds: [min, max]
    assert variant["value"] == pytest.approx(np.mean(finals), abs=1e-9)  # 2 seeds: the mean
    with open("out/curves.csv", newline="") as f:
        points = list(csv.DictReader(f))
    for axis in ("env_steps", "wall_seconds"):
        last = [p for p in points if p["axis"] == axis][-1]
        assert float(last["iqm"]) == variant["value"]
        assert [float(last["low"]), float(last["high"])] == variant["interval"]
    table = re.search(r"^a2c +2 +(\S+) +\[(\S+), (\S+)\]", r.out, re.MULTILINE)
    assert table is not None, r.out
    assert table.groups() == tuple(f"{v:.2f}" for v in (variant["value"], *variant["interval"]))
    assert summary["figure"]["legend"] == ["a2c (2 seeds)"]
    assert "last 100 episodes" in summary["figure"]["ylabel"]
    assert _png_width(tmp_path / "out" / "cmp.png") == 1600


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("algos", "--env", "CartPole-v1", "--seeds", 0), "needs --algos, --env and --seeds"),
        (("algos", "--algos", "a2c", "--seeds", 0), "needs --algos, --env and --seeds"),
        (("algos", "--algos", "a3c", "--env", "CartPole-v1", "--seeds", 0),
         "unknown algorithm 'a3c'"),
        (("algos", "--algos", "a2c", "A2C", "--env", "CartPole-v1", "--seeds", 0),
         "--algos repeats an algorithm"),
        (("algos", "--algos", "a2c", "--env", "CartPole-v1", "--seeds", 2, 2),
         "--seeds repeats a seed"),
        (("algos", "preset", "--algos", "a2c", "--env", "CartPole-v1", "--seeds", 0),
         "'algos' compares algorithms alone, not with ['preset']"),
        (("algos", "--algo", "dqn", "--algos", "a2c", "--env", "CartPole-v1", "--seeds", 0),
         "--algo does not apply to 'algos'"),
        (("preset", "--algos", "a2c", "--algo", "dqn", "--env", "CartPole-v1", "--seeds", 0),
         "--algos only applies to 'algos'"),
    ],
)  # fmt: skip
def test_compare_algos_errors(
    cli: Callable[..., Result],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    args: tuple[object, ...],
    message: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    r = cli("compare", *args)
    assert r.code == 2 and message in r.err and r.err.count("\n") == 1, r.err
    assert not (tmp_path / "runs").exists()


def test_band_against_wall_clock_time() -> None:
    """Each seed's rolling mean as of its last episode finished by each grid point (seconds
    here), from the first point every seed has a value to the end of the longest run; IQM
    over seeds with its bootstrap interval; no band when a run has no times."""
    a = Episodes(np.array([10, 20]), np.array([1.0, 3.0]), np.array([10, 10]), None,
                 np.array([1.0, 2.0]))  # fmt: skip
    b = Episodes(np.array([10, 20]), np.array([3.0, 5.0]), np.array([10, 10]), None,
                 np.array([1.0, 3.0]))  # fmt: skip
    band = variant_band("x", [a, b], points=3, x="times")
    assert band is not None and (band.seeds, band.window, band.min_episodes) == (2, 100, 2)
    np.testing.assert_array_equal(band.steps, [1.0, 2.0, 3.0])  # to the end of the longest
    # rolling means (window 100: all so far): a 1 -> 2 at 1 s, 2 s; b 3 -> 4 at 1 s, 3 s.
    # At 1 s: a 1, b 3; at 2 s: a 2, b 3; at 3 s: a 2 (its last), b 4. Two seeds: IQM = mean,
    # 95% percentile bootstrap = [min, max] (both minima resampled: probability 1/4).
    np.testing.assert_array_equal(band.iqm, [2.0, 2.5, 3.0])
    np.testing.assert_array_equal(band.low, [1.0, 2.0, 2.0])
    np.testing.assert_array_equal(band.high, [3.0, 3.0, 4.0])
    # window 1: the last return; at 2 s both seeds have 3.0: the interval is [3, 3], not NaN
    one = variant_band("x", [a, b], points=3, x="times", window=1)
    assert one is not None
    np.testing.assert_array_equal(one.iqm, [2.0, 3.0, 4.0])
    np.testing.assert_array_equal(one.low, [1.0, 3.0, 3.0])
    np.testing.assert_array_equal(one.high, [3.0, 3.0, 5.0])
    alone = variant_band("x", [a], points=2)
    assert alone is not None and alone.low is None and alone.high is None
    np.testing.assert_array_equal(alone.iqm, [1.0, 2.0])
    untimed = a._replace(times=None)
    assert variant_band("x", [untimed, b], x="times") is None
    assert variant_band("x", [untimed, b]) is not None  # against steps it still draws
    with pytest.raises(ValueError, match="smoothing window must be at least 1 episode, got 0"):
        variant_band("x", [a, b], window=0)


def test_episode_log_keeps_the_columns_of_a_resumed_old_file(tmp_path: Path) -> None:
    """A run folder written before the time column resumes with its four columns (one header
    per file); a new file gets the training seconds, counted on from the run's earlier time."""
    from palaestra.runs.logs import EpisodeLog

    class Model:
        num_timesteps = 7

    def finish_one(log: EpisodeLog) -> None:
        log.init_callback(Model())  # type: ignore[arg-type]
        log.update_locals({"dones": np.array([True]), "infos": [{"episode": {"r": 3.0, "l": 7}}]})
        log.on_step()
        log.close()

    old = tmp_path / "old.csv"
    old.write_text("steps,return,length,terminated\r\n5,1.0,5,1\r\n")
    finish_one(EpisodeLog(old, wall_before=10.0))
    assert old.read_text().splitlines() == [
        "steps,return,length,terminated",
        "5,1.0,5,1",
        "7,3.0,7,1",
    ]
    new = tmp_path / "new.csv"
    finish_one(EpisodeLog(new, wall_before=10.0))
    header, row = new.read_text().splitlines()
    assert header == "steps,return,length,terminated,time_s"
    assert row.startswith("7,3.0,7,1,") and 10.0 <= float(row.split(",")[-1]) < 20.0
