"""The toy-text ids through the command line: listed, trained, evaluated, recorded."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from tests.cli.conftest import run_cli
from tests.envs.toy_text.cases import TOY_TEXT_IDS


def test_envs_lists_every_toy_text_id_with_its_spaces() -> None:
    result = run_cli("envs")
    assert result.code == 0, result.err
    rows = {line.split()[0]: line for line in result.out.splitlines() if line}
    for env_id in TOY_TEXT_IDS:
        assert env_id in rows, env_id
    # action space, threshold, max steps, presets (none), observation space
    assert rows["FrozenLake-v1"].split()[1:6] == ["Discrete(4)", "0.7", "100", "-", "Discrete(16)"]
    assert rows["Taxi-v4"].split()[1:6] == ["Discrete(6)", "8", "200", "-", "Discrete(500)"]
    assert "Tuple(Discrete(32), Discrete(11), Discrete(2))" in rows["Blackjack-v1"]


@pytest.mark.slow
# (CliffWalking has no time limit, as in Gymnasium: a policy that never reaches the goal would
# make eval and record run forever, so the ids with a limit stand for the tabular ones here.)
@pytest.mark.parametrize("algo, env_id", [("ppo", "FrozenLake-v1"), ("dqn", "Taxi-v4")])
def test_train_eval_record_on_discrete_observations(algo: str, env_id: str, tmp_path: Path) -> None:
    run = tmp_path / "run"
    result = run_cli("train", algo, env_id, "--timesteps", 256, "--n-envs", 2, "--seed", 0,
                     "--out", run, "--progress", "none", "--eval-episodes", 2,
                     "--set", "policy_kwargs.net_arch=[16]")  # fmt: skip
    assert result.code == 0, result.err
    assert json.loads((run / "config.json").read_text())["env_id"] == env_id
    result = run_cli("eval", run, "--episodes", 2)
    assert result.code == 0, result.err
    result = run_cli("record", run, "--out", tmp_path / "episode.gif")
    assert result.code == 0, result.err
    assert (tmp_path / "episode.gif").stat().st_size > 0


def test_train_on_blackjack_says_the_tuple_space_is_unsupported(tmp_path: Path) -> None:
    result = run_cli("train", "ppo", "Blackjack-v1", "--timesteps", 64, "--out", tmp_path / "r")
    assert result.code != 0
    assert "does not support Tuple spaces" in result.err
