"""``Monitor`` against Stable-Baselines3's: episode infos, getters and the CSV file."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from stable_baselines3.common.monitor import Monitor as SB3Monitor
from tests.wrappers.conftest import GYM, assert_same, make_toy, pal

from palaestra.envs.env_spec import EnvSpec
from palaestra.error import DependencyNotInstalled
from palaestra.wrappers.monitor import (
    LoadMonitorResultsError,
    Monitor,
    get_monitor_files,
    load_results,
    read_monitor_file,
)


def _drive(env: Any, steps: int = 90, **reset_kwargs: Any) -> list[dict[str, Any]]:
    """Step with seeded actions, resetting at episode ends; return the episode infos."""
    rng = np.random.default_rng(0)
    env.reset(seed=5, **reset_kwargs)
    episodes = []
    for _ in range(steps):
        *_, terminated, truncated, info = env.step(int(rng.integers(3)))
        if terminated or truncated:
            episodes.append(info["episode"])
            env.reset(**reset_kwargs)
    return episodes


def _pair(tmp_path: Path, **kwargs: Any) -> tuple[Any, Any]:
    theirs_env = make_toy(GYM, "ToyChain")
    theirs_env.spec = GYM.EnvSpec("Toy-v0")
    ours_env = make_toy(pal(), "ToyChain")
    ours_env.spec = EnvSpec("Toy-v0")
    return (
        SB3Monitor(theirs_env, str(tmp_path / "sb3"), **kwargs),
        Monitor(ours_env, str(tmp_path / "ours"), **kwargs),
    )


def _rows(path: Path) -> tuple[dict[str, Any], list[str], list[dict[str, str]]]:
    with open(path) as f:
        header = json.loads(f.readline()[1:])
        reader = csv.DictReader(f)
        return header, list(reader.fieldnames or []), list(reader)


def _without_t(items: list[dict[str, Any]]) -> list[dict[str, Any]]:
    for item in items:
        assert float(item["t"]) >= 0
    return [{k: v for k, v in item.items() if k != "t"} for item in items]


def test_episode_infos_getters_and_csv_match_sb3(tmp_path: Path) -> None:
    theirs, ours = _pair(tmp_path, info_keywords=("pos",))
    expected, got = _drive(theirs), _drive(ours)
    assert len(got) >= 4
    assert_same(_without_t(got), _without_t(expected))
    assert ours.get_episode_rewards() == theirs.get_episode_rewards()
    assert ours.get_episode_lengths() == theirs.get_episode_lengths()
    assert len(ours.get_episode_times()) == len(theirs.get_episode_times())
    assert ours.get_total_steps() == theirs.get_total_steps() == 90
    theirs.close()
    ours.close()

    t_header, t_fields, t_rows = _rows(tmp_path / "sb3.monitor.csv")
    o_header, o_fields, o_rows = _rows(tmp_path / "ours.monitor.csv")
    assert list(o_header) == list(t_header) == ["t_start", "env_id"]
    assert o_header["env_id"] == t_header["env_id"] == "Toy-v0"
    assert abs(o_header["t_start"] - t_header["t_start"]) < 60
    assert o_fields == t_fields == ["r", "l", "t", "pos"]
    assert _without_t(o_rows) == _without_t(t_rows)


def test_reset_keywords_are_required_and_logged(tmp_path: Path) -> None:
    def with_level(lib: Any) -> Any:
        toy = make_toy(lib, "ToyChain")
        inner_reset = toy.reset
        toy.reset = lambda *, seed=None, options=None, level=None: inner_reset(seed=seed)
        return toy

    theirs = SB3Monitor(with_level(GYM), str(tmp_path / "a"), reset_keywords=("level",))
    ours = Monitor(with_level(pal()), str(tmp_path / "b"), reset_keywords=("level",))
    for env in (theirs, ours):
        with pytest.raises(ValueError, match="Expected you to pass keyword argument level"):
            env.reset(seed=1)
    assert_same(_without_t(_drive(ours, level=3)), _without_t(_drive(theirs, level=3)))
    ours.close()
    theirs.close()
    assert _rows(tmp_path / "b.monitor.csv")[1] == ["r", "l", "t", "level"]
    assert _without_t(_rows(tmp_path / "b.monitor.csv")[2]) == _without_t(
        _rows(tmp_path / "a.monitor.csv")[2]
    )


def test_early_reset_and_step_before_reset_raise_like_sb3() -> None:
    for cls, lib in ((SB3Monitor, GYM), (Monitor, pal())):
        env = cls(make_toy(lib, "ToyChain"), allow_early_resets=False)
        with pytest.raises(RuntimeError, match="Tried to step environment that needs reset"):
            env.step(1)
        env.reset(seed=0)
        env.step(1)
        with pytest.raises(RuntimeError, match="Tried to reset an environment before done"):
            env.reset()


def test_no_file_by_default_and_info_episode_only_at_end(tmp_path: Path) -> None:
    env = Monitor(make_toy(pal(), "ToyChain"))
    assert env.results_writer is None
    env.reset(seed=0)
    *_, terminated, truncated, info = env.step(1)
    assert ("episode" in info) == (terminated or truncated)
    assert not list(tmp_path.iterdir())


def test_append_mode_keeps_one_header(tmp_path: Path) -> None:
    for override in (True, False):
        env = Monitor(make_toy(pal(), "ToyChain"), str(tmp_path), override_existing=override)
        _drive(env, steps=40)
        env.close()
    text = (tmp_path / "monitor.csv").read_text()
    assert text.count("#{") == 1 and text.count("r,l,t") == 1
    _, columns = read_monitor_file(str(tmp_path / "monitor.csv"))
    assert len(columns["r"]) >= 4 and columns["l"].dtype == np.int64


def test_read_monitor_file_reads_sb3_files(tmp_path: Path) -> None:
    theirs = SB3Monitor(make_toy(GYM, "ToyChain"), str(tmp_path / "x"), info_keywords=("pos",))
    _drive(theirs)
    theirs.close()
    header, columns = read_monitor_file(str(tmp_path / "x.monitor.csv"))
    assert header["env_id"] == "None"
    np.testing.assert_allclose(columns["r"], np.round(theirs.get_episode_rewards(), 6))
    assert columns["l"].tolist() == theirs.get_episode_lengths()
    assert list(columns) == ["r", "l", "t", "pos"]
    assert get_monitor_files(str(tmp_path)) == [str(tmp_path / "x.monitor.csv")]


def test_read_monitor_file_rejects_other_csv(tmp_path: Path) -> None:
    bad = tmp_path / "bad.monitor.csv"
    bad.write_text("r,l,t\n1,2,3\n")
    with pytest.raises(LoadMonitorResultsError, match="not a monitor file"):
        read_monitor_file(str(bad))


def test_load_results_without_pandas_names_it(tmp_path: Path, monkeypatch: Any) -> None:
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas -> ImportError
    with pytest.raises(DependencyNotInstalled) as info:
        load_results(str(tmp_path))
    assert str(info.value) == (
        'pandas is not installed, run `pip install "palaestra[monitor]"` (needed for '
        "load_results; read_monitor_file works without it)"
    )


def test_load_results(tmp_path: Path) -> None:
    pandas = pytest.importorskip("pandas")
    with pytest.raises(LoadMonitorResultsError, match="No monitor files"):
        load_results(str(tmp_path))
    for name in ("a", "b"):
        env = Monitor(make_toy(pal(), "ToyChain"), str(tmp_path / name))
        _drive(env, steps=30)
        env.close()
    frame = load_results(str(tmp_path))
    assert isinstance(frame, pandas.DataFrame)
    assert list(frame["t"]) == sorted(frame["t"])


def test_a_row_torn_by_a_crash_is_skipped_and_cut(tmp_path: Path) -> None:
    path = tmp_path / "monitor.csv"
    env = Monitor(make_toy(pal(), "ToyChain"), str(tmp_path))
    episodes = _drive(env, steps=40)
    env.close()
    with open(path, "a", newline="") as file:
        file.write("-3.5,1")  # killed in the middle of a row: no line end
    _, columns = read_monitor_file(str(path))
    assert columns["l"].tolist() == [e["l"] for e in episodes]  # the torn row is not read
    env = Monitor(make_toy(pal(), "ToyChain"), str(tmp_path), override_existing=False)
    more = _drive(env, steps=40)
    env.close()
    _, columns = read_monitor_file(str(path))
    assert columns["l"].tolist() == [e["l"] for e in episodes + more]  # cut, then appended
    assert "-3.5,1" not in path.read_text()
