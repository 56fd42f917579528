"""``palaestra train``: run-folder contents, settings layering, Ctrl-C checkpoints and resume."""

from __future__ import annotations

import csv
import json
import os
import re
import signal
from pathlib import Path

import numpy as np
import pytest
import torch

from palaestra import presets
from palaestra.algos import A2C, DQN, PPO, LinearSchedule
from palaestra.algos.callbacks import BaseCallback
from palaestra.cli import train
from palaestra.runs.settings import resolve_settings

from .conftest import Result, run_cli, wait_for_file


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as file:
        return list(csv.DictReader(file))


def _untimed(row: dict[str, str]) -> dict[str, str]:
    """An episodes.csv row without its training seconds (which differ between two runs)."""
    return {k: v for k, v in row.items() if k != "time_s"}


def test_ppo_run_folder_and_summary(ppo_run: tuple[Path, Result]) -> None:
    out, result = ppo_run
    for name in ("config.json", "status.json", "progress.csv", "episodes.csv", "model.zip"):
        assert (out / name).is_file(), name
    assert wait_for_file(out / "learning_curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in (out / "checkpoints").iterdir())[0].startswith("model_")
    config = json.loads((out / "config.json").read_text())
    preset = presets.get_preset("ppo", "CartPole-v1")
    assert config["preset"] == "default" and config["n_envs"] == preset["n_envs"] == 8
    assert config["hyperparams"] == preset["hyperparams"]  # recorded unresolved: "lin_0.001"
    assert config["n_timesteps"] == 512 and config["seed"] == 0
    status = json.loads((out / "status.json").read_text())
    assert status["status"] == "finished" and status["num_timesteps"] == 512
    progress = _rows(out / "progress.csv")
    assert [int(r["time/total_timesteps"]) for r in progress] == [256, 512]
    episodes = _rows(out / "episodes.csv")
    steps = [int(r["steps"]) for r in episodes]
    assert episodes and steps == sorted(steps) and steps[-1] <= 512
    assert all(r["terminated"] in ("0", "1") for r in episodes)
    model = PPO.load(out / "model.zip")
    assert model.num_timesteps == 512 and model.n_envs == 8
    assert model.lr_schedule == LinearSchedule(0.001, 0.0)  # "lin_0.001" became a schedule
    # The summary: steps, wall time, fps, final mean return, a deterministic evaluation.
    summary = result.out
    assert re.search(r"trained ppo on CartPole-v1: 512 steps, wall time \d+:\d\d:\d\d", summary)
    assert re.search(r"[\d,]+ fps", summary)
    last = re.search(r"mean return over the last (\d+) training episodes: (-?[\d.]+)", summary)
    assert last is not None
    n = int(last[1])
    returns = [float(r["return"]) for r in episodes[-n:]]
    assert float(last[2]) == pytest.approx(np.mean(returns), abs=0.006)
    assert re.search(r"evaluation \(10 episodes, deterministic, seed 0\):", summary)
    assert "success rate" not in summary  # CartPole terminates on failure: not a goal env


def test_dqn_run_with_set_override(dqn_run: tuple[Path, Result]) -> None:
    out, result = dqn_run
    config = json.loads((out / "config.json").read_text())
    preset = presets.get_preset("dqn", "MountainCar-v0")["hyperparams"]
    assert config["hyperparams"] == {**preset, "learning_starts": 100}
    assert (out / "replay_buffer.zip").is_file() and wait_for_file(out / "learning_curve.png")
    model = DQN.load(out / "model.zip")
    assert model.learning_starts == 100 and model.num_timesteps >= 300
    assert model.policy_kwargs["net_arch"] == preset["policy_kwargs"]["net_arch"]
    rate = re.search(r"success rate: ([\d.]+)% \((\d+)/10 episodes", result.out)
    assert rate is not None and 0 <= float(rate[1]) <= 100
    assert "trained dqn on MountainCar-v0" in result.out


def test_settings_layering(tmp_path: Path) -> None:
    """preset < --config file < --set; dicts merge key by key."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("n_envs: 2\nhyperparams:\n  gamma: 0.9\n  policy_kwargs: {net_arch: [8]}\n"
                   "batch_size: 16\n")  # fmt: skip
    settings, used, notes = resolve_settings(
        "ppo", "CartPole-v1", None, str(cfg), ["gamma=0.5", "policy_kwargs.activation_fn=relu"]
    )
    base = presets.get_preset("ppo", "CartPole-v1")
    assert used == "default" and notes == []
    assert settings["n_envs"] == 2 and settings["n_timesteps"] == base["n_timesteps"]
    hyper = settings["hyperparams"]
    assert hyper["gamma"] == 0.5 and hyper["batch_size"] == 16
    assert hyper["n_steps"] == base["hyperparams"]["n_steps"]
    assert hyper["policy_kwargs"] == {"net_arch": [8], "activation_fn": "relu"}
    resolved = presets.resolve(hyper)
    assert resolved["policy_kwargs"]["activation_fn"] is torch.nn.ReLU
    assert resolved["learning_rate"] == LinearSchedule(0.001, 0.0)
    # JSON config in the preset's own shape; a config.json of a run is accepted as well.
    cfg_json = tmp_path / "c.json"
    cfg_json.write_text(json.dumps({"algo": "ppo", "env_id": "CartPole-v1", "n_steps": 64}))
    settings, *_ = resolve_settings("ppo", "CartPole-v1", None, str(cfg_json), [])
    assert settings["hyperparams"]["n_steps"] == 64


@pytest.mark.filterwarnings("ignore:.*CartPole-v0 is out of date:DeprecationWarning")
def test_no_preset_uses_algorithm_defaults(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from palaestra.cli import progress

    monkeypatch.setattr(progress, "LINE_INTERVAL_S", 0.0)  # a progress line at every step
    result = run_cli("train", "DQN", "CartPole-v0", "--timesteps", 64, "--out", tmp_path / "r",
                     "--progress", "line", "--eval-episodes", 0,
                     "--set", "policy_kwargs.net_arch=[16]", "--set", "learning_starts=32",
                     "--set", "policy_kwargs.activation_fn=tanh")  # fmt: skip
    assert result.code == 0, result.err
    assert "note: no preset for dqn on CartPole-v0: using the DQN defaults" in result.err
    config = json.loads((tmp_path / "r" / "config.json").read_text())
    assert config["preset"] is None and config["n_envs"] == 1
    model = DQN.load(tmp_path / "r" / "model.zip")
    assert model.batch_size == 32 and model.gamma == 0.99  # SB3's defaults
    assert model.policy_kwargs == {"net_arch": [16], "activation_fn": torch.nn.Tanh}
    lines = [line for line in result.err.splitlines() if " fps | " in line]
    assert len(lines) == 64
    assert re.fullmatch(
        r" +64/64 steps \| [\d,]+ fps \| mean return (-?[\d.]+|-) \| ETA 0:00:00", lines[-1]
    ), lines[-1]


class _InterruptAt(BaseCallback):
    """Simulates Ctrl-C: a KeyboardInterrupt from inside ``learn``."""

    def __init__(self, steps: int) -> None:
        super().__init__()
        self.steps = steps

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.steps:
            raise KeyboardInterrupt
        return True


def _status(out: Path) -> dict[str, object]:
    return json.loads((out / "status.json").read_text())


DQN_ARGS = ["dqn", "CartPole-v1", "--timesteps", 600, "--seed", 3, "--n-envs", 1,
            "--set", "learning_starts=50", "--set", "train_freq=4", "--set", "gradient_steps=1",
            "--checkpoint-every", 60, "--progress", "none", "--eval-episodes", 0]  # fmt: skip
PPO_ARGS = ["ppo", "CartPole-v1", "--n-envs", 4, "--timesteps", 512, "--seed", 1,
            "--set", "n_steps=16", "--set", "batch_size=32", "--set", "n_epochs=1",
            "--checkpoint-every", 100, "--progress", "none", "--eval-episodes", 0]  # fmt: skip


PPO_NORM_ARGS = [*PPO_ARGS, "--set", "normalize=true"]  # VecNormalize's statistics resume too
# A2C's Acrobot preset normalises; rollouts of 5 x 4 steps between checkpoints every 100.
A2C_ARGS = ["a2c", "Acrobot-v1", "--n-envs", 4, "--timesteps", 500, "--seed", 2,
            "--checkpoint-every", 100, "--progress", "none", "--eval-episodes", 0]  # fmt: skip


def _params(path: Path, algo: type) -> dict[str, torch.Tensor]:
    return algo.load(path).policy.state_dict()


def _assert_same_params(a: Path, b: Path, algo: type) -> None:
    pa, pb = _params(a, algo), _params(b, algo)
    assert pa.keys() == pb.keys()
    for key in pa:
        assert torch.equal(pa[key], pb[key]), key


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The DQN, PPO and A2C runs of the resume tests, never stopped."""
    runs = {}
    cases = [("dqn", DQN_ARGS), ("ppo", PPO_ARGS), ("ppo-norm", PPO_NORM_ARGS), ("a2c", A2C_ARGS)]
    for name, args in cases:
        out = tmp_path_factory.mktemp("full") / name
        result = run_cli("train", *args, "--out", out)
        assert result.code == 0, result.err
        runs[name] = out
    return runs


def test_second_ctrl_c_keeps_the_last_checkpoint_and_resume_is_exact(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, uninterrupted: dict[str, Path]
) -> None:
    out = tmp_path / "run"
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_InterruptAt(200)])
    result = run_cli("train", *DQN_ARGS, "--out", out)
    assert result.code == 130
    assert result.err.strip().splitlines()[-1] == (
        f"palaestra: stopped at once at 200/600 steps; --resume continues from the checkpoint "
        f"at 180 steps (palaestra train --resume {out})"
    )
    status = _status(out)
    assert (status["status"], status["num_timesteps"], status["total_timesteps"]) == (
        "interrupted",
        180,
        600,
    )
    assert status["checkpoint"] == "resume/step_180"
    checkpoint = DQN.load(out / "resume" / "step_180" / "model.zip")
    checkpoint.load_replay_buffer(out / "resume" / "step_180" / "replay_buffer.zip")
    assert checkpoint.num_timesteps == 180
    assert checkpoint.replay_buffer is not None and checkpoint.replay_buffer.size() == 180
    assert not (out / "model.zip").exists()  # the torn in-memory model was not saved
    episodes_before = _rows(out / "episodes.csv")
    progress_before = (out / "progress.csv").read_text().splitlines()

    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [])
    result = run_cli("train", "--resume", out, "--progress", "none", "--eval-episodes", 0)
    assert result.code == 0, result.err
    assert "from step 180 to 600 steps" in result.err
    assert _status(out)["status"] == "finished" and _status(out)["num_timesteps"] == 600
    resumed = DQN.load(out / "model.zip")
    assert resumed.num_timesteps == 600
    assert resumed._progress_remaining == 0.0
    assert resumed.exploration_rate == pytest.approx(resumed.exploration_final_eps)
    _assert_same_params(out / "model.zip", uninterrupted["dqn"] / "model.zip", DQN)
    # The rows logged between the checkpoint (180) and the stop (200) are logged once, again.
    episodes = _rows(out / "episodes.csv")
    kept = [row for row in episodes_before if int(row["steps"]) <= 180]
    assert len(kept) < len(episodes_before)
    assert episodes[: len(kept)] == kept and int(episodes[len(kept)]["steps"]) > 180
    assert [r["steps"] for r in episodes] == sorted({r["steps"] for r in episodes}, key=int)
    full_episodes = _rows(uninterrupted["dqn"] / "episodes.csv")
    # The exact run logs the same episodes (at other seconds of training).
    assert [_untimed(r) for r in episodes] == [_untimed(r) for r in full_episodes]
    times = [float(r["time_s"]) for r in episodes]
    assert times == sorted(times)  # the resumed session counts on from the first one's time
    progress = (out / "progress.csv").read_text().splitlines()
    assert len(progress) > len(progress_before)


class _StopRequestAt(BaseCallback):
    """Asks for a graceful stop (what the first Ctrl-C or SIGTERM does) at given steps."""

    def __init__(self, steps: list[int]) -> None:
        super().__init__()
        self.steps = steps

    def _on_step(self) -> bool:
        if self.steps and self.num_timesteps >= self.steps[0]:
            self.steps.pop(0)
            os.kill(os.getpid(), signal.SIGINT)
        return True


@pytest.mark.parametrize("algo", ["dqn", "ppo", "ppo-norm", "a2c"])
def test_graceful_stops_anywhere_resume_to_the_same_bits(
    algo: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, uninterrupted: dict[str, Path]
) -> None:
    args, cls = {
        "dqn": (DQN_ARGS, DQN),
        "ppo": (PPO_ARGS, PPO),
        "ppo-norm": (PPO_NORM_ARGS, PPO),
        "a2c": (A2C_ARGS, A2C),
    }[algo]
    out = tmp_path / "run"
    # Stops inside rollouts, right after a checkpoint, on a rollout's last step.
    stops = [37, 101, 188, 256, 444] if algo == "dqn" else [12, 100, 200, 256, 380]
    for i, at in enumerate(stops):
        monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_StopRequestAt([at])])
        first = ["train", *args, "--out", out] if i == 0 else ["train", "--resume", out]
        result = run_cli(*first, "--progress", "none", "--eval-episodes", 0)
        assert result.code == 130, result.err
        assert _status(out)["status"] == "interrupted"
        assert _status(out)["num_timesteps"] >= at
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [])
    result = run_cli("train", "--resume", out, "--progress", "none", "--eval-episodes", 0)
    assert result.code == 0, result.err
    assert "note:" not in result.err  # exact: no "starts new episodes"
    _assert_same_params(out / "model.zip", uninterrupted[algo] / "model.zip", cls)
    assert len(list((out / "resume").iterdir())) == 2  # the newest KEEP checkpoints
    if algo in ("ppo-norm", "a2c"):
        saved = np.load(out / "vecnormalize.npz")
        full = np.load(uninterrupted[algo] / "vecnormalize.npz")
        assert all(np.array_equal(saved[k], full[k]) for k in full.files)


def test_extended_finished_run_trains(tmp_path: Path, uninterrupted: dict[str, Path]) -> None:
    import shutil

    out = tmp_path / "run"
    shutil.copytree(uninterrupted["ppo"], out)
    before = _params(out / "model.zip", PPO)
    result = run_cli("train", "--resume", out, "--timesteps", 1024, "--progress", "none",
                     "--eval-episodes", 0)  # fmt: skip
    assert result.code == 0, result.err
    assert "note: extending the run from 512 to 1,024 steps" in result.err
    after = _params(out / "model.zip", PPO)
    assert any(not torch.equal(before[k], after[k]) for k in before)
    assert PPO.load(out / "model.zip").num_timesteps == 1024


def test_ppo_interrupt_then_resume_to_the_same_total(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "run"
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_InterruptAt(300)])
    args = ["--set", "n_steps=16", "--set", "batch_size=32", "--set", "n_epochs=1"]
    result = run_cli("train", "ppo", "CartPole-v1", "--n-envs", 4, "--timesteps", 512,
                     *args, "--out", out, "--progress", "bar", "--eval-episodes", 0)  # fmt: skip
    # Stopped at once at 300: the status points at the last checkpoint (every 51 steps).
    assert result.code == 130 and _status(out)["num_timesteps"] == 256
    assert re.search(r"\d+/512 \[", result.err)  # the tqdm bar
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [])
    result = run_cli("train", "--resume", out, "--progress", "none", "--eval-episodes", 0)
    assert result.code == 0, result.err
    model = PPO.load(out / "model.zip")
    assert 512 <= model.num_timesteps < 512 + 64  # one rollout is 16 steps x 4 envs
    assert json.loads((out / "config.json").read_text())["n_timesteps"] == 512
    # A finished run resumes only to a larger budget.
    again = run_cli("train", "--resume", out, "--progress", "none")
    assert again.code == 2
    assert again.err.strip() == (
        f"palaestra: error: {out} already trained {model.num_timesteps} of its 512 steps "
        f"(pass --timesteps larger than {model.num_timesteps} to train further)"
    )


class _SigintAt(BaseCallback):
    """Sends this process a real SIGINT, as a terminal's Ctrl-C does."""

    def _on_step(self) -> bool:
        if self.num_timesteps == 96:
            os.kill(os.getpid(), signal.SIGINT)
        return True


def test_real_sigint_stops_at_the_next_step(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_SigintAt()])
    previous = signal.getsignal(signal.SIGINT)
    result = run_cli("train", "dqn", "CartPole-v1", "--timesteps", 1000, "--out", tmp_path / "r",
                     "--n-envs", 1, "--set", "learning_starts=50",
                     "--progress", "none")  # fmt: skip
    assert result.code == 130
    assert "stopping at the next step" in result.err
    assert _status(tmp_path / "r")["num_timesteps"] == 97  # the step after the signal
    assert signal.getsignal(signal.SIGINT) is previous  # the handler was given back


def test_graceful_stop_second_ctrl_c_interrupts() -> None:
    from palaestra.cli.progress import GracefulStop

    stop = GracefulStop()
    stop._handle(signal.SIGINT, None)
    assert stop.requested and stop._on_step() is False
    with pytest.raises(KeyboardInterrupt):
        stop._handle(signal.SIGINT, None)


def test_resume_refuses_new_settings(tmp_path: Path, ppo_run: tuple[Path, Result]) -> None:
    out, _ = ppo_run
    result = run_cli("train", "--resume", out, "--set", "gamma=0.5")
    assert result.code == 2
    assert result.err.strip() == (
        "palaestra: error: --resume continues a run with its saved settings; --set cannot "
        "change them (drop them, or start a new run)"
    )
    result = run_cli("train", "dqn", "CartPole-v1", "--resume", out)
    assert result.code == 2 and "is a run of ppo, not dqn" in result.err


def test_out_folder_holding_a_run_is_not_overwritten(ppo_run: tuple[Path, Result]) -> None:
    out, _ = ppo_run
    result = run_cli("train", "ppo", "CartPole-v1", "--out", out)
    assert result.code == 2
    assert result.err.strip() == (
        f"palaestra: error: {out} already holds a run (choose another --out, or --resume {out})"
    )


def test_kill_9_then_resume_ends_as_the_uninterrupted_run(tmp_path: Path) -> None:
    import subprocess
    import sys
    import time

    args = ["dqn", "CartPole-v1", "--timesteps", 3000, "--seed", 2, "--n-envs", 2,
            "--set", "learning_starts=100", "--checkpoint-every", 300,
            "--progress", "none", "--eval-episodes", 0]  # fmt: skip
    full = tmp_path / "full"
    assert run_cli("train", *args, "--out", full).code == 0
    out = tmp_path / "killed"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(map(str, sys.path))}
    proc = subprocess.Popen(
        [sys.executable, "-m", "palaestra", "train", *map(str, args), "--out", str(out)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 60
        while not (out / "resume" / "step_900").exists():  # a few checkpoints, then kill
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.01)
        proc.kill()  # SIGKILL: nothing of palaestra's runs after this
    finally:
        proc.wait(10)
    assert _status(out)["status"] == "running"
    result = run_cli("train", "--resume", out, "--progress", "none", "--eval-episodes", 0)
    assert result.code == 0, result.err
    _assert_same_params(out / "model.zip", full / "model.zip", DQN)


def test_sac_run_folder_saves_and_resumes_its_replay_buffer(tmp_path: Path) -> None:
    """The off-policy algorithms keep their replay buffer with the run, as DQN does."""
    from palaestra.cli import main

    out = tmp_path / "sac"
    settings = ["--set", "hyperparams.learning_starts=50", "--set", "hyperparams.batch_size=16"]
    assert (
        main(
            [
                "train",
                "sac",
                "Pendulum-v1",
                "--timesteps",
                "120",
                "--seed",
                "0",
                "--out",
                str(out),
                *settings,
            ]
        )
        == 0
    )
    assert (out / "replay_buffer.zip").is_file() and (out / "model.zip").is_file()
    assert main(["train", "--resume", str(out), "--timesteps", "200"]) == 0
    from palaestra.algos import SAC

    assert SAC.load(out / "model.zip").num_timesteps == 200
