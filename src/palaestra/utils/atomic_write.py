"""Files that survive a crash: written whole or not at all, or appended a line at a time.

A crash, ``kill -9`` or power cut while palaestra saves must leave the previous file (a model,
a checkpoint, ``status.json``) intact, never a truncated one. So every file is first written to
a hidden temporary file beside the target, flushed and ``fsync``'d, then renamed over the target
with ``os.replace`` (atomic on POSIX and Windows when both are in one folder), and the folder is
``fsync``'d so the rename itself survives a power cut.

A large file (a model of gigabytes) is written with ``write_behind=True``: each few MiB are
handed to the disk as soon as they are written and dropped from the page cache once they are
there, so the final ``fsync`` has little left to wait for and the save never holds more than a
few MiB of unwritten pages (without it, writing fills the cache first and the kernel then
throttles the writer, or the ``fsync`` waits for all of it at the end).

Temporary names are ``.<name>.<random>.tmp``: hidden, and ending in ``.tmp``, so no palaestra
loader or glob (``model.zip``, ``*monitor.csv`` ...) ever reads one. A process killed with
``kill -9`` cannot remove its temporary file; such leftovers are harmless and may be deleted.

Logs that grow a row at a time (``episodes.csv``, ``progress.csv``, ``monitor.csv``) cannot be
replaced on every row. They are created with their header atomically (``open_append``), each
row is one ``write`` of a whole line, so a crash leaves at worst a torn last line without its
``\n``: readers drop it (``complete_text``) and a resumed writer cuts it before appending.

>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> with atomic_write(folder / "status.json", "w", encoding="utf-8") as f:
...     _ = f.write("{}")
>>> (folder / "status.json").read_text(), sorted(p.name for p in folder.iterdir())
('{}', ['status.json'])
"""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any, TextIO

__all__ = [
    "atomic_path",
    "atomic_write",
    "complete_text",
    "cut_torn_line",
    "fsync_directory",
    "open_append",
]

TEMP_SUFFIX = ".tmp"


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], suffix: str = TEMP_SUFFIX) -> Iterator[Path]:
    """Yield a fresh temporary path beside ``path`` for a writer that needs a file name (ffmpeg,
    ``savefig``); when the block ends normally the file is fsync'd and replaces ``path``.

    On any exception, ``KeyboardInterrupt`` included, the temporary file is removed and
    ``path`` is left as it was. ``suffix`` ends the temporary name (``".tmp.mp4"`` for a writer
    that picks its format from the extension).
    """
    target = Path(path)
    temp = _create_temp(target, suffix)
    try:
        yield temp
        _fsync_file(temp)
        os.replace(temp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            temp.unlink()
        raise
    fsync_directory(target.parent)


@contextlib.contextmanager
def atomic_write(
    path: str | os.PathLike[str],
    mode: str = "wb",
    encoding: str | None = None,
    newline: str | None = None,
    *,
    write_behind: bool = False,
) -> Iterator[IO[Any]]:
    """``open(path, mode)`` for writing (``"w"`` or ``"wb"``), but ``path`` only changes, whole,
    when the block ends without an exception. ``write_behind=True`` (binary mode; for files
    of hundreds of MiB) hands the file to the disk as it is written (see the module
    docstring); where ``posix_fadvise`` is missing (Windows, macOS) it changes nothing."""
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_write opens files with mode 'w' or 'wb', got {mode!r}")
    if write_behind and mode != "wb":
        raise ValueError(f"atomic_write(write_behind=True) writes mode 'wb', got {mode!r}")
    with atomic_path(path) as temp:
        if write_behind and hasattr(os, "posix_fadvise"):
            opened: IO[Any] = io.BufferedWriter(_WriteBehind(temp))
        else:
            opened = open(temp, mode, encoding=encoding, newline=newline)
        with opened as file:
            yield file


def fsync_directory(folder: str | os.PathLike[str]) -> None:
    """Make a rename or a new file in ``folder`` durable (POSIX); a no-op where folders cannot
    be opened (Windows)."""
    if not hasattr(os, "O_DIRECTORY"):
        return
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:  # some file systems (network, FUSE) refuse fsync on folders
        pass
    finally:
        os.close(fd)


def _create_temp(target: Path, suffix: str) -> Path:
    """Create an empty, new file ``.<name>.<random><suffix>`` beside ``target``.

    ``os.open`` with mode 0o666 lets the umask decide the permissions, as a plain ``open``
    would (``tempfile.mkstemp`` would make every saved model 0600).
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    for _ in range(100):
        temp = target.with_name(f".{target.name}.{os.urandom(4).hex()}{suffix}")
        try:
            os.close(os.open(temp, flags, 0o666))
        except FileExistsError:
            continue
        return temp
    raise FileExistsError(f"could not create a temporary file beside {str(target)!r}")


WRITE_BEHIND_CHUNK = 8 << 20  # bytes written before they are handed to the disk


class _WriteBehind(io.FileIO):
    """A binary file that, every ``WRITE_BEHIND_CHUNK`` bytes, starts the writeback of what it
    wrote since the last time and drops the pages it handed over the time before (clean by
    now; ``POSIX_FADV_DONTNEED`` does both: it starts writing dirty pages back, without
    waiting, and evicts the clean ones). The freed pages serve the next chunk, so a file of
    any size passes through a few chunks of page cache. Writes that go back (a zip writer
    fills in a member's header after its data) are plain writes."""

    def __init__(self, path: Path) -> None:
        super().__init__(path, "w")
        self._end = 0  # the furthest offset written
        self._handed = 0  # [0, _handed) was handed to the disk
        self._dropped = 0  # [0, _dropped) was dropped from the cache
        self._advise = True
        self._pos = 0  # kept here: a tell() per write would be a system call

    def seek(self, pos: int, whence: int = os.SEEK_SET) -> int:
        self._pos = super().seek(pos, whence)
        return self._pos

    def write(self, data: Any) -> int:
        written = super().write(data)
        self._pos += written
        self._end = max(self._end, self._pos)
        if self._advise and self._end - self._handed >= WRITE_BEHIND_CHUNK:
            fd, dontneed = self.fileno(), os.POSIX_FADV_DONTNEED
            try:
                if self._handed > self._dropped:
                    os.posix_fadvise(fd, self._dropped, self._handed - self._dropped, dontneed)
                os.posix_fadvise(fd, self._handed, self._end - self._handed, dontneed)
            except OSError:  # a file system without it: the rest is written as a plain file
                self._advise = False
            self._dropped, self._handed = self._handed, self._end
        return written


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDWR | getattr(os, "O_BINARY", 0))  # Windows fsyncs writable fds only
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


# -- append-only line logs --------------------------------------------------------------------
def open_append(
    path: str | os.PathLike[str], header: str, encoding: str = "utf-8", newline: str | None = ""
) -> TextIO:
    """Open a line log for appending. A missing or empty file is first created holding
    ``header``, atomically; an existing one loses a torn last line (left by a crash mid-write),
    so the next row starts on a line of its own."""
    target = Path(path)
    if target.exists():
        cut_torn_line(target)
    if not target.exists() or target.stat().st_size == 0:
        with atomic_write(target, "w", encoding=encoding, newline=newline) as file:
            file.write(header)
    return open(target, "a", encoding=encoding, newline=newline)


def cut_torn_line(path: str | os.PathLike[str]) -> None:
    """Truncate ``path`` after its last ``\n``, dropping a partial last line if any."""
    with open(path, "rb+") as file:
        end = pos = file.seek(0, os.SEEK_END)
        keep = 0
        while pos > 0:
            step = min(1 << 16, pos)
            file.seek(pos - step)
            newline = file.read(step).rfind(b"\n")
            if newline >= 0:
                keep = pos - step + newline + 1
                break
            pos -= step
        if keep < end:
            file.truncate(keep)


def complete_text(path: str | os.PathLike[str], encoding: str = "utf-8") -> str:
    """The text of a line log up to its last ``\n``: a torn last line is left out. Line ends
    are kept as written (``\r\n`` from the csv module), for ``csv`` to read."""
    with open(path, encoding=encoding, newline="") as file:
        text = file.read()
    return text[: text.rfind("\n") + 1]
