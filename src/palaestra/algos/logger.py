"""Training logs in SB3's formats: the stdout table, CSV (``progress.csv``), and TensorBoard
when the ``tensorboard`` package is installed.

>>> import io
>>> out = io.StringIO()
>>> log = Logger(None, [HumanOutputFormat(out)])
>>> log.record("rollout/ep_rew_mean", -200.0); log.record("time/fps", 1234)
>>> log.dump(step=1000)
>>> print(out.getvalue(), end="")
-----------------------------
| rollout/       |          |
|    ep_rew_mean | -200     |
| time/          |          |
|    fps         | 1234     |
-----------------------------
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from collections import defaultdict
from typing import Any, TextIO

import numpy as np

from palaestra.error import dependency_not_installed
from palaestra.utils.atomic_write import atomic_write, complete_text

__all__ = ["CSVOutputFormat", "HumanOutputFormat", "Logger", "TensorBoardOutputFormat", "configure"]

Exclude = str | tuple[str, ...] | None


class HumanOutputFormat:
    """SB3's ASCII table: keys grouped by their ``tag/`` prefix, floats as ``%-8.3g``."""

    def __init__(self, file: TextIO | str = sys.stdout, max_length: int = 36) -> None:
        self.own = isinstance(file, str)
        self.file: TextIO = open(file, "w") if isinstance(file, str) else file
        self.max_length = max_length

    def _cut(self, text: str) -> str:
        return text if len(text) <= self.max_length else text[: self.max_length - 3] + "..."

    def write(self, values: dict[str, Any], step: int) -> None:
        rows: list[tuple[str, str]] = []
        tag = ""
        for key in sorted(values):
            value = values[key]
            text = f"{value:<8.3g}" if isinstance(value, float) else str(value)
            if "/" in key[1:]:
                new_tag = key[: key.index("/", 1) + 1]
                if new_tag != tag:
                    tag = new_tag
                    rows.append((self._cut(tag), ""))
                key = "   " + key[len(tag) :]
            rows.append((self._cut(key), self._cut(text)))
        if not rows:
            return
        kw = max(len(k) for k, _ in rows)
        vw = max(len(v) for _, v in rows)
        dashes = "-" * (kw + vw + 7)
        lines = [dashes, *(f"| {k:<{kw}} | {v:<{vw}} |" for k, v in rows), dashes]
        text = "\n".join(lines) + "\n"
        if self.file is sys.stdout and "tqdm" in sys.modules:
            # Keep an active progress bar intact, as SB3 does.
            sys.modules["tqdm"].tqdm.write(text, file=sys.stdout, end="")
        else:
            self.file.write(text)
        self.file.flush()

    def close(self) -> None:
        if self.own:
            self.file.close()


class CSVOutputFormat:
    """``progress.csv``: one row per dump; a new key rewrites the header (as SB3 does).

    The header and every rewrite replace the file whole (``utils.atomic_write``); rows are
    appended and flushed, so a crash leaves at worst a torn last row, which readers skip.
    """

    def __init__(self, filename: str) -> None:
        self.filename = filename
        with atomic_write(filename, "w", encoding="utf-8"):
            pass  # a fresh, empty file, as SB3's "w" mode gives
        self.file = open(filename, "a", encoding="utf-8")
        self.keys: list[str] = []

    def write(self, values: dict[str, Any], step: int) -> None:
        extra = [k for k in values if k not in self.keys]
        if extra:
            self.keys.extend(extra)
            self._rewrite(len(extra))
        cells = []
        for key in self.keys:
            value = values.get(key)
            if isinstance(value, str):
                cells.append('"' + value.replace('"', '""') + '"')
            else:
                cells.append("" if value is None else str(value))
        self.file.write(",".join(cells) + "\n")
        self.file.flush()

    def _rewrite(self, n_extra: int) -> None:
        """The new header, and the rows so far padded with empty cells for the new keys."""
        self.file.close()
        rows = complete_text(self.filename).splitlines()[1:]
        with atomic_write(self.filename, "w", encoding="utf-8") as out:
            out.write(",".join(self.keys) + "\n")
            for line in rows:
                out.write(line + "," * n_extra + "\n")
        self.file = open(self.filename, "a", encoding="utf-8")

    def close(self) -> None:
        self.file.close()


class TensorBoardOutputFormat:
    """Scalars to TensorBoard through ``torch.utils.tensorboard`` (needs ``tensorboard``)."""

    def __init__(self, folder: str) -> None:
        try:
            from torch.utils.tensorboard import SummaryWriter
        except ImportError as exc:
            raise dependency_not_installed("tensorboard", "tensorboard", "tensorboard_log") from exc
        self.writer = SummaryWriter(log_dir=folder)

    def write(self, values: dict[str, Any], step: int) -> None:
        for key, value in values.items():
            if isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
                self.writer.add_scalar(key, value, step)
        self.writer.flush()

    def close(self) -> None:
        self.writer.close()


OutputFormat = HumanOutputFormat | CSVOutputFormat | TensorBoardOutputFormat
_FORMAT_NAMES = {
    HumanOutputFormat: "stdout",
    CSVOutputFormat: "csv",
    TensorBoardOutputFormat: "tensorboard",
}


class Logger:
    """Collects ``record``ed values and writes them to every output on ``dump``."""

    def __init__(self, folder: str | None, output_formats: list[Any]) -> None:
        self.folder = folder
        self.output_formats = output_formats
        self.name_to_value: dict[str, Any] = {}
        self.name_to_excluded: dict[str, tuple[str, ...]] = {}
        self._sums: dict[str, float] = defaultdict(float)
        self._counts: dict[str, int] = defaultdict(int)

    def record(self, key: str, value: Any, exclude: Exclude = None) -> None:
        """Set ``key`` for the next dump; ``exclude`` names outputs to skip (``"csv"`` …)."""
        self.name_to_value[key] = value
        self.name_to_excluded[key] = (
            (exclude,) if isinstance(exclude, str) else tuple(exclude or ())
        )

    def record_mean(self, key: str, value: float, exclude: Exclude = None) -> None:
        """Average every value given for ``key`` until the next dump."""
        self._sums[key] += float(value)
        self._counts[key] += 1
        self.record(key, self._sums[key] / self._counts[key], exclude)

    def dump(self, step: int = 0) -> None:
        """Write everything recorded since the last dump, then forget it."""
        for fmt in self.output_formats:
            name = _FORMAT_NAMES.get(type(fmt), "")
            values = {
                k: v
                for k, v in self.name_to_value.items()
                if name not in self.name_to_excluded.get(k, ())
                and not (name == "stdout" and "log" in self.name_to_excluded.get(k, ()))
            }
            fmt.write(values, step)
        self.name_to_value.clear()
        self.name_to_excluded.clear()
        self._sums.clear()
        self._counts.clear()

    def get_dir(self) -> str | None:
        return self.folder

    def close(self) -> None:
        for fmt in self.output_formats:
            fmt.close()


def configure(folder: str | None = None, format_strings: list[str] | None = None) -> Logger:
    """SB3's ``configure``: outputs among ``stdout``, ``csv``, ``tensorboard`` (``log`` is
    ``log.txt``) in ``folder`` (default: a fresh temp dir)."""
    if format_strings is None:
        format_strings = ["stdout", "log", "csv"]
    if folder is None:
        folder = os.path.join(tempfile.gettempdir(), time.strftime("palaestra-%Y-%m-%d-%H-%M-%S"))
    os.makedirs(folder, exist_ok=True)
    formats: list[Any] = []
    for name in filter(None, format_strings):
        if name == "stdout":
            formats.append(HumanOutputFormat(sys.stdout))
        elif name == "log":
            formats.append(HumanOutputFormat(os.path.join(folder, "log.txt")))
        elif name == "csv":
            formats.append(CSVOutputFormat(os.path.join(folder, "progress.csv")))
        elif name == "tensorboard":
            formats.append(TensorBoardOutputFormat(folder))
        else:
            raise ValueError(f"Unknown format specified: {name!r} (stdout, log, csv, tensorboard)")
    return Logger(folder, formats)
