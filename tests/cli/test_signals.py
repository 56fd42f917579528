"""``palaestra train`` and the ways a run ends early: SIGTERM (as ``timeout``, schedulers and
``docker stop`` send it), a bad ``status.json`` at ``--resume``, ``sys.exit`` in a callback."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from palaestra.algos.callbacks import BaseCallback
from palaestra.cli import train
from palaestra.cli.progress import GracefulStop

from .conftest import Result, run_cli, wait_for_training

TINY_DQN = ("train", "dqn", "CartPole-v1", "--n-envs", 1, "--set", "learning_starts=50",
            "--set", "train_freq=4", "--set", "gradient_steps=1",
            "--progress", "none", "--eval-episodes", 0)  # fmt: skip


def _status(run: Path) -> dict[str, object]:
    return json.loads((run / "status.json").read_text())


class _SignalAt(BaseCallback):
    """Sends this process ``signum`` at step ``at``, ``times`` times in a row."""

    def __init__(self, signum: int, at: int, times: int = 1) -> None:
        super().__init__()
        self.signum, self.at, self.times = signum, at, times

    def _on_step(self) -> bool:
        if self.num_timesteps == self.at:
            for _ in range(self.times):
                os.kill(os.getpid(), self.signum)
        return True


def test_sigterm_stops_at_the_next_step_and_resume_finishes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    run = tmp_path / "run"
    previous = signal.getsignal(signal.SIGTERM)
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_SignalAt(signal.SIGTERM, 96)])
    result = run_cli(*TINY_DQN, "--timesteps", 400, "--out", run)
    assert result.code == 143
    assert "SIGTERM received: stopping at the next step" in result.err
    assert result.err.strip().splitlines()[-1] == (
        f"palaestra: interrupted at 97/400 steps; checkpoint saved in {run} "
        f"(resume with: palaestra train --resume {run})"
    )
    status = _status(run)
    assert (status["status"], status["num_timesteps"]) == ("interrupted", 97)
    assert signal.getsignal(signal.SIGTERM) is previous  # the handler was given back
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [])
    result = run_cli("train", "--resume", run, "--progress", "none", "--eval-episodes", 0)
    assert result.code == 0, result.err
    assert "from step 97 to 400 steps" in result.err
    status = _status(run)
    steps = status["num_timesteps"]  # DQN collects train_freq=4 steps at a time
    assert status["status"] == "finished" and isinstance(steps, int) and 400 <= steps < 404


def test_a_second_sigterm_stops_at_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    run = tmp_path / "run"
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_SignalAt(signal.SIGTERM, 96, times=2)])
    result = run_cli(*TINY_DQN, "--timesteps", 400, "--out", run)
    assert result.code == 143
    # The second signal came inside step 96's callbacks: learn stopped there, not one later,
    # saving nothing it was in the middle of; --resume goes on from the last checkpoint.
    assert "stopped at once at 96/400 steps" in result.err
    assert _status(run)["num_timesteps"] == 80 and _status(run)["status"] == "interrupted"


def test_graceful_stop_exit_codes_and_handlers() -> None:
    stop = GracefulStop()
    assert stop.exit_code == 130  # a KeyboardInterrupt from inside learn
    stop._handle(signal.SIGTERM, None)
    assert stop.requested and stop._on_step() is False and stop.exit_code == 143
    with pytest.raises(KeyboardInterrupt):
        stop._handle(signal.SIGINT, None)  # either signal, a second time: now
    assert stop.exit_code == 143  # the first signal decides
    before = {s: signal.getsignal(s) for s in GracefulStop.SIGNALS}
    stop = GracefulStop()
    stop.install()
    assert all(signal.getsignal(s) == stop._handle for s in GracefulStop.SIGNALS)
    stop.uninstall()
    assert {s: signal.getsignal(s) for s in GracefulStop.SIGNALS} == before


@pytest.mark.slow
def test_sigterm_to_a_train_process(tmp_path: Path) -> None:
    """The real thing: another process sends SIGTERM, as ``timeout`` or ``docker stop`` do."""
    run = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(Path(train.__file__).parents[2])}
    argv = [sys.executable, "-m", "palaestra", *map(str, TINY_DQN), "--timesteps", "10000000",
            "--out", str(run)]  # fmt: skip
    proc = subprocess.Popen(argv, stderr=subprocess.PIPE, text=True, env=env)
    assert proc.stderr is not None
    wait_for_training(proc, "training dqn on CartPole-v1")
    time.sleep(1.0)
    proc.send_signal(signal.SIGTERM)
    try:
        err = proc.stderr.read()
        code = proc.wait(timeout=60)
    finally:
        proc.kill()
    assert code == 143, err
    assert f"(resume with: palaestra train --resume {run})" in err.strip().splitlines()[-1]
    status = _status(run)
    assert status["status"] == "interrupted"
    done = status["num_timesteps"]
    assert isinstance(done, int) and 0 < done < 10_000_000
    resumed = subprocess.run(
        [sys.executable, "-m", "palaestra", "train", "--resume", str(run), "--timesteps",
         str(done + 200), "--progress", "none", "--eval-episodes", "0"],
        capture_output=True, text=True, env=env, timeout=120,
    )  # fmt: skip
    assert resumed.returncode == 0, resumed.stderr
    status = _status(run)
    steps = status["num_timesteps"]  # DQN collects train_freq=4 steps at a time
    assert status["status"] == "finished" and isinstance(steps, int)
    assert done + 200 <= steps < done + 204


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{not json", "cannot read run status '{path}': Expecting property name enclosed in "
         "double quotes: line 1 column 2 (char 1) (fix or remove the file)"),
        ('{"status": "interrupted", "num_timesteps": -5, "total_timesteps": 400, '
         '"wall_time_s": 1.0}',
         "{path}: num_timesteps must be an integer from 0 to 1000000000000000, got -5 "
         "(fix the file, or start a new run)"),
        ('{"status": "interrupted", "num_timesteps": "97", "total_timesteps": 400, '
         '"wall_time_s": 1.0}', "{path}: num_timesteps must be an integer from 0 to "),
        ('{"status": "interrupted", "num_timesteps": 97, "total_timesteps": 400, '
         '"wall_time_s": "soon"}',
         "{path}: wall_time_s must be a number of seconds >= 0, got 'soon'"),
        ('{"status": 1, "num_timesteps": 97, "total_timesteps": 400, "wall_time_s": 1}',
         "{path}: status must be a name, got 1"),
        ('{"status": "interrupted", "total_timesteps": 400, "wall_time_s": 1}',
         "{path} lacks num_timesteps (fix the file, or start a new run)"),
        ("[]", "run status '{path}' is not a JSON object (fix or remove the file)"),
    ],
)  # fmt: skip
def test_a_bad_status_file_is_found_before_training(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str, message: str
) -> None:
    run = tmp_path / "run"
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_SignalAt(signal.SIGTERM, 60)])
    assert run_cli(*TINY_DQN, "--timesteps", 400, "--out", run).code == 143
    (run / "status.json").write_text(text)

    def no_env(*args: object) -> None:
        raise AssertionError("an env was built")

    from palaestra.runs import training

    monkeypatch.setattr(training, "make_env", no_env)
    result = run_cli("train", "--resume", run, "--progress", "none")
    assert result.code == 2
    assert result.err.startswith("palaestra: error: " + message.format(path=run / "status.json"))
    assert result.err.count("\n") == 1


class _Exit(BaseCallback):
    def __init__(self, code: object) -> None:
        super().__init__()
        self.code = code

    def _on_step(self) -> bool:
        sys.exit(self.code)


@pytest.mark.parametrize(
    ("code", "exit_code", "line"),
    [
        ("disk full", 1, "stopped by sys.exit before the command finished: disk full"),
        (3, 3, "stopped by sys.exit(3) before the command finished"),
        (None, 1, "stopped by sys.exit before the command finished"),
        (0, 1, "stopped by sys.exit before the command finished"),
    ],
)
def test_sys_exit_in_a_callback_is_not_success(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, code: object, exit_code: int, line: str
) -> None:
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_Exit(code)])
    result: Result = run_cli(*TINY_DQN, "--timesteps", 100, "--out", tmp_path / "run")
    assert result.code == exit_code
    assert result.err.splitlines()[-1] == f"palaestra: error: {line}"


def test_help_and_version_still_exit_0() -> None:
    assert run_cli("--help").code == 0
    assert run_cli("--version").code == 0
    assert run_cli("train", "--help").code == 0
