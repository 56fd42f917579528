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

import json
import os
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Mapping
from typing import Any, TextIO

import numpy as np

from palaestra.error import dependency_not_installed
from palaestra.utils.atomic_write import atomic_write, complete_text

__all__ = [
    "DEBUG",
    "DISABLED",
    "ERROR",
    "INFO",
    "WARN",
    "CSVOutputFormat",
    "Figure",
    "FormatUnsupportedError",
    "HParam",
    "HumanOutputFormat",
    "Image",
    "JSONOutputFormat",
    "KVWriter",
    "Logger",
    "SeqWriter",
    "TensorBoardOutputFormat",
    "Video",
    "configure",
    "filter_excluded_keys",
    "make_output_format",
]

Exclude = str | tuple[str, ...] | None

# SB3's levels: ``Logger.log(..., level=)`` prints when ``level >= logger.level``; at
# ``DISABLED`` nothing is printed and ``dump`` writes nothing.
DEBUG = 10
INFO = 20
WARN = 30
ERROR = 40
DISABLED = 50


# -- values only TensorBoard shows (SB3's classes): record them with
# ``exclude=("stdout", "log", "json", "csv")``, the other outputs refuse them ------------------
class Video:
    """Frames ``[N, T, C, H, W]`` (a tensor) shown at ``fps`` (TensorBoard's ``add_video``)."""

    def __init__(self, frames: Any, fps: float) -> None:
        self.frames, self.fps = frames, fps


class Figure:
    """A matplotlib figure; ``close``: close it once logged."""

    def __init__(self, figure: Any, close: bool) -> None:
        self.figure, self.close = figure, close


class Image:
    """An image array or tensor with its layout (``"HWC"`` for env frames, ``"CHW"`` ...)."""

    def __init__(self, image: Any, dataformats: str) -> None:
        self.image, self.dataformats = image, dataformats


class HParam:
    """Hyperparameters and the metrics TensorBoard's HPARAMS tab shows beside them."""

    def __init__(self, hparam_dict: dict[str, Any], metric_dict: dict[str, float]) -> None:
        if not metric_dict:
            # SB3 raises a bare Exception with these words; a ValueError is still one
            raise ValueError(
                "`metric_dict` must not be empty to display hyperparameters to the HPARAMS "
                "tensorboard tab."
            )
        self.hparam_dict, self.metric_dict = hparam_dict, metric_dict


_RICH = {Video: "video", Figure: "figure", Image: "image", HParam: "hparam"}


class FormatUnsupportedError(NotImplementedError):
    """An output cannot show a recorded value (SB3's error and words)."""

    def __init__(self, unsupported_formats: list[str], value_description: str) -> None:
        if len(unsupported_formats) > 1:
            where = f"formats {', '.join(unsupported_formats)} are"
        else:
            where = f"format {unsupported_formats[0]} is"
        super().__init__(
            f"The {where} not supported for the {value_description} value logged.\n"
            "You can exclude formats via the `exclude` parameter of the logger's `record` "
            "function."
        )


def _refuse_rich(values: dict[str, Any], formats: list[str]) -> None:
    for key in sorted(values):
        kind = _RICH.get(type(values[key]))
        if kind is not None:
            raise FormatUnsupportedError(formats, kind)


Excluded = Mapping[str, "tuple[str, ...] | None"]


def _checked_excluded(key_excluded: Any) -> Excluded:
    """SB3's second argument of ``write``: the formats each key is kept out of."""
    if key_excluded is None:
        return {}
    if not isinstance(key_excluded, Mapping):
        raise TypeError(
            "write(key_values, key_excluded, step): key_excluded must map keys to the formats "
            f"they are excluded from, got {key_excluded!r}; pass the step as step=..."
        )
    return key_excluded


def _formats(excluded: Excluded, key: str) -> tuple[str, ...]:
    """The formats ``key`` is excluded from: one name given as a string is that format (SB3's
    ``("stdout")``, a string, is read so by its substring test), ``None`` is none."""
    value = excluded.get(key)
    if value is None:
        return ()
    return (value,) if isinstance(value, str) else tuple(value)


def filter_excluded_keys(
    key_values: dict[str, Any], key_excluded: Excluded | None, _format: str
) -> dict[str, Any]:
    """The values of ``key_values`` that ``_format`` writes (SB3's helper)."""
    excluded = _checked_excluded(key_excluded)
    return {k: v for k, v in key_values.items() if _format not in _formats(excluded, k)}


class KVWriter:
    """An output of key/value rows (SB3's base class, for users' own formats): ``write``
    gets every recorded value, the formats each key is excluded from, and the step."""

    def write(
        self, key_values: dict[str, Any], key_excluded: Excluded | None = None, step: int = 0
    ) -> None:
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError


class SeqWriter:
    """An output of free text lines (SB3's base class)."""

    def write_sequence(self, sequence: list[str]) -> None:
        raise NotImplementedError


class HumanOutputFormat(KVWriter, SeqWriter):
    """SB3's ASCII table: keys grouped by their ``tag/`` prefix, floats as ``%-8.3g``."""

    def __init__(self, file: TextIO | str = sys.stdout, max_length: int = 36) -> None:
        self.own = isinstance(file, str)
        self.file: TextIO = open(file, "w") if isinstance(file, str) else file
        self.max_length = max_length

    def _cut(self, text: str) -> str:
        return text if len(text) <= self.max_length else text[: self.max_length - 3] + "..."

    def write(
        self, key_values: dict[str, Any], key_excluded: Excluded | None = None, step: int = 0
    ) -> None:
        """One table of the values not excluded from ``stdout``/``log``; two keys that
        truncate to the same text are a ``ValueError``, as in SB3."""
        excluded = _checked_excluded(key_excluded)
        values = {
            k: v
            for k, v in key_values.items()
            if not {"stdout", "log"} & set(_formats(excluded, k))
        }
        _refuse_rich(values, ["stdout", "log"])
        rows: list[tuple[str, str]] = []
        seen: set[tuple[str, str]] = set()
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
            cut = self._cut(key)
            if (tag, cut) in seen:
                raise ValueError(
                    f"Key '{key}' truncated to '{cut}' that already exists. Consider "
                    "increasing `max_length`."
                )
            seen.add((tag, cut))
            rows.append((cut, self._cut(text)))
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

    def write_sequence(self, sequence: list[str]) -> None:
        """The items on one line, separated by spaces (``Logger.log``)."""
        self.file.write(" ".join(sequence) + "\n")
        self.file.flush()

    def close(self) -> None:
        if self.own:
            self.file.close()


class CSVOutputFormat(KVWriter):
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

    def write(
        self, key_values: dict[str, Any], key_excluded: Excluded | None = None, step: int = 0
    ) -> None:
        values = filter_excluded_keys(key_values, key_excluded, "csv")
        _refuse_rich(values, ["csv"])
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


class JSONOutputFormat(KVWriter):
    """``progress.json``: one JSON object per dump (numpy values as numbers or lists)."""

    def __init__(self, filename: str) -> None:
        with atomic_write(filename, "w", encoding="utf-8"):
            pass  # a fresh, empty file; rows are appended and flushed, as the CSV's
        self.file = open(filename, "a", encoding="utf-8")

    def write(
        self, key_values: dict[str, Any], key_excluded: Excluded | None = None, step: int = 0
    ) -> None:
        values = filter_excluded_keys(key_values, key_excluded, "json")
        _refuse_rich(values, ["json"])
        row = {k: _json_value(v) for k, v in values.items()}
        self.file.write(json.dumps(row) + "\n")
        self.file.flush()

    def close(self) -> None:
        self.file.close()


def _json_value(value: Any) -> Any:
    """numpy scalars and one-element arrays as numbers, other arrays as (nested) lists."""
    if hasattr(value, "dtype"):
        array = np.asarray(value)
        return float(array.item()) if array.size == 1 else array.tolist()
    return value


class TensorBoardOutputFormat(KVWriter):
    """Scalars, text, histograms (arrays, tensors) and SB3's ``Video``/``Figure``/``Image``/
    ``HParam`` values to TensorBoard through ``torch.utils.tensorboard`` (needs
    ``tensorboard``)."""

    def __init__(self, folder: str) -> None:
        try:
            from torch.utils.tensorboard import SummaryWriter
        except ImportError as exc:
            raise dependency_not_installed("tensorboard", "tensorboard", "tensorboard_log") from exc
        self.writer = SummaryWriter(log_dir=folder)

    def write(
        self, key_values: dict[str, Any], key_excluded: Excluded | None = None, step: int = 0
    ) -> None:
        """Each value not excluded from ``tensorboard`` as an event at ``step``."""
        import torch

        values = filter_excluded_keys(key_values, key_excluded, "tensorboard")
        for key in sorted(values):
            value = values[key]
            if isinstance(value, str):
                self.writer.add_text(key, value, step)
            elif isinstance(value, (int, float, np.generic)):  # SB3: bools too
                self.writer.add_scalar(key, value, step)
            elif isinstance(value, (np.ndarray, torch.Tensor)):
                self.writer.add_histogram(key, torch.as_tensor(value), step)
            elif isinstance(value, Video):
                self.writer.add_video(key, value.frames, step, value.fps)
            elif isinstance(value, Figure):
                self.writer.add_figure(key, value.figure, step, close=value.close)
            elif isinstance(value, Image):
                self.writer.add_image(key, value.image, step, dataformats=value.dataformats)
            elif isinstance(value, HParam):
                # written into this run's folder (add_hparams would open a sub-folder)
                from torch.utils.tensorboard.summary import hparams

                file_writer: Any = self.writer.file_writer
                for summary in hparams(value.hparam_dict, metric_dict=value.metric_dict):
                    file_writer.add_summary(summary)
        self.writer.flush()

    def close(self) -> None:
        self.writer.close()


OutputFormat = HumanOutputFormat | CSVOutputFormat | JSONOutputFormat | TensorBoardOutputFormat


class Logger:
    """Collects ``record``ed values and writes them to every output on ``dump``."""

    def __init__(self, folder: str | None, output_formats: list[Any]) -> None:
        self.folder = folder
        self.output_formats = output_formats
        self.level = INFO
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

    def record_mean(self, key: str, value: float | None, exclude: Exclude = None) -> None:
        """Average every value given for ``key`` until the next dump (None: ignored, as SB3)."""
        if value is None:
            return
        self._sums[key] += float(value)
        self._counts[key] += 1
        self.record(key, self._sums[key] / self._counts[key], exclude)

    def dump(self, step: int = 0) -> None:
        """Write everything recorded since the last dump, then forget it: each output gets
        all values and what each key is excluded from (SB3's ``KVWriter.write``). At level
        ``DISABLED`` nothing is written and the values are kept, as in SB3."""
        if self.level == DISABLED:
            return
        for fmt in self.output_formats:
            if hasattr(fmt, "write"):
                fmt.write(self.name_to_value, self.name_to_excluded, step)
        self.name_to_value.clear()
        self.name_to_excluded.clear()
        self._sums.clear()
        self._counts.clear()

    @property
    def dir(self) -> str | None:
        """The folder the outputs write to (SB3's attribute), None without one."""
        return self.folder

    def log(self, *args: Any, level: int = INFO) -> None:
        """Write ``args`` (as ``str``) on one line to the text outputs (stdout, ``log.txt``)
        when ``level`` is at least the logger's level."""
        if self.level <= level:
            for fmt in self.output_formats:
                if isinstance(fmt, SeqWriter):
                    fmt.write_sequence([str(arg) for arg in args])

    def debug(self, *args: Any) -> None:
        """``log`` at ``DEBUG``."""
        self.log(*args, level=DEBUG)

    def info(self, *args: Any) -> None:
        """``log`` at ``INFO``."""
        self.log(*args, level=INFO)

    def warn(self, *args: Any) -> None:
        """``log`` at ``WARN``."""
        self.log(*args, level=WARN)

    def error(self, *args: Any) -> None:
        """``log`` at ``ERROR``."""
        self.log(*args, level=ERROR)

    def set_level(self, level: int) -> None:
        """Print only ``log`` calls at ``level`` or above; ``DISABLED`` also stops ``dump``."""
        self.level = level

    def get_dir(self) -> str | None:
        return self.folder

    def close(self) -> None:
        for fmt in self.output_formats:
            fmt.close()


def make_output_format(_format: str, log_dir: str, log_suffix: str = "") -> OutputFormat:
    """One output (SB3's ``make_output_format``): ``stdout``, ``log`` (``log{suffix}.txt``),
    ``json``/``csv`` (``progress{suffix}.json``/``.csv``) or ``tensorboard``, in ``log_dir``."""
    os.makedirs(log_dir, exist_ok=True)
    if _format == "stdout":
        return HumanOutputFormat(sys.stdout)
    if _format == "log":
        return HumanOutputFormat(os.path.join(log_dir, f"log{log_suffix}.txt"))
    if _format == "json":
        return JSONOutputFormat(os.path.join(log_dir, f"progress{log_suffix}.json"))
    if _format == "csv":
        return CSVOutputFormat(os.path.join(log_dir, f"progress{log_suffix}.csv"))
    if _format == "tensorboard":
        return TensorBoardOutputFormat(log_dir)
    raise ValueError(f"Unknown format specified: {_format!r} (stdout, log, json, csv, tensorboard)")


def configure(folder: str | None = None, format_strings: list[str] | None = None) -> Logger:
    """SB3's ``configure``: outputs among ``stdout``, ``log``, ``json``, ``csv``,
    ``tensorboard`` in ``folder`` (default: a fresh temp dir)."""
    if format_strings is None:
        format_strings = ["stdout", "log", "csv"]
    if folder is None:
        folder = os.path.join(tempfile.gettempdir(), time.strftime("palaestra-%Y-%m-%d-%H-%M-%S"))
    formats = [make_output_format(name, folder) for name in filter(None, format_strings)]
    os.makedirs(folder, exist_ok=True)
    logger = Logger(folder, formats)
    names = list(filter(None, format_strings))
    if names and names != ["stdout"]:  # SB3 says where files go
        logger.log(f"Logging to {folder}")
    return logger
