"""Stable-Baselines3's ``Monitor``: episode returns, lengths and times, optionally to a CSV file.

Same constructor, ``info["episode"]`` contents, getters and file format as
``stable_baselines3.common.monitor``, so ``load_results`` and SB3's plotting helpers read the
files either library writes. The file starts with a JSON comment line, then CSV::

    #{"t_start": 1700000000.0, "env_id": "CartPole-v1"}
    r,l,t
    21.0,21,0.004521
"""

from __future__ import annotations

import csv
import io
import json
import os
import time
from glob import glob
from typing import TYPE_CHECKING, Any, SupportsFloat

import numpy as np

from palaestra.core import ActType, Env, ObsType, Wrapper
from palaestra.error import dependency_not_installed
from palaestra.utils.atomic_write import atomic_write, open_append
from palaestra.utils.record_constructor import RecordConstructorArgs

if TYPE_CHECKING:
    import pandas

__all__ = [
    "LoadMonitorResultsError",
    "Monitor",
    "ResultsWriter",
    "get_monitor_files",
    "load_results",
    "read_monitor_file",
]

EXT = "monitor.csv"


class Monitor(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Record each episode's return ``r``, length ``l`` and time ``t`` (seconds since the
    monitor was created) into ``info["episode"]`` and, if ``filename`` is given, a CSV file.

    ``reset_keywords`` are required ``reset`` kwargs logged with the episode; ``info_keywords``
    are keys of the final step's ``info`` logged too. With ``allow_early_resets=False`` a reset
    before the episode ends raises. ``override_existing=False`` appends to an existing file.

    >>> import palaestra as gym
    >>> env = Monitor(gym.make("CartPole-v1"))
    >>> _ = env.reset(seed=0)
    >>> done = False
    >>> while not done:
    ...     _, _, terminated, truncated, info = env.step(1)
    ...     done = terminated or truncated
    >>> sorted(info["episode"]), env.get_episode_rewards(), env.get_total_steps()
    (['l', 'r', 't'], [8.0], 8)
    """

    EXT = EXT

    def __init__(
        self,
        env: Env[ObsType, ActType],
        filename: str | None = None,
        allow_early_resets: bool = True,
        reset_keywords: tuple[str, ...] = (),
        info_keywords: tuple[str, ...] = (),
        override_existing: bool = True,
    ) -> None:
        RecordConstructorArgs.__init__(
            self,
            filename=filename,
            allow_early_resets=allow_early_resets,
            reset_keywords=reset_keywords,
            info_keywords=info_keywords,
            override_existing=override_existing,
        )
        Wrapper.__init__(self, env)
        self.t_start = time.time()
        self.results_writer: ResultsWriter | None = None
        if filename is not None:
            env_id = env.spec.id if env.spec is not None else None
            self.results_writer = ResultsWriter(
                filename,
                header={"t_start": self.t_start, "env_id": str(env_id)},
                extra_keys=tuple(reset_keywords) + tuple(info_keywords),
                override_existing=override_existing,
            )
        self.reset_keywords = tuple(reset_keywords)
        self.info_keywords = tuple(info_keywords)
        self.allow_early_resets = allow_early_resets
        # Kept as a list and summed at the end, as SB3 does, so returns round identically.
        self.rewards: list[float] = []
        self.needs_reset = True
        self.episode_returns: list[float] = []
        self.episode_lengths: list[int] = []
        self.episode_times: list[float] = []
        self.total_steps = 0
        self.current_reset_info: dict[str, Any] = {}  # reset_keywords of the current episode

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None, **kwargs: Any
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env; ``kwargs`` must include every name in ``reset_keywords``."""
        if not self.allow_early_resets and not self.needs_reset:
            raise RuntimeError(
                "Tried to reset an environment before done. If you want to allow early resets, "
                "wrap your env with Monitor(env, path, allow_early_resets=True)"
            )
        self.rewards = []
        self.needs_reset = False
        given = {"seed": seed, "options": options, **kwargs}  # any of them may be logged
        for key in self.reset_keywords:
            value = given.get(key)
            if value is None:
                raise ValueError(f"Expected you to pass keyword argument {key} into reset")
            self.current_reset_info[key] = value
        if options is not None:  # SB3 forwards only what it was given: envs may lack `options`
            kwargs["options"] = options
        return self.env.reset(seed=seed, **kwargs)

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner env; at episode end add ``info["episode"]`` and write a CSV row."""
        if self.needs_reset:
            raise RuntimeError("Tried to step environment that needs reset")
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.rewards.append(float(reward))
        if terminated or truncated:
            self.needs_reset = True
            ep_rew, ep_len = sum(self.rewards), len(self.rewards)
            elapsed = time.time() - self.t_start
            ep_info: dict[str, Any] = {"r": round(ep_rew, 6), "l": ep_len, "t": round(elapsed, 6)}
            for key in self.info_keywords:
                ep_info[key] = info[key]
            self.episode_returns.append(ep_rew)
            self.episode_lengths.append(ep_len)
            self.episode_times.append(elapsed)
            ep_info.update(self.current_reset_info)
            if self.results_writer is not None:
                self.results_writer.write_row(ep_info)
            info["episode"] = ep_info
        self.total_steps += 1
        return obs, reward, terminated, truncated, info

    def close(self) -> None:
        """Close the inner env and the log file."""
        super().close()
        if self.results_writer is not None:
            self.results_writer.close()

    def get_total_steps(self) -> int:
        """Steps taken over all episodes."""
        return self.total_steps

    def get_episode_rewards(self) -> list[float]:
        """Return of every finished episode."""
        return self.episode_returns

    def get_episode_lengths(self) -> list[int]:
        """Length of every finished episode."""
        return self.episode_lengths

    def get_episode_times(self) -> list[float]:
        """Seconds from the monitor's creation to the end of every finished episode."""
        return self.episode_times


class LoadMonitorResultsError(Exception):
    """No monitor file was found where one was expected."""


class ResultsWriter:
    """Write monitor rows to ``filename`` (``monitor.csv`` is appended unless it ends so; a
    directory gets ``monitor.csv`` inside it)."""

    def __init__(
        self,
        filename: str = "",
        header: dict[str, float | str] | None = None,
        extra_keys: tuple[str, ...] = (),
        override_existing: bool = True,
    ) -> None:
        filename = os.fspath(filename)
        if not filename.endswith(EXT):
            filename = (
                os.path.join(filename, EXT) if os.path.isdir(filename) else f"{filename}.{EXT}"
            )
        filename = os.path.realpath(filename)
        os.makedirs(os.path.dirname(filename), exist_ok=True)
        fieldnames = ("r", "l", "t", *extra_keys)
        # The JSON comment and the CSV header, written atomically (as one new file), so a
        # crash never leaves a file without them; csv's own "\r\n" line ends, as SB3 writes.
        head = io.StringIO()
        head.write(f"#{json.dumps(header or {})}\n")
        csv.DictWriter(head, fieldnames=fieldnames).writeheader()
        if override_existing:
            with atomic_write(filename, "w", newline="\n") as file:
                file.write(head.getvalue())
        # newline="\n": no "\r\n" rows on Windows (SB3 issue #692). A row torn by a crash of
        # an earlier run is cut before this one appends.
        self.file_handler = open_append(filename, head.getvalue(), encoding="utf-8", newline="\n")
        self.logger = csv.DictWriter(self.file_handler, fieldnames=fieldnames)

    def write_row(self, epinfo: dict[str, Any]) -> None:
        """Append one episode and flush, so a crashed run keeps its log."""
        self.logger.writerow(epinfo)
        self.file_handler.flush()

    def close(self) -> None:
        """Close the file."""
        self.file_handler.close()


def get_monitor_files(path: str) -> list[str]:
    """The ``*monitor.csv`` files directly inside ``path``."""
    return glob(os.path.join(path, "*" + EXT))


def _monitor_text(filename: str) -> str:
    """The text of a monitor file for ``csv``: ``complete_text`` (a row torn by a crash is
    left out), but an unterminated last line is kept when it is whole: the column line
    (palaestra writes it with the comment line, atomically), or a row with a value for every
    column whose ``r``, ``l``, ``t`` parse. Files written by hand or by other tools (SB3's
    own test data) need not end with a line end; a torn row lacks fields."""
    with open(filename, encoding="utf-8", newline="") as file:
        text = file.read()
    cut = text.rfind("\n") + 1
    tail, lines = text[cut:], text[:cut].splitlines()
    if not tail or not lines:
        return text[:cut] if lines else text
    if len(lines) == 1:  # the comment, then the column line
        return text + "\n"
    columns, fields = next(csv.reader([lines[1]])), next(csv.reader([tail]))
    parse = {"r": float, "l": int, "t": float}
    try:
        whole = len(fields) == len(columns) and all(
            parse[name](value) is not None for name, value in zip(columns, fields) if name in parse
        )
    except ValueError:
        whole = False
    return text + "\n" if whole else text[:cut]


def read_monitor_file(filename: str) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Read one monitor file without pandas: ``(header, columns)``.

    ``columns`` maps each CSV column to a numpy array: ``r`` float64, ``l`` int64, ``t`` float64
    (seconds since the header's ``t_start``), extra columns as strings.
    """
    f = io.StringIO(_monitor_text(filename))  # a row torn by a crash is left out
    first = f.readline()
    if not first.startswith("#"):
        raise LoadMonitorResultsError(
            f"{filename} is not a monitor file: its first line should be '#{{json header}}', "
            f"got {first[:80]!r}"
        )
    header = json.loads(first[1:])
    reader = csv.DictReader(f)
    rows = list(reader)
    names = reader.fieldnames or ["r", "l", "t"]
    dtypes = {"r": np.float64, "l": np.int64, "t": np.float64}
    columns = {
        name: np.array([row[name] for row in rows], dtype=dtypes.get(name, str)) for name in names
    }
    return header, columns


def load_results(path: str) -> pandas.DataFrame:
    """All ``*monitor.csv`` logs in ``path`` as one pandas DataFrame sorted by time, with ``t``
    counted from the earliest ``t_start`` (SB3's function; needs pandas: ``palaestra[monitor]``)."""
    try:
        import pandas
    except ImportError as e:
        raise dependency_not_installed(
            "pandas", "monitor", "load_results; read_monitor_file works without it"
        ) from e
    files = get_monitor_files(path)
    if not files:
        raise LoadMonitorResultsError(f"No monitor files of the form *{EXT} found in {path}")
    frames, headers = [], []
    for name in files:
        f = io.StringIO(_monitor_text(name))  # a row torn by a crash is left out
        first = f.readline()
        if not first.startswith("#"):
            raise LoadMonitorResultsError(f"{name} does not start with a '#{{json}}' header line")
        header = json.loads(first[1:])
        frame = pandas.read_csv(f, index_col=None)
        headers.append(header)
        frame["t"] += header["t_start"]
        frames.append(frame)
    frames = [df for df in frames if not df.empty]
    if not frames:
        return pandas.DataFrame(columns=["r", "l", "t"]).reset_index()
    data = pandas.concat(frames).sort_values("t").reset_index()
    data["t"] -= min(h["t_start"] for h in headers)
    return data
