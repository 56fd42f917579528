"""Plot monitor logs as SB3's ``stable_baselines3.common.results_plotter`` does.

``plot_results(dirs, num_timesteps, x_axis, task_name)`` reads every ``*monitor.csv`` in each
folder, merges them by time and draws each episode's return (points) and its 100-episode mean
(line) against timesteps, episodes or wall-clock hours. Unlike SB3 it needs no pandas: the logs
are read with :func:`palaestra.wrappers.monitor.read_monitor_file`, and ``ts2xy`` takes either a
pandas ``DataFrame`` (from ``load_results``) or that dict of columns. Needs matplotlib.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from palaestra.wrappers.monitor import (
    LoadMonitorResultsError,
    get_monitor_files,
    read_monitor_file,
)

__all__ = [
    "EPISODES_WINDOW",
    "POSSIBLE_X_AXES",
    "X_EPISODES",
    "X_TIMESTEPS",
    "X_WALLTIME",
    "load_columns",
    "plot_curves",
    "plot_results",
    "rolling_window",
    "ts2xy",
    "window_func",
]

X_TIMESTEPS = "timesteps"
X_EPISODES = "episodes"
X_WALLTIME = "walltime_hrs"
POSSIBLE_X_AXES = [X_TIMESTEPS, X_EPISODES, X_WALLTIME]
EPISODES_WINDOW = 100


def rolling_window(array: np.ndarray, window: int) -> np.ndarray:
    """A read-only view of ``array``'s last axis as overlapping windows of ``window`` items.

    >>> rolling_window(np.arange(5), 3).tolist()
    [[0, 1, 2], [1, 2, 3], [2, 3, 4]]
    """
    return np.lib.stride_tricks.sliding_window_view(array, window, axis=-1)


def window_func(
    var_1: np.ndarray, var_2: np.ndarray, window: int, func: Callable[..., np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """``func`` over each ``window`` of ``var_2``, paired with ``var_1`` at each window's end.

    >>> x, y = window_func(np.arange(4), np.array([1.0, 3.0, 5.0, 7.0]), 2, np.mean)
    >>> x.tolist(), y.tolist()
    ([1, 2, 3], [2.0, 4.0, 6.0])
    """
    return var_1[window - 1 :], func(rolling_window(var_2, window), axis=-1)


def _column(data: Any, name: str) -> np.ndarray:
    return np.asarray(data[name])


def ts2xy(data_frame: Any, x_axis: str) -> tuple[np.ndarray, np.ndarray]:
    """``(x, episode returns)``: x is cumulative timesteps, the episode index or hours.

    ``data_frame`` is ``load_results``' DataFrame or :func:`load_columns`' dict.
    """
    returns = _column(data_frame, "r")
    if x_axis == X_TIMESTEPS:
        return np.cumsum(_column(data_frame, "l")), returns
    if x_axis == X_EPISODES:
        return np.arange(len(returns)), returns
    if x_axis == X_WALLTIME:
        return _column(data_frame, "t") / 3600.0, returns
    raise NotImplementedError(f"Unsupported {x_axis=}, please use one of {POSSIBLE_X_AXES}")


def load_columns(path: str) -> dict[str, np.ndarray]:
    """Every monitor log in ``path`` merged as ``load_results`` merges them (sorted by end
    time, ``t`` counted from the earliest ``t_start``), as a dict of arrays; no pandas."""
    files = get_monitor_files(path)
    if not files:
        raise LoadMonitorResultsError(f"No monitor files of the form *monitor.csv found in {path}")
    parts, starts = [], []
    for name in files:
        header, columns = read_monitor_file(name)
        starts.append(float(header["t_start"]))
        parts.append((float(header["t_start"]), columns))
    origin = min(starts)
    merged = {key: np.concatenate([cols[key] for _, cols in parts]) for key in ("r", "l", "t")}
    merged["t"] = merged["t"] + np.concatenate(
        [np.full(len(cols["t"]), start) for start, cols in parts]
    )
    order = np.argsort(merged["t"], kind="stable")
    out = {key: value[order] for key, value in merged.items()}
    out["t"] = out["t"] - origin
    return out


def plot_curves(
    xy_list: list[tuple[np.ndarray, np.ndarray]],
    x_axis: str,
    title: str,
    figsize: tuple[int, int] = (8, 2),
) -> Any:
    """One figure: each curve's points and, past ``EPISODES_WINDOW`` episodes, its running
    mean. Returns the matplotlib figure."""
    from matplotlib import pyplot as plt

    figure = plt.figure(title, figsize=figsize)
    max_x = max(x[-1] for x, _ in xy_list if len(x))
    for x, y in xy_list:
        plt.scatter(x, y, s=2)
        if x.shape[0] >= EPISODES_WINDOW:
            plt.plot(*window_func(x, y, EPISODES_WINDOW, np.mean))
    plt.xlim(0, max_x)
    plt.title(title)
    plt.xlabel(x_axis)
    plt.ylabel("Episode Rewards")
    plt.tight_layout()
    return figure


def plot_results(
    dirs: list[str],
    num_timesteps: int | None,
    x_axis: str,
    task_name: str,
    figsize: tuple[int, int] = (8, 2),
) -> Any:
    """Plot the monitor logs of each folder in ``dirs`` (episodes up to ``num_timesteps``
    cumulative steps when given). Returns the matplotlib figure."""
    xy_list = []
    for folder in dirs:
        data: Mapping[str, np.ndarray] = load_columns(folder)
        if num_timesteps is not None:
            keep = np.cumsum(data["l"]) <= num_timesteps
            data = {key: value[keep] for key, value in data.items()}
        xy_list.append(ts2xy(data, x_axis))
    return plot_curves(xy_list, x_axis, task_name, figsize)
