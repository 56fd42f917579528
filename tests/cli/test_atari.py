"""The Atari path of the CLI: SB3's recipe (make_atari_env + VecFrameStack + CnnPolicy) from the
Breakout presets, rebuilt by eval and record, which score whole games."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from palaestra import presets

from .conftest import Result, run_cli

pytest.importorskip("ale_py")

BREAKOUT = "ALE/Breakout-v5"
# 256 steps of one env: PPO's rollout shrunk to fit, no checkpoints.
TINY = ("--timesteps", 256, "--n-envs", 1, "--checkpoint-every", 0, "--progress", "none")


@pytest.fixture(scope="session")
def atari_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Result]:
    """The PPO Breakout preset for 256 steps, evaluated on one game at the end."""
    import torch

    torch.set_num_threads(1)
    out = tmp_path_factory.mktemp("runs") / "breakout"
    result = run_cli("train", "ppo", BREAKOUT, *TINY, "--seed", 0, "--out", out,
                     "--set", "n_steps=64", "--set", "batch_size=64",
                     "--eval-episodes", 1)  # fmt: skip
    assert result.code == 0, result.err
    return out, result


def test_presets_resolve_to_the_atari_recipe() -> None:
    for algo in ("ppo", "dqn"):
        preset = presets.get_preset(algo, BREAKOUT)
        assert preset["atari"] is True and preset["frame_stack"] == 4
        assert preset["policy"] == "CnnPolicy"
        assert preset["env_kwargs"] == {"frameskip": 1}  # the wrapper skips 4, not the env
        presets.resolve(preset["hyperparams"])
    ppo = presets.resolve(presets.get_preset("ppo", BREAKOUT)["hyperparams"])
    assert ppo["learning_rate"](1.0) == pytest.approx(2.5e-4) and ppo["clip_range"](0.0) == 0.0
    dqn = presets.get_preset("dqn", BREAKOUT)
    assert dqn["hyperparams"]["optimize_memory_usage"] is True


def test_atari_id_without_preset_gets_the_recipe() -> None:
    from palaestra.runs.settings import resolve_settings

    settings, used, notes = resolve_settings("ppo", "ALE/Pong-v5", None, None, [])
    assert used is None and settings["atari"] is True and settings["policy"] == "CnnPolicy"
    assert "Atari recipe" in notes[0]


def test_train_writes_the_run(atari_run: tuple[Path, Result]) -> None:
    out, result = atari_run
    for name in ("config.json", "status.json", "progress.csv", "episodes.csv", "model.zip"):
        assert (out / name).is_file(), name
    config = json.loads((out / "config.json").read_text())
    assert (config["atari"], config["frame_stack"], config["policy"]) == (True, 4, "CnnPolicy")
    assert "evaluation (1 game, deterministic, seed 0)" in result.out
    assert "whole games" in result.out


def test_eval_scores_whole_games(
    cli: Callable[..., Result], atari_run: tuple[Path, Result]
) -> None:
    out, _ = atari_run
    result = cli("eval", out, "--episodes", 2)
    assert result.code == 0, result.err
    assert f"on {BREAKOUT}: 2 games, deterministic, seed 0" in result.out
    assert "whole games (all lives" in result.out
    assert "mean return:" in result.out and "game lengths in agent steps" in result.out


class RandomPolicy:
    def __init__(self) -> None:
        self.rng = np.random.default_rng(0)

    def predict(self, obs: np.ndarray, **_: Any) -> tuple[np.ndarray, None]:
        return self.rng.integers(0, 4, len(obs)), None


def test_play_episodes_counts_games_not_lives() -> None:
    """A lost life is a done for training, but a game has 5 lives: one game sees 5 dones."""
    from palaestra.runs.evaluation import play_episodes
    from palaestra.runs.recipe import make_vec

    config = {**presets.get_preset("ppo", BREAKOUT), "env_id": BREAKOUT}
    venv = make_vec(config, 1, seed=0)
    dones: list[bool] = []
    step = venv.step

    def counting_step(action: Any) -> Any:
        result = step(action)
        dones.append(bool(result[2][0]))
        return result

    venv.step = counting_step
    venv.seed(0)
    returns, lengths, terminated = play_episodes(RandomPolicy(), venv, 1)
    venv.close()
    assert sum(dones) == 5 and len(returns) == 1
    assert lengths == [len(dones)] and terminated == [True]


def test_record_writes_a_gif(
    cli: Callable[..., Result], atari_run: tuple[Path, Result], tmp_path: Path
) -> None:
    pytest.importorskip("PIL")
    out, _ = atari_run
    gif = tmp_path / "breakout.gif"
    result = cli("record", out, "--out", gif)
    assert result.code == 0, result.err
    assert gif.stat().st_size > 0
    assert "1 game(s)" in result.out and "at 15 fps" in result.out  # 60 Hz over frame skip 4


def test_dqn_preset_trains_with_the_frame_buffer(
    cli: Callable[..., Result], tmp_path: Path
) -> None:
    result = cli("train", "dqn", BREAKOUT, *TINY, "--seed", 0, "--out", tmp_path / "d",
                 "--set", "learning_starts=64", "--set", "buffer_size=1000",
                 "--eval-episodes", 0)  # fmt: skip
    assert result.code == 0, result.err
    assert (tmp_path / "d" / "replay_buffer.zip").is_file()


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (("dqn", BREAKOUT, "--set", "bogus=1"), "unknown --set key 'bogus' for dqn"),
        (("dqn", BREAKOUT, "--set", "atari.skip=4"), "unknown AtariWrapper setting(s) ['skip']"),
        (("ppo", BREAKOUT, "--set", "frame_stack=0"), "frame_stack must be a positive integer"),
        (("ppo", "CartPole-v1", "--set", "atari=true"), "CartPole-v1 is not an Atari game"),
        (("ppo", BREAKOUT, "--set", "normalize=true"), "normalize does not apply to the Atari"),
        (
            ("ppo", BREAKOUT, "--set", "atari.noop_max=-1"),
            "atari.noop_max must be a int from 0 to 10000, got -1",
        ),
    ],
)
def test_bad_atari_settings_give_one_line(
    cli: Callable[..., Result], tmp_path: Path, args: tuple[str, ...], expected: str
) -> None:
    result = cli("train", *args, "--out", tmp_path / "r")
    assert result.code == 2
    assert result.err.count("\n") == 1 and result.err.startswith("palaestra: error: ")
    assert expected in result.err
    assert not (tmp_path / "r").exists()


def test_missing_ale_py_is_one_line(tmp_path: Path) -> None:
    code = (
        "import sys; sys.modules['ale_py'] = None\n"
        "from palaestra.cli import main\n"
        f"sys.exit(main(['train', 'ppo', '{BREAKOUT}', '--out', {str(tmp_path / 'r')!r}]))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 1
    assert proc.stderr.count("\n") == 1, proc.stderr
    assert 'pip install "palaestra[atari]"' in proc.stderr
    assert not (tmp_path / "r").exists()


def test_compare_says_atari_episodes_are_games(
    cli: Callable[..., Result], atari_run: tuple[Path, Result], tmp_path: Path
) -> None:
    pytest.importorskip("matplotlib")
    out, _ = atari_run
    result = cli("compare", out, "--out", tmp_path / "c.png")
    assert result.code == 0, result.err
    assert "(Atari runs: training episodes are whole games" in result.out


def test_eval_of_an_atari_run_on_a_non_atari_env_is_one_line(
    cli: Callable[..., Result], atari_run: tuple[Path, Result]
) -> None:
    out, _ = atari_run
    result = cli("eval", out, "--env", "CartPole-v1")
    assert result.code == 2 and result.err.count("\n") == 1
    assert "trained on SB3's Atari recipe; CartPole-v1 is not an Atari game" in result.err


@pytest.mark.parametrize("algo", ["ppo", "dqn"])
def test_breakout_presets_carry_their_measurement(algo: str) -> None:
    measured = presets.get_preset(algo, BREAKOUT)["measured"]
    assert measured["seeds"] == [0] and measured["games"] == 20
    for key in ("mean_return", "random_mean_return", "wall_s", "frames", "load_average_1m"):
        assert key in measured, key
    assert measured["command"].startswith(f"palaestra train {algo} {BREAKOUT} --seed 0")
