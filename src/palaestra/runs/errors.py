"""The one exception of the run API: what went wrong and how to fix it."""

from __future__ import annotations

from palaestra.error import Error

__all__ = ["RunError"]


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
