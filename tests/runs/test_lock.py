"""One process writes a run folder at a time (:mod:`palaestra.runs.lock`), and a run that fails
says so in ``status.json``."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

import palaestra
from palaestra.algos.callbacks import BaseCallback
from palaestra.runs import RunError, RunSpec, open_resume, open_run, train_run
from palaestra.runs.lock import LOCK_FILE, FolderLock

SRC = str(Path(palaestra.__file__).parents[1])
HOLD = (
    "import sys; from palaestra.runs.lock import FolderLock; "
    "lock = FolderLock(sys.argv[1]).acquire(); print('locked', flush=True); sys.stdin.read()"
)


def holder(folder: Path) -> subprocess.Popen[str]:
    """Another process that holds ``folder``'s lock until its stdin closes (or it is killed)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([SRC, os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(folder)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert proc.stdout is not None and proc.stdout.readline() == "locked\n"
    return proc


@pytest.fixture
def held(tmp_path: Path) -> Iterator[tuple[Path, int]]:
    """A folder whose lock another live process holds, and that process's PID."""
    folder = tmp_path / "run"
    proc = holder(folder)
    try:
        yield folder, proc.pid
    finally:
        proc.kill()
        proc.wait()


def tiny(seed: int = 0, steps: int = 64) -> RunSpec:
    return RunSpec.from_preset("a2c", "CartPole-v1", seed=seed, n_timesteps=steps)


def test_a_lock_is_exclusive_names_its_holder_and_leaves_no_file(tmp_path: Path) -> None:
    folder = tmp_path / "new" / "run"
    with FolderLock(folder) as lock:  # the folder is created
        assert lock.held and (folder / LOCK_FILE).read_text() == f"{os.getpid()}\n"
        with pytest.raises(RunError) as info:
            FolderLock(folder).acquire()  # a second holder, even in this process
        assert info.value.line() == (
            f"{folder} is in use by process {os.getpid()} (another palaestra command writing "
            "this run folder) (wait for it to finish, or stop it: one process writes a folder "
            "at a time)"
        )
        assert info.value.code == 1
    assert not lock.held and not (folder / LOCK_FILE).exists()
    lock.release()  # idempotent
    with FolderLock(folder):  # free again
        pass


def test_another_process_holding_the_folder_refuses_train_and_resume(
    held: tuple[Path, int], capsys: pytest.CaptureFixture[str]
) -> None:
    folder, pid = held
    with pytest.raises(RunError, match=f"^{folder} is in use by process {pid} "):
        open_run(tiny(), folder)
    assert os.listdir(folder) == [LOCK_FILE]  # nothing written beside the holder's lock
    with pytest.raises(RunError, match=f"is in use by process {pid} "):
        train_run(tiny(), folder)
    with pytest.raises(RunError, match=f"is in use by process {pid} "):
        open_resume(folder)
    assert "warning" not in capsys.readouterr().err


def test_a_lock_left_by_a_killed_process_is_taken_over_with_a_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "run"
    proc = holder(folder)
    proc.send_signal(signal.SIGKILL)  # no chance to clean up: the file keeps its PID
    proc.wait()
    assert (folder / LOCK_FILE).read_text() == f"{proc.pid}\n"
    result = train_run(tiny(), folder, checkpoint_every=0)
    assert result.status == "finished"
    assert capsys.readouterr().err == (
        f"palaestra: warning: {folder}: lock left by process {proc.pid}, which is no longer "
        "running; taking it over\n"
    )
    assert not (folder / LOCK_FILE).exists()


def test_a_run_holds_its_folder_until_it_is_trained_or_closed(tmp_path: Path) -> None:
    run = open_run(tiny(), tmp_path / "run")
    with pytest.raises(RunError, match=f"in use by process {os.getpid()}"):
        open_run(tiny(), tmp_path / "run")
    run.train(checkpoint_every=0)
    with pytest.raises(RunError, match="already holds a run"):  # free, and complete
        open_run(tiny(), tmp_path / "run")
    with open_resume(tmp_path / "run", n_timesteps=128):
        with pytest.raises(RunError, match="in use by process"):
            open_resume(tmp_path / "run", n_timesteps=128)
    open_resume(tmp_path / "run", n_timesteps=128).close()  # the with block released it


def test_bad_settings_release_the_lock_and_leave_no_folder(tmp_path: Path) -> None:
    spec = RunSpec.from_preset("a2c", "CartPole-v1", seed=0, n_timesteps=64)
    spec.hyperparams["no_such_setting"] = 1
    with pytest.raises(RunError, match="invalid a2c settings"):
        open_run(spec, tmp_path / "run")
    assert not (tmp_path / "run").exists()


class _DiskFull(BaseCallback):
    def _on_step(self) -> bool:
        if self.num_timesteps >= 40:
            raise OSError(28, "No space left on device")
        return True


def test_a_run_that_fails_says_so_in_its_status(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    with pytest.raises(OSError, match="No space left"):
        train_run(tiny(steps=200), folder, callbacks=[_DiskFull()], checkpoint_every=20)
    status = json.loads((folder / "status.json").read_text())
    assert status["status"] == "failed"
    assert status["error"] == "OSError: [Errno 28] No space left on device"
    # A2C's preset steps 4 envs at a time: the checkpoint due at 20 is taken at 24.
    assert status["num_timesteps"] == 24 and status["checkpoint"] == "resume/step_24"
    with FolderLock(folder):  # released on the way out
        pass
    result = open_resume(folder).train(checkpoint_every=0)  # a failed run resumes
    assert result.status == "finished" and result.num_timesteps >= 200


def test_a_disk_full_at_the_final_save_leaves_a_failed_status(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from palaestra.runs import checkpoint

    def full(*args: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(checkpoint, "write_checkpoint", full)
    with pytest.raises(OSError):
        train_run(tiny(), tmp_path / "run", checkpoint_every=0)
    status = json.loads((tmp_path / "run" / "status.json").read_text())
    assert (status["status"], status["num_timesteps"], status["checkpoint"]) == ("failed", 0, None)
    assert status["error"] == "OSError: [Errno 28] No space left on device"


def test_the_lock_module_imports_without_fcntl() -> None:
    """Windows has no fcntl: the module must import there (it locks with msvcrt)."""
    code = "import sys; sys.modules['fcntl'] = None; import palaestra.runs.lock, palaestra.runs"
    env = {**os.environ, "PYTHONPATH": SRC}
    subprocess.run([sys.executable, "-c", code], check=True, env=env, timeout=60)


def test_an_eval_env_that_fails_to_build_releases_the_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from palaestra.runs import periodic_eval

    def broken(*args: object) -> None:
        raise RuntimeError("the eval env cannot be built")

    monkeypatch.setattr(periodic_eval, "make_eval_env", broken)
    folder = tmp_path / "run"
    with pytest.raises(RuntimeError, match="cannot be built"):
        train_run(tiny(steps=200), folder, eval_freq=40, eval_episodes=1)
    status = json.loads((folder / "status.json").read_text())
    assert status["status"] == "failed"
    assert status["error"] == "RuntimeError: the eval env cannot be built"
    with FolderLock(folder):  # released on the way out, not held until the process ends
        pass
