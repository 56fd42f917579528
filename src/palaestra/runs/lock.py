"""One process writes a folder at a time: an exclusive lock on a run, sweep or grid folder for
the whole command that writes it.

Two ``palaestra train --out X`` (or two ``--resume X``) at once would write every log row twice
and delete each other's temporary checkpoint; the second one is refused instead, with the
holder's PID in the message. The lock is ``fcntl.flock`` on ``<folder>/.palaestra.lock``
(``msvcrt.locking`` on Windows), so the kernel releases it when its holder exits however it
ends, SIGKILL included: a lock is never stuck. The file holds the holder's PID for the message
and is removed on release; a file that still names a process but whose lock is free was left
by a process that died, and the next command takes it over with a warning.

>>> with FolderLock("runs/x"):       # doctest: +SKIP
...     ...                          # this process alone writes runs/x
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from types import TracebackType

from palaestra.runs.errors import RunError

__all__ = ["LOCK_FILE", "FolderLock"]

LOCK_FILE = ".palaestra.lock"
_PID_WAIT_S = 1.0  # a holder writes its PID right after it takes the lock
_WINDOWS_BYTE = 1 << 20  # msvcrt locks bytes; lock one past the PID text so it stays readable


def _try_lock(fd: int) -> bool:
    """Take the exclusive lock on ``fd`` without waiting; False when another holds it."""
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt

        os.lseek(fd, _WINDOWS_BYTE, os.SEEK_SET)
        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)  # type: ignore[attr-defined]
        except OSError:
            return False
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    return True


def _unlock(fd: int) -> None:
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt

        os.lseek(fd, _WINDOWS_BYTE, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)  # type: ignore[attr-defined]
        return
    fcntl.flock(fd, fcntl.LOCK_UN)


def _read_pid(fd: int) -> int | None:
    os.lseek(fd, 0, os.SEEK_SET)
    text = os.read(fd, 64).decode("ascii", "replace").strip()
    return int(text) if text.isdigit() else None


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` is still the file open as ``fd`` (its last holder may have removed it
    between our open and our lock)."""
    try:
        return os.path.samestat(os.fstat(fd), os.stat(path))
    except OSError:
        return False


class FolderLock:
    """The exclusive lock on ``folder`` (created when missing): :meth:`acquire` takes it or
    raises ``RunError`` naming the holder's PID; :meth:`release` gives it back. A context
    manager; ``what`` names the folder in messages (``"run folder"``, ``"sweep folder"``)."""

    def __init__(self, folder: str | Path, what: str = "run folder") -> None:
        self.folder, self.what = Path(folder), what
        self.path = self.folder / LOCK_FILE
        self._fd: int | None = None

    @property
    def held(self) -> bool:
        """Whether this object holds the lock now."""
        return self._fd is not None

    def acquire(self) -> FolderLock:
        """Take the lock (``RunError``, exit status 1, when another process holds it)."""
        if self._fd is not None:
            return self
        self.folder.mkdir(parents=True, exist_ok=True)
        for _ in range(20):
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            if not _try_lock(fd):
                holder = self._holder(fd)
                os.close(fd)
                who = f"process {holder}" if holder is not None else "another process"
                raise RunError(
                    f"{self.folder} is in use by {who} (another palaestra command writing "
                    f"this {self.what})",
                    "wait for it to finish, or stop it: one process writes a folder at a time",
                    code=1,
                )
            if _same_file(fd, self.path):
                break
            _unlock(fd)  # a file its last holder removed: lock the one at the path now
            os.close(fd)
        else:
            raise RunError(f"cannot lock {self.path}: it keeps being replaced", code=1)
        left = _read_pid(fd)
        if left is not None and left != os.getpid():
            print(
                f"palaestra: warning: {self.folder}: lock left by process {left}, which is no "
                "longer running; taking it over",
                file=sys.stderr,
                flush=True,
            )
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, f"{os.getpid()}\n".encode("ascii"))
        self._fd = fd
        return self

    def _holder(self, fd: int) -> int | None:
        deadline = time.monotonic() + _PID_WAIT_S
        while True:
            pid = _read_pid(fd)
            if pid is not None or time.monotonic() > deadline:
                return pid
            time.sleep(0.02)

    def release(self) -> None:
        """Give the lock back (idempotent); the lock file goes with it."""
        fd, self._fd = self._fd, None
        if fd is None:
            return
        try:
            if _same_file(fd, self.path):
                try:
                    os.unlink(self.path)  # while still held: no one can lock it in between
                except OSError:  # Windows cannot remove an open file: leave it empty
                    os.ftruncate(fd, 0)
            _unlock(fd)
        finally:
            os.close(fd)

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.release()

    def __del__(self) -> None:
        if getattr(self, "_fd", None) is not None:  # a Run opened but never trained or closed
            try:
                self.release()
            except OSError:
                pass
