"""What every command shares: the one-line error and the stderr notes."""

from __future__ import annotations

import argparse
import sys
from typing import Any

import numpy as np

from palaestra.runs.errors import RunError

__all__ = [
    "CLIError",
    "add_address",
    "add_allow_import",
    "add_timesteps",
    "eprint",
    "format_duration",
]


class CLIError(RunError):
    """A failure the user can fix: printed as ``palaestra: error: <what> (<fix>)``."""

    def line(self) -> str:
        """The single line printed on stderr."""
        return "palaestra: error: " + super().line()


def format_duration(seconds: float) -> str:
    """``3725.2`` -> ``"1:02:05"``."""
    if not np.isfinite(seconds):
        return "?"
    whole = round(seconds)
    return f"{whole // 3600}:{whole % 3600 // 60:02d}:{whole % 60:02d}"


def eprint(*parts: Any) -> None:
    """Print to stderr (progress and notes; results go to stdout)."""
    print(*parts, file=sys.stderr, flush=True)


def add_allow_import(parser: Any, what: str) -> None:
    """The ``--allow-import MODULE`` option of a command that reads a run folder or a
    settings file."""
    parser.add_argument(
        "--allow-import",
        action="append",
        default=[],
        metavar="MODULE",
        help=f"let {what} import MODULE (its top-level code runs) when a run folder's "
        "config.json or a --config settings file names it: env_wrapper 'MODULE:Class', or "
        "env_id 'MODULE:Name-v0' of a run folder; repeatable. Without it those files run no "
        "code. Needed by no module given on the command line itself (ENV 'MODULE:Name-v0', "
        "--set env_wrapper=...) and by no wrapper name under palaestra (but Monitor, "
        "RecordVideo, HumanRendering, which write files or open windows) or mapped to it in "
        "palaestra.runs.known_names (docs/known_names.md).",
    )


def add_timesteps(parser: Any, metavar: str, help: str) -> None:
    """``--timesteps N``, with CleanRL's ``--total-timesteps`` and the RL Zoo's
    ``--n-timesteps`` as aliases (each its own option, so an error names the flag typed)."""
    parser.add_argument(
        "--timesteps",
        type=int,
        metavar=metavar,
        help=f"{help}; --total-timesteps (CleanRL's name) and --n-timesteps (the RL Zoo's) "
        "are the same flag",
    )
    for alias in ("--total-timesteps", "--n-timesteps"):
        parser.add_argument(alias, dest="timesteps", type=int, help=argparse.SUPPRESS)


def add_address(parser: Any) -> None:
    """The ``--address`` option of the commands that can run on Ray (``compare``, ``sweep``)."""
    parser.add_argument(
        "--address",
        metavar="ADDR",
        help="Ray cluster to run on with --backend ray: auto (the cluster this machine joined "
        "with `ray start`) or HEAD:6379; with token authentication, export RAY_AUTH_MODE=token "
        'first; ray://HOST:10001 (Ray Client) needs pip install "ray[client]" (default: a '
        "local Ray, started without the dashboard and shut down on any exit)",
    )
