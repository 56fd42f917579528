"""``palaestra compare`` on hand-written runs: the table, ``summary.json`` and ``curves.csv``
(IQM over seeds, percentile-bootstrap intervals inside the seeds' range, the curve's last point
equal to the table's figure, a figure that says what it shows)."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from palaestra.runs.curves import read_episodes, rolling_mean

from .conftest import run_cli


def _fake_run(root: Path, name: str, gamma: float, seed: int, returns: list[float],
              terminated: list[int]) -> Path:  # fmt: skip
    run = root / name
    run.mkdir()
    config = {"algo": "dqn", "env_id": "MountainCar-v0", "preset": "default", "n_envs": 1,
              "hyperparams": {"gamma": gamma, "policy_kwargs": {"net_arch": [64]}},
              "seed": seed, "device": "auto", "palaestra_version": "0.1.0"}  # fmt: skip
    (run / "config.json").write_text(json.dumps(config))
    lines = ["steps,return,length,terminated"]
    lines += [f"{100 * (i + 1)},{r},100,{t}" for i, (r, t) in enumerate(zip(returns, terminated))]
    (run / "episodes.csv").write_text("\n".join(lines) + "\n")
    return run


@pytest.fixture
def four_runs(tmp_path: Path) -> list[Path]:
    """Two variants (gamma 0.9 and 0.99) x two seeds."""
    return [
        _fake_run(tmp_path, "a1", 0.9, 1, [10, 20, 30], [1, 0, 0]),
        _fake_run(tmp_path, "b1", 0.99, 1, [90, 100, 110], [0, 0, 0]),
        _fake_run(tmp_path, "a2", 0.9, 2, [30, 40, 50], [1, 1, 0]),
        _fake_run(tmp_path, "b2", 0.99, 2, [100, 110, 120], [0, 0, 0]),
    ]


def _table(out: str) -> dict[str, list[str]]:
    rows = {}
    for line in out.splitlines():
        match = re.fullmatch(
            r"(\S+)\s+(\d+)\s+(-?[\d.]+)\s+\[(-?[\d.]+), (-?[\d.]+)\]\s+(\S+)\s+(-|[\d.]+ s)", line
        )
        if match:
            rows[match[1]] = list(match.groups()[1:])
    return rows


def test_compare_table_and_plot(tmp_path: Path, four_runs: list[Path]) -> None:
    plot = tmp_path / "cmp.png"
    result = run_cli("compare", *four_runs, "--out", plot)
    assert result.code == 0, result.err
    rows = _table(result.out)
    # gamma=0.9: finals 20 and 40 (mean of all 3 episodes: fewer than --last 100) -> IQM of
    # 2 seeds = their mean 30; the 95% percentile bootstrap of 2 seeds is [min, max] (a
    # resample of both minima has probability 1/4 > 2.5%); success (1/3 + 2/3) / 2 = 50%
    assert rows["gamma=0.9"] == ["2", "30.00", "20.00", "40.00", "50.0%", "-"]  # no status
    assert rows["gamma=0.99"] == ["2", "105.00", "100.00", "110.00", "0.0%", "-"]
    assert f"  gamma=0.9: {four_runs[0]}, {four_runs[2]}" in result.out
    assert (
        "(final return: each seed's mean return over its last 100 episodes; IQM: interquartile "
        "mean (25% trimmed mean; the plain mean below 4 seeds), over seeds; CI: percentile "
        "bootstrap over seeds (scipy.stats.bootstrap), 9,999 resamples, none with one seed; "
        "wall time: training seconds per run, averaged over seeds)\n"
    ) in result.out
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    profile_png = tmp_path / "cmp_profile.png"
    assert profile_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    summary, curves = tmp_path / "summary.json", tmp_path / "curves.csv"
    assert result.out.strip().endswith(f"wrote {plot}, {profile_png}, {summary}, {curves}")
    record = json.loads(summary.read_text())
    assert record["files"] == {"plot": "cmp.png", "curves": "curves.csv",
                               "profile": "cmp_profile.png"}  # fmt: skip
    # Performance profiles by hand. Final returns 20, 40 (gamma=0.9) and 100, 110: thresholds
    # are each of them and 5% of their range (90) beyond both ends. Fraction strictly above
    # each; band of 2 seeds: 1 of 2 above -> Binomial(2, 1/2) quantiles 0 and 2 -> [0, 1].
    thresholds = [15.5, 20.0, 40.0, 100.0, 110.0, 114.5]
    assert record["variants"][0]["profile"] == {
        "thresholds": thresholds,
        "fraction": [1.0, 0.5, 0.0, 0.0, 0.0, 0.0],
        "low": [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        "high": [1.0, 1.0, 0.0, 0.0, 0.0, 0.0],
    }
    assert record["variants"][1]["profile"] == {
        "thresholds": thresholds,
        "fraction": [1.0, 1.0, 1.0, 0.5, 0.0, 0.0],
        "low": [1.0, 1.0, 1.0, 0.0, 0.0, 0.0],
        "high": [1.0, 1.0, 1.0, 1.0, 0.0, 0.0],
    }
    assert record["profile"]["statistic"] == (
        "fraction of runs (seeds) whose final return is above the threshold"
    )
    assert record["profile"]["interval_method"].startswith(
        "percentile bootstrap over runs at each threshold, exact"
    )
    assert record["variants"][0]["per_seed_values"] == [20.0, 40.0]
    assert record["variants"][0]["seeds"] == [1, 2]
    assert record["variants"][0]["episodes_per_seed"] == [3, 3]
    assert record["per_seed_value"] == (
        "each seed's mean return over its last 100 episodes of training (over all of them "
        "where it has fewer: the fewest, 3)"
    )
    assert "time_s" not in (four_runs[0] / "episodes.csv").read_text()
    assert {row["axis"] for row in _curves(curves)} == {"env_steps"}  # no times: one panel


def test_compare_last_n_and_labels(tmp_path: Path, four_runs: list[Path]) -> None:
    result = run_cli("compare", *four_runs, "--last", 2, "--labels", "short", "long",
                     "--out", tmp_path / "c.png")  # fmt: skip
    assert result.code == 0, result.err
    rows = _table(result.out)
    assert rows["short"][:2] == ["2", "35.00"] and rows["long"][:2] == ["2", "110.00"]
    bad = run_cli("compare", *four_runs, "--labels", "one", "--out", tmp_path / "c.png")
    assert bad.code == 2
    assert bad.err == (
        "palaestra: error: 1 labels for 2 variants (give one label per variant, in order of "
        "first appearance: gamma=0.9; gamma=0.99)\n"
    )
    missing = run_cli("compare", tmp_path / "nope")
    assert missing.code == 2 and missing.err.startswith("palaestra: error: no run folder at")


def test_one_seed_has_no_interval(tmp_path: Path, four_runs: list[Path]) -> None:
    result = run_cli("compare", four_runs[0], four_runs[1], "--out", tmp_path / "c.png")
    assert result.code == 0, result.err
    assert re.search(r"gamma=0\.9\s+1\s+20\.00\s+n/a \(one seed\)\s+33\.3%\s+-", result.out)
    record = json.loads((tmp_path / "summary.json").read_text())
    assert [v["interval"] for v in record["variants"]] == [None, None]
    assert record["figure"]["legend"] == ["gamma=0.9 (1 seed, no interval)",
                                          "gamma=0.99 (1 seed, no interval)"]  # fmt: skip
    rows = _curves(tmp_path / "curves.csv")
    assert rows and all(row["low"] == row["high"] == "" for row in rows)
    # the profile of one seed: 1 above each threshold below its value, no band
    assert [v["profile"] for v in record["variants"]] == [
        {"thresholds": [16.0, 20.0, 100.0, 104.0], "fraction": [1.0, 0.0, 0.0, 0.0],
         "low": None, "high": None},
        {"thresholds": [16.0, 20.0, 100.0, 104.0], "fraction": [1.0, 1.0, 0.0, 0.0],
         "low": None, "high": None},
    ]  # fmt: skip
    assert record["profile"]["figure"]["legend"] == record["figure"]["legend"]


def test_read_episodes_fallbacks(tmp_path: Path) -> None:
    (tmp_path / "0.monitor.csv").write_text('#{"t_start": 0}\nr,l,t\n-200,200,1.0\n-150,150,2.0\n')
    episodes = read_episodes(tmp_path)
    assert episodes.steps.tolist() == [200, 350] and episodes.returns.tolist() == [-200, -150]
    assert episodes.terminated is None
    other = tmp_path / "p"
    other.mkdir()
    (other / "progress.csv").write_text(
        "time/total_timesteps,rollout/ep_rew_mean,train/loss\n100,,0.5\n200,-180.5,0.4\n"
    )
    assert read_episodes(other).returns.tolist() == [-180.5]
    np.testing.assert_allclose(rolling_mean(np.array([1.0, 3.0, 5.0]), 2), [1.0, 2.0, 4.0])


def test_read_episodes_skips_a_row_torn_by_a_crash(tmp_path: Path) -> None:
    (tmp_path / "episodes.csv").write_bytes(
        b"steps,return,length,terminated\r\n200,-200.0,200,0\r\n350,-150.0,150,1\r\n500,-1"
    )
    episodes = read_episodes(tmp_path)
    assert episodes.steps.tolist() == [200, 350] and episodes.lengths.tolist() == [200, 150]
    assert episodes.terminated is not None and episodes.terminated.tolist() == [False, True]
    (tmp_path / "episodes.csv").unlink()
    (tmp_path / "0.monitor.csv").write_text('#{"t_start": 0}\nr,l,t\n-200,200,1.0\n-15')
    assert read_episodes(tmp_path).returns.tolist() == [-200]


def _curves(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as file:
        return list(csv.DictReader(file))


def _iqm_by_hand(values: list[float]) -> float:
    cut = len(values) // 4
    kept = sorted(values)[cut : len(values) - cut]
    return sum(kept) / len(kept)


def _cartpole_like_run(root: Path, algo: str, seed: int, slope: float) -> Path:
    """A run folder whose episodes look like CartPole training: returns = lengths in
    [8, 500], growing with the steps at ``slope`` (seed 3 never learns: an outlier seed)."""
    rng = np.random.default_rng(100 * seed + len(algo))
    run = root / algo / f"seed{seed}"
    run.mkdir(parents=True)
    config = {"algo": algo, "env_id": "CartPole-v1", "preset": "default", "n_envs": 1,
              "hyperparams": {}, "seed": seed, "device": "auto"}  # fmt: skip
    (run / "config.json").write_text(json.dumps(config))
    lines, steps = ["steps,return,length,terminated,time_s"], 0
    while steps < 6000:
        mean = 20.0 if seed == 3 else 20.0 + slope * steps
        length = int(np.clip(rng.normal(mean, 0.2 * mean), 8, 500))
        steps += length
        lines.append(f"{steps},{float(length)},{length},{int(length < 500)},{steps / 2000:.4f}")
    (run / "episodes.csv").write_text("\n".join(lines) + "\n")
    return run


def _rolling_as_of(run: Path, axis: str, x: float, window: int) -> float:
    """A seed's value at ``x``, computed here without palaestra: the mean return of its last
    ``window`` episodes finished by ``x``."""
    rows = _curves(run / "episodes.csv")
    key = "steps" if axis == "env_steps" else "time_s"
    done = [float(r["return"]) for r in rows if float(r[key]) <= x]
    return sum(done[-window:]) / len(done[-window:])


@pytest.mark.parametrize("n_seeds", [2, 5])
def test_compare_statistics_agree_everywhere(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, n_seeds: int
) -> None:
    """Two variants on 2 and on 5 seeds: every interval (table, summary.json, each point of
    curves.csv) lies inside [min, max] of the per-seed values; the last point of each curve is
    the table's figure; the figure draws the words summary.json records, which name the
    statistic, the interval method, the seed count and the smoothing window."""
    import matplotlib.text

    from palaestra.runs import curves as curves_module

    drawn: list[str] = []
    real_save = curves_module.save_figure

    def spy(fig: Any, path: Path) -> None:
        drawn.extend(t.get_text() for t in fig.findobj(matplotlib.text.Text))
        real_save(fig, path)

    monkeypatch.setattr(curves_module, "save_figure", spy)
    runs = {
        algo: [_cartpole_like_run(tmp_path / "runs", algo, s, slope) for s in range(n_seeds)]
        for algo, slope in (("a2c", 0.01), ("ppo", 0.05))
    }
    plot = tmp_path / "out" / "cmp.png"
    plot.parent.mkdir()
    window = 20
    result = run_cli("compare", *runs["a2c"], *runs["ppo"], "--last", window, "--out", plot)
    assert result.code == 0, result.err
    table = _table(result.out)
    summary = json.loads((plot.parent / "summary.json").read_text())
    points = _curves(plot.parent / "curves.csv")
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    assert summary["smoothing_window_episodes"] == window
    assert summary["confidence_level"] == 0.95
    assert summary["statistic"].startswith("interquartile mean")
    assert summary["interval_method"].startswith("percentile bootstrap over seeds")
    for variant in summary["variants"]:
        label, finals = variant["label"], variant["per_seed_values"]
        assert variant["seed_count"] == n_seeds == len(finals)
        assert variant["seeds"] == list(range(n_seeds))
        for run, final in zip(runs[label], finals):
            assert final == pytest.approx(_rolling_as_of(run, "env_steps", 1e9, window))
        low, high = variant["interval"]
        assert min(finals) <= low <= high <= max(finals)
        assert variant["value"] == pytest.approx(_iqm_by_hand(finals), abs=1e-9)
        # the table prints the same figure and interval
        assert table[label][:4] == [str(n_seeds), f"{variant['value']:.2f}", f"{low:.2f}",
                                    f"{high:.2f}"]  # fmt: skip
        for axis in ("env_steps", "wall_seconds"):
            curve = [p for p in points if p["variant"] == label and p["axis"] == axis]
            assert len(curve) == 100 and all(int(p["seeds"]) == n_seeds for p in curve)
            for point in curve[::9] + curve[-1:]:
                values = [_rolling_as_of(r, axis, float(point["x"]), window) for r in runs[label]]
                assert float(point["iqm"]) == pytest.approx(_iqm_by_hand(values), abs=1e-9)
                assert min(values) - 1e-9 <= float(point["low"]) <= float(point["high"])
                assert float(point["high"]) <= max(values) + 1e-9
            for point in curve:  # within the data's range: returns of CartPole lie in [8, 500]
                assert 8.0 <= float(point["low"]) <= float(point["iqm"]) <= 500.0
                assert float(point["iqm"]) <= float(point["high"]) <= 500.0
            # the curve's last point is the table's figure, to the last bit
            last = curve[-1]
            assert float(last["iqm"]) == variant["value"]
            assert [float(last["low"]), float(last["high"])] == variant["interval"]
            assert f"{float(last['iqm']):.2f}" == table[label][1]
    assert points[-1]["variant"] == "ppo" and float(points[-1]["iqm"]) == pytest.approx(
        summary["variants"][1]["value"], abs=0
    )

    figure = summary["figure"]
    seeds = f"{n_seeds} seeds"
    assert figure["legend"] == [f"a2c ({seeds})", f"ppo ({seeds})"]
    assert figure["title"] == "CartPole-v1: IQM over seeds, 95% bootstrap CI"
    assert figure["ylabel"] == f"return (mean of last {window} episodes)"
    assert figure["footnote"].startswith(
        "Line: interquartile mean (25% trimmed mean; the plain mean below 4 seeds) over seeds "
        f"of each seed's mean return over its last {window} episodes finished by then.\n"
        "Band: 95% confidence interval, percentile bootstrap over seeds"
    )
    assert figure["footnote"].endswith(f"Seeds per variant: a2c {n_seeds}, ppo {n_seeds}.")
    few = "none with 1 seed; with 2 or 3 seeds, their whole range. Seeds"
    assert (few in figure["footnote"]) == (n_seeds == 2)
    for text in [figure["title"], figure["ylabel"], figure["footnote"], *figure["legend"]]:
        assert text in drawn  # what summary.json says is what matplotlib drew
    assert drawn.count(figure["ylabel"]) == 2  # both panels: env steps and wall-clock seconds

    # The performance profile: from the per-seed values checked above, by hand.
    assert (plot.parent / "cmp_profile.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert summary["files"]["profile"] == "cmp_profile.png"
    pooled = {v for variant in summary["variants"] for v in variant["per_seed_values"]}
    for variant in summary["variants"]:
        finals, profile = variant["per_seed_values"], variant["profile"]
        taus = profile["thresholds"]
        assert taus == sorted(taus) and set(taus[1:-1]) == pooled  # a step at every value
        assert profile["fraction"] == [sum(f > t for f in finals) / n_seeds for t in taus]
        assert profile["fraction"][0] == 1.0 and profile["fraction"][-1] == 0.0
        for fraction, low, high in zip(profile["fraction"], profile["low"], profile["high"]):
            assert 0.0 <= low <= fraction <= high <= 1.0
            assert low * n_seeds == int(low * n_seeds)  # a resample's fraction: k / n
            if fraction in (0.0, 1.0):  # every resample alike
                assert low == high == fraction
            elif n_seeds == 2:  # 1 of 2 above: a resample has 0, 1 or 2 above
                assert (low, high) == (0.0, 1.0)
    words = summary["profile"]["figure"]
    assert words["title"] == ("CartPole-v1: performance profile of final returns, 95% bootstrap CI")
    assert words["xlabel"] == f"final return τ (mean of last {window} episodes)"
    assert words["ylabel"] == "fraction of runs with final return > τ"
    assert words["legend"] == figure["legend"]
    assert words["footnote"] == (
        "Line: fraction of runs (seeds) whose final return is above the threshold τ; a "
        "run's final return is each seed's mean return over its last "
        f"{window} episodes of training.\nBand: 95% confidence interval, percentile bootstrap "
        "over runs at each threshold, exact (a resample's count above it is binomial: "
        "scipy.stats.binom quantiles); none with 1 seed. "
        f"Seeds per variant: a2c {n_seeds}, ppo {n_seeds}."
    )
    for text in [words["title"], words["xlabel"], words["ylabel"], words["footnote"],
                 *words["legend"]]:  # fmt: skip
        assert text in drawn


@pytest.mark.parametrize(
    ("n_episodes", "legend"),
    [
        (0, ["episode return (0 episodes, not smoothed)"]),
        (39, ["episode return (39 episodes, not smoothed)"]),  # window 39 // 20 = 1: no line
        (40, ["episode return", "mean of last 2 episodes"]),
        (1000, ["episode return", "mean of last 50 episodes"]),
        (5000, ["episode return", "mean of last 100 episodes"]),  # capped at 100
    ],
)
def test_learning_curve_legend_names_the_real_window(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, n_episodes: int, legend: list[str]
) -> None:
    """train's learning_curve.png never says "mean of last 1": its legend names the window
    the smoothed line really uses, or says the returns are not smoothed."""
    from palaestra.runs import curves

    drawn: list[list[str]] = []
    real_save = curves.save_figure

    def spy(fig: Any, path: Path) -> None:
        drawn.append([t.get_text() for t in fig.axes[0].get_legend().get_texts()])
        real_save(fig, path)

    monkeypatch.setattr(curves, "save_figure", spy)
    returns = np.arange(n_episodes, dtype=np.float64)
    episodes = curves.Episodes(10 * np.arange(1, n_episodes + 1), returns,
                               np.full(n_episodes, 10), None)  # fmt: skip
    curves.plot_learning_curve(episodes, tmp_path / "lc.png", "t")
    assert drawn == [legend]
    assert (tmp_path / "lc.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_run_without_episodes_is_left_out_and_said(tmp_path: Path, four_runs: list[Path]) -> None:
    empty = _fake_run(tmp_path, "a3", 0.9, 3, [], [])
    result = run_cli("compare", four_runs[0], four_runs[2], empty, "--labels", "g",
                     "--out", tmp_path / "c.png")  # fmt: skip
    assert result.code == 0, result.err
    assert _table(result.out)["g"][:4] == ["2", "30.00", "20.00", "40.00"]
    assert f"  g: {four_runs[0]}, {four_runs[2]}, {empty}\n" in result.out
    assert "    (1 run(s) without episodes left out)\n" in result.out
    (variant,) = json.loads((tmp_path / "summary.json").read_text())["variants"]
    assert variant["runs"] == [str(four_runs[0]), str(four_runs[2])]
    assert variant["seed_count"] == 2 and variant["seeds"] == [1, 2]
