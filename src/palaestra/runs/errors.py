"""The one exception of the run API: what went wrong and how to fix it."""

from __future__ import annotations

from palaestra.error import Error

__all__ = ["RunError", "first_line", "one_line"]


class RunError(Error, ValueError):
    """A run description, settings file or run folder that cannot be used.

    ``what`` says what is wrong (naming the value), ``fix`` how to fix it; ``code`` is the exit
    status the command line uses (2: bad input, 1: a runtime failure such as a missing package).
    """

    def __init__(self, what: str, fix: str = "", code: int = 2) -> None:
        super().__init__(what)
        self.what, self.fix, self.code = what, fix, code

    def line(self) -> str:
        """The message and its fix on one line: ``<what> (<fix>)``."""
        text = " ".join(self.what.split())  # one line, whatever the message held
        return text + (f" ({self.fix})" if self.fix else "")


def first_line(exc: BaseException) -> str:
    """The first line of an exception's message (its type when it has none): what a one-line
    error quotes of a library's multi-line message."""
    text = str(exc)
    return text.splitlines()[0] if text else type(exc).__name__


def one_line(exc: BaseException) -> str:
    """A failed run's error for a summary table: a ``RunError``'s line, else ``Type: message``,
    whitespace folded."""
    text = exc.line() if isinstance(exc, RunError) else f"{type(exc).__name__}: {exc}"
    return " ".join(text.split())
