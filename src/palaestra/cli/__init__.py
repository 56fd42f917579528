"""The ``palaestra`` command line: ``envs``, ``train``, ``eval``, ``record``, ``compare``,
``sweep``, ``bench``. Run ``palaestra --help`` or ``palaestra <command> --help``.

Every failure the user can fix prints one line, ``palaestra: error: <what> (<fix>)``, and
exits with 2 (bad input) or 1 (a runtime failure, e.g. a missing optional package); Ctrl-C
exits with 130 (``train`` and ``sweep``: 143 after SIGTERM). ``sys.exit`` called while a
command runs (a callback, an env wrapper) prints its message and exits non-zero: the command
did not finish.
``PALAESTRA_DEBUG=1`` shows the traceback of unexpected errors instead.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

from palaestra import __version__, error
from palaestra.cli import bench, compare, envs, evaluate, record, sweep, train
from palaestra.cli.common import CLIError
from palaestra.runs.errors import RunError

__all__ = ["build_parser", "main"]

COMMANDS = ("envs", "train", "eval", "record", "compare", "sweep", "bench")


class _Parser(argparse.ArgumentParser):
    """argparse's usage errors as one ``CLIError`` line instead of usage + message."""

    def error(self, message: str) -> NoReturn:
        raise CLIError(message, f"see {self.prog} --help")


def build_parser() -> argparse.ArgumentParser:
    """The parser of every command."""
    parser = _Parser(
        prog="palaestra",
        description="palaestra: train, evaluate, record and compare RL agents on palaestra envs.",
        epilog="Examples: palaestra envs --filter cart | palaestra train ppo CartPole-v1 | "
        "palaestra eval runs/<run> | palaestra record runs/<run> --out agent.gif | "
        "palaestra compare runs/a runs/b",
    )
    parser.add_argument("--version", action="version", version=f"palaestra {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands")
    for module in (envs, train, evaluate, record, compare, sweep, bench):
        module.add_parser(sub)
    return parser


def _report(exc: BaseException) -> int:
    """One stderr line for an exception; the exit code."""
    if isinstance(exc, RunError):  # CLIError, and the run API's errors
        line = exc.line()
        print(line if isinstance(exc, CLIError) else f"palaestra: error: {line}", file=sys.stderr)
        return exc.code
    if isinstance(exc, error.DependencyNotInstalled):
        return _report(CLIError(str(exc), code=1))
    if isinstance(exc, (error.UnregisteredEnv, error.DeprecatedEnv)):
        return _report(CLIError(str(exc), "run `palaestra envs` to list the ids"))
    if isinstance(exc, error.Error) or type(exc).__name__ == "ModelFileError":
        return _report(CLIError(str(exc), ""))
    if isinstance(exc, FileNotFoundError):
        return _report(CLIError(str(exc), "check the path"))
    return _report(
        CLIError(f"{type(exc).__name__}: {exc}", "set PALAESTRA_DEBUG=1 for the traceback", 1)
    )


def _stopped(exc: SystemExit) -> CLIError:
    """The line for ``sys.exit(code)`` raised while a command ran: the command did not finish,
    so the exit code is never 0 (``sys.exit(3)``: 3; a message or 0: 1)."""
    code = exc.code
    if isinstance(code, int) and not isinstance(code, bool) and code != 0:
        return CLIError(f"stopped by sys.exit({code}) before the command finished", "", code)
    what = "" if code is None or code == 0 else f": {code}"
    return CLIError(f"stopped by sys.exit before the command finished{what}", "", 1)


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; returns the exit code (``sys.exit(main())``)."""
    try:
        parser = build_parser()
        try:
            args: Any = parser.parse_args(argv)
        except SystemExit as exc:  # --help and --version (usage errors are CLIError)
            return exc.code if isinstance(exc.code, int) else 0
        if args.command is None:
            raise CLIError("no command given", f"choose one of {', '.join(COMMANDS)}")
        return int(args.func(args))
    except SystemExit as exc:  # sys.exit() inside the command: a callback, a user's wrapper
        return _report(_stopped(exc))
    except KeyboardInterrupt:
        print("palaestra: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `palaestra envs | head`: the reader has gone, nothing to report
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # so the exit-time flush does not fail again
        return 1
    except Exception as exc:
        if os.environ.get("PALAESTRA_DEBUG") and not isinstance(exc, CLIError):
            raise
        return _report(exc)
