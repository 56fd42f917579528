"""``palaestra compare`` on hand-written runs, and the t-interval against hand computations."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from palaestra.runs.curves import read_episodes, rolling_mean
from palaestra.runs.stats import confidence_interval, t_cdf, t_quantile

from .conftest import run_cli

# Student t 0.975 and 0.995 quantiles from printed tables (e.g. NIST/SEMATECH 1.3.6.7.2).
T_TABLE = {1: (12.706, 63.657), 2: (4.303, 9.925), 3: (3.182, 5.841), 4: (2.776, 4.604),
           9: (2.262, 3.250), 29: (2.045, 2.756), 100: (1.984, 2.626)}  # fmt: skip


@pytest.mark.parametrize("df", sorted(T_TABLE))
def test_t_quantile_matches_tables(df: int) -> None:
    q975, q995 = T_TABLE[df]
    assert t_quantile(0.975, df) == pytest.approx(q975, abs=6e-4)
    assert t_quantile(0.995, df) == pytest.approx(q995, abs=6e-4)
    assert t_quantile(0.025, df) == pytest.approx(-q975, abs=6e-4)
    assert t_cdf(t_quantile(0.9, df), df) == pytest.approx(0.9, abs=1e-12)


def test_t_cdf_closed_forms() -> None:
    # df=1 is the Cauchy distribution, df=2 has F(t) = 1/2 + t / (2 sqrt(2 + t^2)).
    for t in (-3.0, -0.5, 0.0, 0.7, 5.0):
        assert t_cdf(t, 1) == pytest.approx(0.5 + math.atan(t) / math.pi, abs=1e-12)
        assert t_cdf(t, 2) == pytest.approx(0.5 + t / (2 * math.sqrt(2 + t * t)), abs=1e-12)


def test_confidence_interval_by_hand() -> None:
    # [20, 40]: mean 30, s = 14.1421, se = 10, t(0.975, 1) = 12.7062 -> 30 ± 127.062
    mean, low, high = confidence_interval([20.0, 40.0])
    assert (mean, low, high) == pytest.approx((30.0, -97.062, 157.062), abs=1e-3)
    # [1, 2, 3, 4]: mean 2.5, s = 1.29099, se = 0.645497, t(0.975, 3) = 3.18245
    assert confidence_interval([1, 2, 3, 4]) == pytest.approx((2.5, 0.44574, 4.55426), abs=1e-5)
    mean, low, high = confidence_interval([7.0])
    assert mean == 7.0 and math.isnan(low) and math.isnan(high)
    with pytest.raises(ValueError, match="p must be in"):
        t_quantile(1.0, 3)


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
    # gamma=0.9: finals 20 and 40 -> 30 ± 127.062; success (1/3 + 2/3) / 2 = 50%
    assert rows["gamma=0.9"] == ["2", "30.00", "-97.06", "157.06", "50.0%", "-"]  # no status
    # gamma=0.99: finals 100 and 110 -> 105 ± 12.7062 * 5 = 63.531
    assert rows["gamma=0.99"] == ["2", "105.00", "41.47", "168.53", "0.0%", "-"]
    assert f"  gamma=0.9: {four_runs[0]}, {four_runs[2]}" in result.out
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert result.out.strip().endswith(f"wrote {plot}")


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
