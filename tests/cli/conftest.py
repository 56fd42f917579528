"""Run ``palaestra`` commands in-process and share two tiny trained runs between the tests."""

from __future__ import annotations

import contextlib
import io
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import pytest

from palaestra.cli import main


class Result(NamedTuple):
    code: int
    out: str
    err: str


def run_cli(*argv: object) -> Result:
    """``palaestra *argv`` in this process: exit code, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return Result(code, out.getvalue(), err.getvalue())


def wait_for_file(path: Path, timeout: float = 60.0) -> Path:
    """``path`` once it exists: ``train`` draws its learning curve in a background process,
    which writes it whole (atomically) a moment after the command returns."""
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert time.monotonic() < deadline, f"{path} not written within {timeout} s"
        time.sleep(0.05)
    return path


def wait_for_training(proc: subprocess.Popen[str], announcement: str) -> str:
    """Read ``proc``'s stderr up to the line that starts with ``announcement`` ("training dqn
    on CartPole-v1", printed once ``learn`` starts); before it only ``note:`` lines (a preset's
    recorded shortfall) may come. The lines read, for the failure message."""
    assert proc.stderr is not None
    lines: list[str] = []
    while line := proc.stderr.readline():
        lines.append(line)
        if line.startswith(announcement):
            return "".join(lines)
        assert line.startswith("note: ") or not line.strip(), "".join(lines)
    raise AssertionError(f"stderr ended before {announcement!r}:\n{''.join(lines)}")


@pytest.fixture
def cli() -> Callable[..., Result]:
    return run_cli


@pytest.fixture(scope="session")
def ppo_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Result]:
    """The brief's tiny PPO run: the CartPole-v1 default preset (8 envs) for 512 steps."""
    import torch

    torch.set_num_threads(1)
    out = tmp_path_factory.mktemp("runs") / "ppo"
    result = run_cli("train", "ppo", "CartPole-v1", "--timesteps", 512, "--seed", 0,
                     "--out", out, "--progress", "line")  # fmt: skip
    assert result.code == 0, result.err
    return out, result


@pytest.fixture(scope="session")
def dqn_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Result]:
    """The brief's tiny DQN run: MountainCar-v0's preset for 300 steps, learning from step 100."""
    out = tmp_path_factory.mktemp("runs") / "dqn"
    result = run_cli("train", "dqn", "MountainCar-v0", "--timesteps", 300, "--seed", 1,
                     "--set", "learning_starts=100", "--out", out,
                     "--progress", "none")  # fmt: skip
    assert result.code == 0, result.err
    return out, result
