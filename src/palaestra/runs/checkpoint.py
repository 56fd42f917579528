"""A run folder's resumable state: complete checkpoints, and the newest one to resume from.

A checkpoint is a folder ``resume/step_<N>/`` with all that ``train --resume`` needs to go on
exactly where the run was:

- ``model.zip``: weights, optimizer, and the learn loop's state (current observations, a
  partial PPO rollout, DQN's open collection, generators);
- ``env_state.zip``: the native batch's rows, generators and counters, the episode and
  normalisation statistics (absent when the envs cannot save their state: then a resume
  starts new episodes and is not exact);
- ``replay_buffer.zip`` (DQN) and ``vecnormalize.npz`` (when normalising).

It is written as ``resume/.step_<N>.tmp`` and renamed once complete, so whatever stops the
process (a crash, ``kill -9``, a second Ctrl-C) leaves every earlier checkpoint whole; the
newest ``KEEP`` are kept. Each model is also linked as ``checkpoints/model_<N>_steps.zip``
(SB3's ``CheckpointCallback`` name), kept for evaluation, and the final state's files as the
run folder's ``model.zip``, ``replay_buffer.zip`` and ``vecnormalize.npz``.
"""

from __future__ import annotations

import csv
import os
import re
import shutil
from pathlib import Path
from typing import Any

from palaestra.algos.common.callbacks import BaseCallback
from palaestra.algos.common.model_io import ModelFileError, read_archive, write_archive
from palaestra.algos.common.saving import bind_env_token, env_token
from palaestra.error import RunStateError
from palaestra.runs.files import MODEL_FILE, NORMALIZE_FILE, REPLAY_ALGOS, REPLAY_FILE
from palaestra.utils.atomic_write import atomic_write, complete_text
from palaestra.vec_env import VecNormalize

__all__ = [
    "ENV_STATE_FILE",
    "KEEP",
    "RESUME_DIR",
    "CheckpointDue",
    "checkpoint_steps",
    "checkpoints",
    "latest_checkpoint",
    "load_env_state",
    "publish",
    "trim_logs",
    "write_checkpoint",
]

RESUME_DIR = "resume"
ENV_STATE_FILE = "env_state.zip"
KEEP = 2
_NAME = re.compile(r"step_(\d+)")


class CheckpointDue(BaseCallback):
    """Ends ``learn`` at the first step at or past the next multiple of ``every`` steps, so
    the checkpoint is written between two whole steps; never on the last step (which must
    still run the final update). ``every`` 0: never."""

    def __init__(self, every: int, total: int) -> None:
        super().__init__()
        self.every, self.total = every, total
        self.at: int | None = None

    def plan(self, steps: int) -> None:
        """Aim at the first multiple of ``every`` after ``steps``."""
        self.at = (steps // self.every + 1) * self.every if self.every > 0 else None

    def reached(self, steps: int) -> bool:
        """Whether ``learn`` returned because the checkpoint is due."""
        return self.at is not None and self.at <= steps < self.total

    def _on_step(self) -> bool:
        return not self.reached(self.num_timesteps)


def checkpoints(run_dir: Path) -> list[Path]:
    """The complete checkpoints of a run, oldest first."""
    folder = run_dir / RESUME_DIR
    if not folder.is_dir():
        return []
    found = [(int(m.group(1)), p) for p in folder.iterdir() if (m := _NAME.fullmatch(p.name))]
    return [p for _, p in sorted(found) if (p / MODEL_FILE).is_file()]


def checkpoint_steps(folder: Path) -> int:
    """The step count a checkpoint folder was written at."""
    match = _NAME.fullmatch(folder.name)
    if match is None:
        raise ValueError(f"{folder} is not a checkpoint folder")
    return int(match.group(1))


def latest_checkpoint(run_dir: Path) -> Path | None:
    """The newest complete checkpoint, or None (a run folder from before checkpoints)."""
    found = checkpoints(run_dir)
    return found[-1] if found else None


def write_checkpoint(model: Any, run_dir: Path, algo: str) -> tuple[Path, bool]:
    """Write the model's and its env's state as ``resume/step_<N>``; returns the folder and
    whether the env state is in it (False: the envs cannot save theirs)."""
    steps = int(model.num_timesteps)
    final = run_dir / RESUME_DIR / f"step_{steps}"
    tmp = run_dir / RESUME_DIR / f".step_{steps}.tmp"
    shutil.rmtree(tmp, ignore_errors=True)  # a leftover of a process killed while writing
    tmp.mkdir(parents=True)
    venv = model.get_env()
    model.save(tmp / MODEL_FILE)  # tags venv: env_state below carries the same token
    if algo in REPLAY_ALGOS:
        model.save_replay_buffer(tmp / REPLAY_FILE)
    if isinstance(venv, VecNormalize):
        venv.save(str(tmp / NORMALIZE_FILE))
    try:
        meta, arrays = venv.get_run_state()
        has_env = True
    except RunStateError:
        has_env = False
    if has_env:
        token = env_token(venv)
        write_archive(tmp / ENV_STATE_FILE, "env_state", {"state": meta, "token": token}, arrays)
    _sync_dir(tmp)
    if final.exists():  # the same step saved twice (a stop right after a checkpoint)
        shutil.rmtree(final)
    os.replace(tmp, final)
    _sync_dir(final.parent)
    _link(final / MODEL_FILE, run_dir / "checkpoints" / f"model_{steps}_steps.zip")
    for old in checkpoints(run_dir)[:-KEEP]:
        shutil.rmtree(old, ignore_errors=True)
    return final, has_env


def publish(folder: Path, run_dir: Path) -> None:
    """Make a checkpoint's model, replay buffer and statistics the run folder's own files."""
    for name in (MODEL_FILE, REPLAY_FILE, NORMALIZE_FILE):
        if (folder / name).is_file():
            _link(folder / name, run_dir / name)


def load_env_state(folder: Path, venv: Any) -> str | None:
    """Restore a checkpoint's env state into ``venv`` (built as the run builds it) and mark
    ``venv`` as the env its model was saved with. None when done, else why not (the resume
    then starts new episodes): no env state saved, or one that does not fit ``venv``."""
    path = folder / ENV_STATE_FILE
    if not path.is_file():
        return "the run's envs cannot save their state"
    try:
        meta, arrays = read_archive(path, "env_state")
        token = meta.get("token")
        if not isinstance(token, str):
            raise ModelFileError(f"{path}: no env token")
        venv.set_run_state((meta.get("state"), arrays))  # all or nothing
    except (ModelFileError, RunStateError) as exc:
        return f"the saved env state does not fit the env ({exc})"
    bind_env_token(venv, token)
    return None


# The logs a run appends to, and the column that says at which step a row was written.
_LOGS = (
    ("episodes.csv", "steps"),
    ("progress.csv", "time/total_timesteps"),
    ("evaluations.csv", "timesteps"),
)


def trim_logs(run_dir: Path, steps: int) -> None:
    """Drop the log rows written after step ``steps`` (by a run that went on past its last
    checkpoint and died): the resumed run writes them again, once."""
    for name, column in _LOGS:
        path = run_dir / name
        if not path.is_file():
            continue
        lines = complete_text(path).splitlines(keepends=True)
        if not lines:
            continue
        header = next(csv.reader([lines[0]]))
        if column not in header:
            continue
        at = header.index(column)
        keep = [lines[0]]
        for line in lines[1:]:
            row = next(csv.reader([line]), [])
            try:
                if int(float(row[at])) > steps:
                    continue
            except (IndexError, ValueError):  # a row without the column (SB3's sparse logs)
                pass
            keep.append(line)
        if len(keep) < len(lines):
            with atomic_write(path, "w", encoding="utf-8", newline="") as file:
                file.write("".join(keep))


def _link(source: Path, target: Path) -> None:
    """``target`` becomes ``source``'s content atomically: a hard link (no copy) where the file
    system has them, else a copy, under a temporary name then renamed."""
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    tmp.unlink(missing_ok=True)
    try:
        os.link(source, tmp)
    except OSError:
        shutil.copyfile(source, tmp)
    os.replace(tmp, target)


def _sync_dir(folder: Path) -> None:
    """Persist a folder's entries (renames, new files) where the OS allows it."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
