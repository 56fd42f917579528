"""Two commands on one run folder: the second is refused with the first one's PID."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from tests.runs.test_lock import SRC, holder

from .conftest import run_cli, wait_for_training

TRAIN = ("train", "a2c", "CartPole-v1", "--progress", "none", "--eval-episodes", 0)


def _refused(err: str, folder: Path, pid: int) -> None:
    assert err == (
        f"palaestra: error: {folder} is in use by process {pid} (another palaestra command "
        "writing this run folder) (wait for it to finish, or stop it: one process writes a "
        "folder at a time)\n"
    )


def test_a_second_train_out_and_resume_are_refused_with_the_holders_pid(tmp_path: Path) -> None:
    run = tmp_path / "run"
    first = run_cli(*TRAIN, "--timesteps", 64, "--out", run)
    assert first.code == 0, first.err
    proc = holder(run)  # another process writing the folder
    try:
        again = run_cli(*TRAIN, "--timesteps", 64, "--out", run)
        assert again.code == 1
        _refused(again.err, run, proc.pid)
        resumed = run_cli("train", "--resume", run, "--timesteps", 128, "--progress", "none")
        assert resumed.code == 1
        _refused(resumed.err, run, proc.pid)
    finally:
        proc.kill()
        proc.wait()
    # The holder was killed: its lock is taken over with a warning, and the resume runs.
    resumed = run_cli("train", "--resume", run, "--timesteps", 128, "--progress", "none",
                      "--eval-episodes", 0)  # fmt: skip
    assert resumed.code == 0, resumed.err
    assert f"lock left by process {proc.pid}, which is no longer running" in resumed.err


def _wait_for_rows(path: Path, past: int, seconds: float = 60.0) -> None:
    """Wait until ``path`` holds episode rows (past its header) beyond its first ``past`` bytes.

    The refusals come back in well under a second, before a fresh process may have finished
    and flushed an episode; without rows from both writers the file would show nothing.
    """
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if path.is_file() and path.stat().st_size > past and path.read_bytes().count(b"\n") > 1:
            return
        time.sleep(0.05)
    raise AssertionError(f"no new episode rows in {path} after {seconds} s")


@pytest.mark.slow
def test_two_train_processes_on_one_folder(tmp_path: Path) -> None:
    """The reported case: a second ``train --out X`` and a second ``--resume X`` while a real
    ``train`` writes X; then the first resumes to the end, each log row written once."""
    run = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([SRC, os.environ.get("PYTHONPATH", "")])}

    def start(*argv: object) -> subprocess.Popen[str]:
        cmd = [sys.executable, "-m", "palaestra", *map(str, argv)]
        proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, env=env)
        wait_for_training(proc, "training a2c on CartPole-v1")
        return proc

    first = start(*TRAIN, "--timesteps", 10_000_000, "--out", run)
    try:
        second = run_cli(*TRAIN, "--timesteps", 64, "--out", run)
        assert second.code == 1
        _refused(second.err, run, first.pid)
        _wait_for_rows(run / "episodes.csv", 0)
        first.send_signal(signal.SIGTERM)
        assert first.wait(timeout=60) == 143
        resumed = start("train", "--resume", run, "--timesteps", 10_000_000, "--progress", "none")
        try:
            again = run_cli("train", "--resume", run, "--progress", "none")
            assert again.code == 1
            _refused(again.err, run, resumed.pid)
            _wait_for_rows(run / "episodes.csv", (run / "episodes.csv").stat().st_size)
        finally:
            resumed.send_signal(signal.SIGTERM)
            assert resumed.wait(timeout=60) == 143
    finally:
        first.kill()
    rows = (run / "episodes.csv").read_text().splitlines()[1:]
    steps = [int(row.split(",")[0]) for row in rows]
    assert steps and steps == sorted(steps)  # one writer: no rows written twice, interleaved
