"""Files written whole or not at all: a temporary file in the same folder, moved into place.

A crash, ``kill -9`` or power cut while palaestra saves must leave the previous file (a model,
a checkpoint, ``status.json``) intact, never a truncated one. So every file is first written to
a hidden temporary file beside the target, flushed and ``fsync``'d, then renamed over the target
with ``os.replace`` (atomic on POSIX and Windows when both are in one folder), and the folder is
``fsync``'d so the rename itself survives a power cut.

Temporary names are ``.<name>.<random>.tmp``: hidden, and ending in ``.tmp``, so no palaestra
loader or glob (``model.zip``, ``*monitor.csv`` ...) ever reads one. A process killed with
``kill -9`` cannot remove its temporary file; such leftovers are harmless and may be deleted.

>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> with atomic_write(folder / "status.json", "w", encoding="utf-8") as f:
...     _ = f.write("{}")
>>> (folder / "status.json").read_text(), sorted(p.name for p in folder.iterdir())
('{}', ['status.json'])
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

__all__ = ["atomic_path", "atomic_write", "fsync_directory"]

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
) -> Iterator[IO[Any]]:
    """``open(path, mode)`` for writing (``"w"`` or ``"wb"``), but ``path`` only changes, whole,
    when the block ends without an exception."""
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_write opens files with mode 'w' or 'wb', got {mode!r}")
    with atomic_path(path) as temp, open(temp, mode, encoding=encoding, newline=newline) as file:
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
        temp = target.with_name(f".{target.name}.{secrets.token_hex(4)}{suffix}")
        try:
            os.close(os.open(temp, flags, 0o666))
        except FileExistsError:
            continue
        return temp
    raise FileExistsError(f"could not create a temporary file beside {str(target)!r}")


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDWR | getattr(os, "O_BINARY", 0))  # Windows fsyncs writable fds only
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
