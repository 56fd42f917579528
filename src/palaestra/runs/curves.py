"""Episode returns of a run and the learning-curve plots of ``train`` and ``compare``.

``train``'s ``learning_curve.png`` is drawn off the training path. Importing matplotlib costs
1-2 s (more than a short run), so unless ``matplotlib.pyplot`` is already loaded in this process
(a notebook, a test session: drawing then costs ~0.2 s and is done in place),
``draw_learning_curve`` starts a detached process that reads the finished run's ``episodes.csv``,
draws the PNG and exits; the command does not wait for it, and the summary lists the file as
``learning_curve.png (drawing)``. The drawing process runs in its own session (a Ctrl-C or the
closing terminal does not reach it) at a lower priority, isolated (``python -I``: no
``PYTHON*`` variables, user site or current folder) but importing palaestra and matplotlib from
this process's ``sys.path`` exactly, so it runs no code this process would not. Every plot is
written atomically (a temporary file beside it, then ``os.replace``): a reader sees the previous
PNG, or none, until the new one is whole; a failed drawing only means no new PNG (a killed one
may leave its hidden ``.learning_curve.png.PID.tmp``).

A run evaluated during training (``train --eval-freq``) shows its ``evaluations.csv`` beside
the training returns.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import math
import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from palaestra.error import dependency_not_installed
from palaestra.runs.errors import RunError
from palaestra.runs.files import EPISODES_FILE, EVALUATIONS_FILE
from palaestra.utils.atomic_write import atomic_write, complete_text

__all__ = [
    "LEARNING_CURVE_FILE",
    "Episodes",
    "Evaluations",
    "draw_learning_curve",
    "plot_compare",
    "plot_learning_curve",
    "read_episodes",
    "read_evaluations",
    "rolling_mean",
    "save_figure",
]

LEARNING_CURVE_FILE = "learning_curve.png"


class Episodes(NamedTuple):
    """Finished episodes of one run, in order; ``terminated`` and ``times`` are None when
    unknown."""

    steps: np.ndarray  # [E] env steps when the episode ended
    returns: np.ndarray  # [E] float
    lengths: np.ndarray  # [E] int
    terminated: np.ndarray | None  # [E] bool
    times: np.ndarray | None = None  # [E] seconds of training when the episode ended


def _read_csv(path: Path) -> list[dict[str, str]]:
    """The rows of a CSV log, without ``#`` comment lines or a row torn by a crash."""
    text = complete_text(path)
    return list(csv.DictReader(line for line in text.splitlines() if not line.startswith("#")))


def _floats(rows: list[dict[str, str]], key: str) -> np.ndarray:
    return np.array([float(r[key]) if r.get(key) not in (None, "") else np.nan for r in rows])


def read_episodes(run: Path) -> Episodes:
    """From ``episodes.csv`` (written by ``train``), else SB3-style ``*monitor.csv`` files,
    else ``progress.csv``'s ``rollout/ep_rew_mean`` (already a rolling mean)."""
    try:
        if (run / EPISODES_FILE).is_file():
            rows = _read_csv(run / EPISODES_FILE)
            times = _floats(rows, "time_s") if rows and "time_s" in rows[0] else None
            return Episodes(
                _floats(rows, "steps").astype(np.int64),
                _floats(rows, "return"),
                _floats(rows, "length").astype(np.int64),
                _floats(rows, "terminated").astype(bool),
                times,
            )
        monitors = sorted(run.glob("*monitor.csv"))
        if monitors:
            rows = _read_csv(monitors[0])  # one env's file: its lengths add up to its steps
            lengths = _floats(rows, "l").astype(np.int64)
            times = _floats(rows, "t") if rows and "t" in rows[0] else None  # since its start
            return Episodes(np.cumsum(lengths), _floats(rows, "r"), lengths, None, times)
        if (run / "progress.csv").is_file():
            rows = [r for r in _read_csv(run / "progress.csv") if r.get("rollout/ep_rew_mean")]
            returns = _floats(rows, "rollout/ep_rew_mean")
            steps = _floats(rows, "time/total_timesteps").astype(np.int64)
            lengths = np.nan_to_num(_floats(rows, "rollout/ep_len_mean")).astype(np.int64)
            times = _floats(rows, "time/time_elapsed") if "time/time_elapsed" in rows[0] else None
            return Episodes(steps, returns, lengths, None, times)
    except (OSError, KeyError, ValueError) as exc:
        raise RunError(f"cannot read the episodes of run {str(run)!r}: {exc}", "") from None
    raise RunError(
        f"run {str(run)!r} has no episodes.csv, monitor.csv or progress.csv",
        "pass folders written by palaestra train",
    )


class Evaluations(NamedTuple):
    """The periodic evaluations of one run (``evaluations.csv``), in order."""

    steps: np.ndarray  # [V] env steps when evaluated
    mean: np.ndarray  # [V] mean return of the episodes
    std: np.ndarray  # [V]
    episodes: np.ndarray  # [V] int, episodes per evaluation


def read_evaluations(run: Path) -> Evaluations | None:
    """``evaluations.csv`` (written by ``train --eval-freq``), or None when the run has none."""
    path = run / EVALUATIONS_FILE
    if not path.is_file():
        return None
    try:
        rows = _read_csv(path)
        return Evaluations(
            _floats(rows, "timesteps").astype(np.int64),
            _floats(rows, "mean_return"),
            _floats(rows, "std_return"),
            np.array([len(r["returns"].split()) for r in rows], dtype=np.int64),
        )
    except (OSError, KeyError, ValueError, AttributeError) as exc:
        raise RunError(f"cannot read {str(path)!r}: {exc}", "fix or remove the file") from None


def evaluation_label(evaluations: Evaluations) -> str:
    """The legend of the evaluation series.

    >>> evaluation_label(Evaluations(*[np.array([5, 5])] * 4))
    'evaluation: mean of 5 deterministic episodes'
    """
    low, high = int(evaluations.episodes.min()), int(evaluations.episodes.max())
    count = f"{low}" if low == high else f"{low}-{high}"
    return f"evaluation: mean of {count} deterministic episode{'s' * (high != 1)}"


def rolling_mean(values: np.ndarray, window: int) -> np.ndarray:
    """Mean of the last ``window`` values at each index (fewer at the start).

    >>> rolling_mean(np.array([1.0, 2.0, 3.0, 4.0]), 2).tolist()
    [1.0, 1.5, 2.5, 3.5]
    """
    values = np.asarray(values, dtype=np.float64)
    sums = np.cumsum(np.concatenate([[0.0], values]))
    idx = np.arange(1, len(values) + 1)
    start = np.maximum(idx - window, 0)
    return (sums[idx] - sums[start]) / (idx - start)


def default_window(n_episodes: int) -> int:
    """Smoothing window: about a twentieth of the episodes, between 1 and 100."""
    return int(min(100, max(1, n_episodes // 20)))


def _no_matplotlib() -> Exception:
    return dependency_not_installed("matplotlib", "render", "learning-curve plots")


def _pyplot() -> Any:
    try:
        import matplotlib
    except ImportError:
        raise _no_matplotlib() from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_learning_curve(
    episodes: Episodes, path: Path, title: str, evaluations: Evaluations | None = None
) -> None:
    """Episode returns against env steps, with their rolling mean; with ``evaluations``, the
    mean return of each evaluation during training, as markers on a line."""
    plt = _pyplot()
    window = default_window(len(episodes.returns))
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(episodes.steps, episodes.returns, ".", ms=2, alpha=0.3, label="episode return")
    if len(episodes.returns):
        smooth = rolling_mean(episodes.returns, window)
        ax.plot(episodes.steps, smooth, lw=2, label=f"mean of last {window}")
    if evaluations is not None and len(evaluations.mean):
        ax.plot(
            evaluations.steps,
            evaluations.mean,
            "o-",
            ms=5,
            lw=1,
            color="tab:red",
            label=evaluation_label(evaluations),
        )
    ax.set(xlabel="env steps", ylabel="return", title=title)
    ax.legend(loc="best")
    fig.tight_layout()
    save_figure(fig, path)


# The drawing process: this process's sys.path, then draw_main on the remaining arguments.
_CHILD_CODE = (
    "import json, sys; sys.path[:] = json.loads(sys.argv[1]); "
    "from palaestra.runs.curves import draw_main; sys.exit(draw_main(sys.argv[2:]))"
)


def draw_learning_curve(
    run: Path, title: str, background: bool | None = None
) -> subprocess.Popen[bytes] | None:
    """Draw ``run/learning_curve.png`` from the run's episodes and evaluations: in a detached
    process when ``background`` (by default, unless pyplot is already imported here: see the
    module docstring), which is returned (the file appears when whole; exit code 0 when written);
    else in this process, returning None. ``DependencyNotInstalled`` when matplotlib is
    missing (checked without importing it)."""
    if background is None:
        background = "matplotlib.pyplot" not in sys.modules
    if not background:
        plot_learning_curve(
            read_episodes(run), run / LEARNING_CURVE_FILE, title, read_evaluations(run)
        )
        return None
    if importlib.util.find_spec("matplotlib") is None:
        raise _no_matplotlib()
    argv = [sys.executable, "-I", "-c", _CHILD_CODE, json.dumps(sys.path), str(run.absolute())]
    detach: dict[str, Any] = {"start_new_session": True}
    if sys.platform == "win32":
        detach = {
            "creationflags": subprocess.DETACHED_PROCESS | subprocess.CREATE_NEW_PROCESS_GROUP
        }
    io = subprocess.DEVNULL
    proc = subprocess.Popen([*argv, title], stdin=io, stdout=io, stderr=io, **detach)
    # Reaped by a daemon thread: no zombie while this process lives on (a notebook), and no
    # wait at exit (daemon threads are left behind, and the handle with them: no warning).
    threading.Thread(target=proc.wait, name="palaestra-learning-curve", daemon=True).start()
    return proc


def draw_main(argv: list[str]) -> int:
    """The drawing process: ``RUN TITLE`` -> ``RUN/learning_curve.png``; 0 when written."""
    if hasattr(os, "nice"):  # leave the CPU to the foreground: 2 cores are often all there is
        os.nice(10)
    run, title = Path(argv[0]), argv[1]
    plot_learning_curve(read_episodes(run), run / LEARNING_CURVE_FILE, title, read_evaluations(run))
    return 0


def save_figure(fig: Any, path: Path) -> None:
    """``fig.savefig``, written atomically (a crash mid-draw keeps the previous plot), then
    the figure closed, whether the save worked or not (pyplot keeps every open figure)."""
    import matplotlib.pyplot as plt

    try:
        with atomic_write(path, "wb") as file:
            fig.savefig(file, dpi=100, format=path.suffix.lstrip(".") or "png")
    finally:
        plt.close(fig)


class Band(NamedTuple):
    """One variant's curve on a grid of steps (or seconds): mean and the 95% interval over
    seeds."""

    label: str
    steps: np.ndarray  # [G] env steps, or seconds for a band against time
    mean: np.ndarray  # [G]
    low: np.ndarray  # [G] nan with one seed
    high: np.ndarray  # [G]


def variant_band(
    label: str, runs: list[Episodes], points: int = 100, x: str = "steps"
) -> Band | None:
    """Each seed's rolling mean interpolated on a common grid of ``x`` (``"steps"`` or
    ``"times"``: training seconds), then mean ± t-interval; None without data (no episodes,
    or a run without times)."""
    from palaestra.runs.stats import confidence_interval

    runs = [r for r in runs if len(r.returns)]
    xs = [getattr(r, x) for r in runs]
    if not runs or any(v is None or np.isnan(v).any() for v in xs):
        return None
    start = max(float(v[0]) for v in xs)
    end = min(float(v[-1]) for v in xs)
    grid = np.linspace(start, max(end, start), points)
    curves = np.stack(
        [
            np.interp(grid, v, rolling_mean(r.returns, default_window(len(r.returns))))
            for v, r in zip(xs, runs)
        ]
    )  # [seeds, G]
    stats = np.array([confidence_interval(list(col)) for col in curves.T])  # [G, 3]
    return Band(label, grid, stats[:, 0], stats[:, 1], stats[:, 2])


def plot_compare(
    bands: list[Band], path: Path, title: str, time_bands: list[Band] | None = None
) -> None:
    """Every variant's mean curve with its 95% confidence band against env steps; with
    ``time_bands``, a second plot beside it against training wall-clock seconds."""
    plt = _pyplot()
    panels = [(bands, "env steps")]
    if time_bands:
        panels.append((time_bands, "wall-clock seconds of training"))
    fig, axes = plt.subplots(1, len(panels), figsize=(8 * len(panels), 4.5), squeeze=False)
    for ax, (panel, xlabel) in zip(axes[0], panels):
        for band in panel:
            (line,) = ax.plot(band.steps, band.mean, lw=2, label=band.label)
            if not all(math.isnan(v) for v in band.low):
                ax.fill_between(band.steps, band.low, band.high, color=line.get_color(), alpha=0.2)
        ax.set(xlabel=xlabel, ylabel="return (rolling mean)", title=title)
        ax.legend(loc="best")
    fig.tight_layout()
    save_figure(fig, path)
