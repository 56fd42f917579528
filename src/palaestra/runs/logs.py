"""The files a training run appends to as it goes: ``episodes.csv`` (one row per finished
episode, behind the learning curves) and ``progress.csv`` (SB3's log table), both of which a
resumed run extends instead of overwriting."""

from __future__ import annotations

import csv
import time
from pathlib import Path
from typing import Any

import numpy as np

from palaestra.algos.common.callbacks import BaseCallback
from palaestra.algos.common.logger import CSVOutputFormat
from palaestra.utils.atomic_write import cut_torn_line, open_append

__all__ = ["EPISODE_COLUMNS", "AppendingCSV", "EpisodeLog"]

EPISODE_COLUMNS = ("steps", "return", "length", "terminated", "time_s")


class EpisodeLog(BaseCallback):
    """Append one row per finished episode to ``episodes.csv``: the env step count when it
    ended, its return and length, whether it terminated (rather than hit a time limit), and
    the run's training wall time in seconds then (``wall_before``: the seconds of earlier
    sessions of a resumed run), for learning curves against wall-clock time."""

    def __init__(self, path: Path, wall_before: float = 0.0) -> None:
        super().__init__()
        # A file written before the time column existed keeps its four columns when resumed.
        timed = True
        if path.is_file() and path.stat().st_size:
            with open(path, encoding="utf-8", newline="") as file:
                timed = "time_s" in next(csv.reader([file.readline()]), [])
        self.timed = timed
        # A new file gets its header atomically; a resumed one loses a row torn by a crash.
        self.file = open_append(path, ",".join(EPISODE_COLUMNS) + "\r\n")  # csv's line end
        self.writer = csv.writer(self.file)
        self.clock_zero = time.perf_counter() - wall_before

    def _on_step(self) -> bool:
        dones = self.locals.get("dones")
        if dones is not None and np.any(dones):
            for info, done in zip(self.locals["infos"], dones):
                episode = info.get("episode") if done else None
                if episode is not None:
                    terminated = not info.get("TimeLimit.truncated", False)
                    row: list[Any] = [self.num_timesteps, float(episode["r"])]
                    row += [int(episode["l"]), int(terminated)]
                    if self.timed:
                        row.append(round(time.perf_counter() - self.clock_zero, 3))
                    self.writer.writerow(row)
        return True

    def _on_training_end(self) -> None:
        self.file.flush()

    def close(self) -> None:
        """Flush and close the file (also after an interrupted ``learn``)."""
        self.file.close()


class AppendingCSV(CSVOutputFormat):
    """``progress.csv`` that a resumed run extends instead of overwriting (a row torn by a
    crash is cut first)."""

    def __init__(self, filename: str) -> None:
        path = Path(filename)
        if path.exists():
            cut_torn_line(path)
        if not path.exists() or path.stat().st_size == 0:
            super().__init__(filename)
            return
        self.filename = filename
        with open(filename, encoding="utf-8") as file:
            header = file.readline().strip()
        self.keys = header.split(",") if header else []
        self.file = open(filename, "a", encoding="utf-8")
