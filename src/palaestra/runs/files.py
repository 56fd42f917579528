"""The files of a run folder and how they are read and written.

A run folder holds ``config.json`` (the run description as resolved), ``status.json`` (steps
done, total, wall time, the checkpoint to resume from), ``progress.csv``, ``episodes.csv``,
``model.zip``, ``replay_buffer.zip`` (off-policy algorithms), ``vecnormalize.npz`` (normalized
runs), ``resume/`` (complete checkpoints), ``learning_curve.png`` and ``tb/``; with periodic
evaluation (``train --eval-freq``) also ``evaluations.csv`` and ``best_model.zip`` (with
``best_vecnormalize.npz`` when normalized). Every file is written atomically.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import palaestra
from palaestra import error
from palaestra.envs.lookup import load_env_creator
from palaestra.runs.algorithms import REPLAY_ALGOS
from palaestra.runs.errors import RunError
from palaestra.utils.atomic_write import atomic_write

__all__ = [
    "BEST_MODEL_FILE",
    "BEST_NORMALIZE_FILE",
    "CONFIG_FILE",
    "EPISODES_FILE",
    "EVALUATIONS_FILE",
    "MODEL_FILE",
    "NORMALIZE_FILE",
    "REPLAY_ALGOS",
    "REPLAY_FILE",
    "STATUS_FILE",
    "find_config_beside",
    "is_goal_env",
    "model_file",
    "note",
    "read_json",
    "write_json",
    "write_status",
]

CONFIG_FILE = "config.json"
STATUS_FILE = "status.json"
EPISODES_FILE = "episodes.csv"
MODEL_FILE = "model.zip"
REPLAY_FILE = "replay_buffer.zip"
NORMALIZE_FILE = "vecnormalize.npz"
EVALUATIONS_FILE = "evaluations.csv"  # one row per periodic evaluation
BEST_MODEL_FILE = "best_model.zip"  # SB3's EvalCallback name: the best evaluation's model
BEST_NORMALIZE_FILE = "best_vecnormalize.npz"  # the normalization it was evaluated with


def is_goal_env(env_id: str) -> bool:
    """Whether a terminated episode of ``env_id`` counts as a success: the env class says so
    with a class attribute ``success_on_termination`` (MountainCar, Acrobot; CartPole terminates
    when the pole falls, so not CartPole). Unknown ids and bridged Gymnasium envs: False."""
    try:
        spec = palaestra.spec(env_id)
    except error.Error:
        return False
    entry = spec.entry_point
    if not isinstance(entry, str) or not entry.startswith("palaestra."):
        return False  # loading another package's entry point would import it
    creator = load_env_creator(entry)
    return bool(getattr(creator, "success_on_termination", False))


def read_json(path: Path, what: str) -> dict[str, Any]:
    """A JSON object from ``path``; ``RunError`` when it is missing or malformed."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise RunError(f"no {what} at {str(path)!r}", "check the path") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise RunError(
            f"cannot read {what} {str(path)!r}: {exc}", "fix or remove the file"
        ) from None
    if not isinstance(data, dict):
        raise RunError(f"{what} {str(path)!r} is not a JSON object", "fix or remove the file")
    return data


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Pretty JSON, written atomically: a reader, or a crash, never sees half a file."""
    with atomic_write(path, "w", encoding="utf-8") as file:
        file.write(json.dumps(data, indent=2) + "\n")


def find_config_beside(model_path: Path) -> Path | None:
    """The ``config.json`` of the run a model file belongs to (its folder, or the folder above
    for ``checkpoints/``), or None."""
    for folder in (model_path.parent, model_path.parent.parent):
        candidate = folder / CONFIG_FILE
        if candidate.is_file():
            return candidate
    return None


def model_file(path: str | Path) -> Path:
    """A model path as given: a ``.zip``, a name without ``.zip``, or a run folder."""
    p = Path(path)
    if p.is_dir():
        p = p / MODEL_FILE
    elif not p.exists() and Path(f"{path}.zip").exists():
        p = Path(f"{path}.zip")
    if not p.is_file():
        raise RunError(
            f"no model file at {str(path)!r}", "pass a model.zip or a run folder written by train"
        )
    return p


def write_status(
    run_dir: Path,
    state: str,
    steps: int,
    total: int,
    wall: float,
    checkpoint: str | None,
    error: str | None = None,
) -> None:
    """``status.json``: where the run stands and which checkpoint a resume continues; a
    ``"failed"`` run also says why (``error``)."""
    status: dict[str, Any] = {
        "status": state,
        "num_timesteps": int(steps),
        "total_timesteps": int(total),
        "wall_time_s": round(wall, 3),
        "checkpoint": checkpoint,
    }
    if error is not None:
        status["error"] = error
    write_json(run_dir / STATUS_FILE, status)


def note(text: str) -> None:
    """A note for the person running the command, on stderr: ``note: <text>``."""
    print(f"note: {text}", file=sys.stderr, flush=True)
