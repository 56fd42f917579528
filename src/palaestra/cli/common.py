"""What every command shares: the one-line error, run-folder files, goal envs, value parsing."""

from __future__ import annotations

import ast
import json
import sys
from pathlib import Path
from typing import Any

from palaestra.utils.atomic_write import atomic_write

__all__ = [
    "CONFIG_FILE",
    "EPISODES_FILE",
    "GOAL_ENVS",
    "MODEL_FILE",
    "STATUS_FILE",
    "CLIError",
    "find_run_config",
    "is_goal_env",
    "parse_value",
    "read_json",
    "write_json",
]

CONFIG_FILE = "config.json"
STATUS_FILE = "status.json"
EPISODES_FILE = "episodes.csv"
MODEL_FILE = "model.zip"
REPLAY_FILE = "replay_buffer.zip"
# Off-policy algorithms: their replay buffer is saved with each checkpoint and the final model.
REPLAY_ALGOS = ("dqn", "sac", "td3", "ddpg")
NORMALIZE_FILE = "vecnormalize.npz"

# Envs whose episodes end by termination only when the agent reaches the goal, so
# "terminated" means "succeeded" (CartPole terminates when the pole falls: not a goal env).
GOAL_ENVS = frozenset({"MountainCar-v0", "MountainCarContinuous-v0", "Acrobot-v1"})


class CLIError(Exception):
    """A failure the user can fix: printed as ``palaestra: error: <what> (<fix>)``."""

    def __init__(self, what: str, fix: str = "", code: int = 2) -> None:
        super().__init__(what)
        self.what, self.fix, self.code = what, fix, code

    def line(self) -> str:
        """The single line printed on stderr."""
        text = " ".join(self.what.split())  # one line, whatever the message held
        return f"palaestra: error: {text}" + (f" ({self.fix})" if self.fix else "")


def is_goal_env(env_id: str) -> bool:
    """Whether a terminated episode of ``env_id`` counts as a success."""
    return env_id in GOAL_ENVS


def parse_value(text: str) -> Any:
    """``--set`` values: JSON, else a Python literal, else the text itself.

    >>> parse_value("[128, 128]"), parse_value("True"), parse_value("1e-3"), parse_value("relu")
    ([128, 128], True, 0.001, 'relu')
    """
    try:
        return json.loads(text)
    except ValueError:
        pass
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        return text


def read_json(path: Path, what: str) -> dict[str, Any]:
    """A JSON object from ``path``; ``CLIError`` when it is missing or malformed."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise CLIError(f"no {what} at {str(path)!r}", "check the path") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise CLIError(
            f"cannot read {what} {str(path)!r}: {exc}", "fix or remove the file"
        ) from None
    if not isinstance(data, dict):
        raise CLIError(f"{what} {str(path)!r} is not a JSON object", "fix or remove the file")
    return data


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Pretty JSON, written atomically: a reader, or a crash, never sees half a file."""
    with atomic_write(path, "w", encoding="utf-8") as file:
        file.write(json.dumps(data, indent=2) + "\n")


def find_run_config(model_path: Path) -> dict[str, Any] | None:
    """The ``config.json`` of the run a model file belongs to (its folder, or the folder above
    for ``checkpoints/``), or None."""
    for folder in (model_path.parent, model_path.parent.parent):
        candidate = folder / CONFIG_FILE
        if candidate.is_file():
            return read_json(candidate, "run config")
    return None


def model_file(path: str) -> Path:
    """A model path as given: a ``.zip``, a name without ``.zip``, or a run folder."""
    p = Path(path)
    if p.is_dir():
        p = p / MODEL_FILE
    elif not p.exists() and Path(path + ".zip").exists():
        p = Path(path + ".zip")
    if not p.is_file():
        raise CLIError(
            f"no model file at {path!r}", "pass a model.zip or a run folder written by train"
        )
    return p


def eprint(*parts: Any) -> None:
    """Print to stderr (progress and notes; results go to stdout)."""
    print(*parts, file=sys.stderr, flush=True)
