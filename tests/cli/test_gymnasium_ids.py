"""``gymnasium:ID``: any env of the installed Gymnasium trains, evaluates and records."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from tests.cli.conftest import run_cli

gymnasium = pytest.importorskip("gymnasium")


def test_train_and_eval_a_gymnasium_env(tmp_path: Path) -> None:
    out = tmp_path / "run"
    r = run_cli("train", "ppo", "gymnasium:Acrobot-v1", "--timesteps", 256, "--seed", 0,
                "--out", out, "--progress", "none", "--eval-episodes", 1)  # fmt: skip
    assert r.code == 0, r.err
    assert "no preset for ppo on gymnasium:Acrobot-v1" in r.err
    assert json.loads((out / "config.json").read_text())["env_id"] == "gymnasium:Acrobot-v1"
    shown = run_cli("eval", out, "--episodes", 2)
    assert shown.code == 0, shown.err
    assert "on gymnasium:Acrobot-v1: 2 episodes" in shown.out
    # Gymnasium's time limit and threshold came with the spec
    import palaestra

    spec = palaestra.spec("gymnasium:Acrobot-v1")
    assert (spec.max_episode_steps, spec.reward_threshold) == (500, -100.0)


@pytest.mark.parametrize(
    ("env", "message"),
    [
        ("gymnasium:Nope-v1", "'Nope-v1' is not in Gymnasium's registry"),
        ("gymnasium:Taxi-v3", "'Taxi-v3' is deprecated in Gymnasium's registry"),
    ],
)
def test_unknown_gymnasium_ids_are_one_line(tmp_path: Path, env: str, message: str) -> None:
    r = run_cli("train", "ppo", env, "--out", tmp_path / "r")
    assert r.code == 2 and r.err.count("\n") == 1 and message in r.err, r.err
    assert not (tmp_path / "r").exists()
