"""``palaestra train qrdqn``: the algorithm registered by one line trains from the CLI with its
preset, leaves a model file and a replay buffer, and ``palaestra eval`` plays the model."""

from __future__ import annotations

from pathlib import Path

from palaestra import presets
from palaestra.algos.qrdqn import QRDQN

from .conftest import run_cli


def test_cli_trains_qrdqn_on_cartpole(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = run_cli("train", "qrdqn", "CartPole-v1", "--timesteps", 600, "--seed", 0,
                     "--set", "learning_starts=200", "--set", "train_freq=16",
                     "--set", "gradient_steps=4", "--out", out, "--progress", "none")  # fmt: skip
    assert result.code == 0, result.err
    assert "trained qrdqn on CartPole-v1" in result.out
    assert (out / "replay_buffer.zip").is_file()
    model = QRDQN.load(out / "model.zip")
    preset = presets.get_preset("qrdqn", "CartPole-v1")["hyperparams"]
    assert model.num_timesteps >= 600 and model.learning_starts == 200
    assert model.policy_kwargs == preset["policy_kwargs"] and model.n_quantiles == 10
    result = run_cli("eval", out / "model.zip", "--episodes", 2, "--seed", 7)
    assert result.code == 0, result.err
    assert result.out.splitlines()[0] == (
        f"QRDQN {out / 'model.zip'} on CartPole-v1: 2 episodes, deterministic, seed 7"
    )
