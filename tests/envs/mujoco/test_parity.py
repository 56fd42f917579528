"""The MuJoCo envs against Gymnasium 1.4.0's v5 envs: every reset and step bit for bit.

palaestra's side runs in a subprocess in which ``gymnasium`` cannot be imported and in which
every model MuJoCo compiles is noted: each must be one of palaestra's own files. Gymnasium's
side runs here. Observations, rewards, flags, infos (values, dtypes and types) and the actions
drawn (``action_space.sample()`` on each side's own seeded space) must be identical.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.envs.mujoco.cases import MUJOCO_IDS, long_runs, short_runs
from tests.envs.mujoco.trajectories import Run, record

gymnasium = pytest.importorskip("gymnasium")
pytest.importorskip("mujoco")

PACKAGE = Path(__file__).resolve().parents[3] / "src" / "palaestra"


def palaestra_records(runs: list[Run], tmp_path: Path) -> dict[str, Any]:
    """Run ``runs`` on palaestra in a fresh interpreter with gymnasium blocked."""
    out = tmp_path / "records.pkl"
    spec = json.dumps([dataclasses.asdict(run) for run in runs])
    subprocess.run(
        [sys.executable, "-m", "tests.envs.mujoco.trajectories", str(out)],
        input=spec,
        text=True,
        check=True,
        cwd=PACKAGE.parents[1],
        env={**os.environ, "PYTHONPATH": f"{PACKAGE.parent}{os.pathsep}{PACKAGE.parents[1]}"},
        timeout=900,
    )
    with open(out, "rb") as file:
        result: dict[str, Any] = pickle.load(file)
    return result


def _describe(ours: Any, ref: Any) -> str:
    """Where two encoded records first differ, with the largest difference of arrays."""
    for i, (a, b) in enumerate(zip(ours, ref)):
        if a == b:
            continue
        if isinstance(a, dict) and isinstance(b, dict):
            keys = [k for k in a.keys() | b.keys() if a.get(k) != b.get(k)]
            return f"item {i}: info keys {sorted(keys)} differ: " + "; ".join(
                f"{k}: {_describe([a.get(k)], [b.get(k)])}" for k in sorted(keys)
            )
        if isinstance(a, tuple) and len(a) == 4 and isinstance(b, tuple) and len(b) == 4:
            x = np.frombuffer(a[3], dtype=a[1])
            y = np.frombuffer(b[3], dtype=b[1])
            diff = np.max(np.abs(x - y)) if x.shape == y.shape else "shapes differ"
            return f"item {i}: {a[:3]} vs {b[:3]}, max |difference| {diff}"
        return f"item {i}: {a!r} vs {b!r}"
    return "lengths differ"


def check_parity(runs: list[Run], tmp_path: Path) -> None:
    result = palaestra_records(runs, tmp_path)
    assert result["package"].startswith(str(PACKAGE)), result["package"]
    assert result["gymnasium_loaded"] == []
    assert result["compiled"], "no model compiled"
    for path in result["compiled"]:
        assert Path(path).resolve().is_relative_to(PACKAGE), path
    for run, ours in zip(runs, result["records"], strict=True):
        ref = record(gymnasium.make, run)
        assert len(ours) == len(ref), run
        for t, (a, b) in enumerate(zip(ours, ref)):
            assert a == b, f"{run}, record {t}: {_describe(a, b)}"
        assert sum(r[0] == "reset" for r in ours) >= 2 or run.steps < 1000, run


@pytest.mark.parametrize("env_id", MUJOCO_IDS)
def test_short_parity(env_id: str, tmp_path: Path) -> None:
    check_parity(short_runs(env_id), tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("env_id", MUJOCO_IDS)
def test_long_parity(env_id: str, tmp_path: Path) -> None:
    """1,200 steps with uniform and with sampled actions, defaults and two option sets."""
    check_parity(long_runs(env_id), tmp_path)
