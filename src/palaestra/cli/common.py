"""What every command shares: the one-line error and the stderr notes."""

from __future__ import annotations

import sys
from typing import Any

from palaestra.runs.errors import RunError

__all__ = ["CLIError", "add_allow_import", "eprint"]


class CLIError(RunError):
    """A failure the user can fix: printed as ``palaestra: error: <what> (<fix>)``."""

    def line(self) -> str:
        """The single line printed on stderr."""
        return "palaestra: error: " + super().line()


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
