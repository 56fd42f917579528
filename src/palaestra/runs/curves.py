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
from palaestra.runs.stats import (
    CONFIDENCE_LEVEL,
    INTERVAL_METHOD,
    PROFILE_INTERVAL_METHOD,
    PROFILE_STATISTIC,
    RESAMPLES,
    STATISTIC,
    Estimate,
    Profile,
    iqm_interval,
)
from palaestra.utils.atomic_write import atomic_write, complete_text

__all__ = [
    "LEARNING_CURVE_FILE",
    "Band",
    "Episodes",
    "Evaluations",
    "draw_learning_curve",
    "figure_text",
    "learning_curve_label",
    "plot_compare",
    "plot_learning_curve",
    "plot_profile",
    "profile_text",
    "read_episodes",
    "read_evaluations",
    "rolling_mean",
    "save_figure",
    "variant_band",
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


def learning_curve_label(n_episodes: int) -> str | None:
    """The legend of ``learning_curve.png``'s smoothed line, naming the window it really
    uses; None when there is no line to draw (a window of 1 episode is no smoothing).

    >>> learning_curve_label(30), learning_curve_label(1000)
    (None, 'mean of last 50 episodes')
    """
    window = default_window(n_episodes)
    return None if window < 2 else f"mean of last {window} episodes"


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
    label = learning_curve_label(len(episodes.returns))
    if label is None:  # too few episodes to smooth: the returns themselves, joined
        n = len(episodes.returns)
        ax.plot(episodes.steps, episodes.returns, ".-", lw=1, ms=4,
                label=f"episode return ({n} episodes, not smoothed)")  # fmt: skip
    else:
        ax.plot(episodes.steps, episodes.returns, ".", ms=2, alpha=0.3, label="episode return")
        ax.plot(episodes.steps, rolling_mean(episodes.returns, window), lw=2, label=label)
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
    """One variant's curve over seeds on a grid of env steps (or seconds): at each point the
    IQM over seeds of each seed's mean return over its last ``window`` episodes finished by
    then, and its percentile-bootstrap interval (``low``, ``high`` None with one seed)."""

    label: str
    steps: np.ndarray  # [G] env steps, or seconds for a band against time
    iqm: np.ndarray  # [G]
    low: np.ndarray | None  # [G]
    high: np.ndarray | None  # [G]
    seeds: int
    window: int  # episodes in each seed's rolling mean
    min_episodes: int  # the fewest episodes a seed has: below window, its mean is over all


def variant_band(
    label: str, runs: list[Episodes], points: int = 100, x: str = "steps", window: int = 100
) -> Band | None:
    """The curve of a variant against ``x`` (``"steps"`` or ``"times"``: training seconds);
    None without data (no episodes, or a run without times).

    Each seed's value at a grid point is its rolling mean (last ``window`` episodes) as of the
    last episode it finished by then. The grid runs from the first point every seed has a value
    to the last episode of the longest run, so the last point is every seed's final value: the
    figure of ``compare``'s table (:func:`palaestra.runs.compare.summarize`), bit for bit."""
    if window < 1:
        raise ValueError(f"the smoothing window must be at least 1 episode, got {window!r}")
    runs = [r for r in runs if len(r.returns)]
    xs = [getattr(r, x) for r in runs]
    if not runs or any(v is None or np.isnan(v).any() for v in xs):
        return None
    grid = np.linspace(max(float(v[0]) for v in xs), max(float(v[-1]) for v in xs), points)
    curves = np.stack(
        [
            rolling_mean(r.returns, window)[np.searchsorted(v, grid, side="right") - 1]
            for v, r in zip(xs, runs)
        ]
    )  # [seeds, G]
    seen: dict[bytes, Estimate] = {}  # a step-function curve repeats its columns
    for col in curves.T:
        if col.tobytes() not in seen:
            seen[col.tobytes()] = iqm_interval(col)
    estimates = [seen[col.tobytes()] for col in curves.T]
    low = high = None
    if len(runs) > 1:
        low = np.array([e.low for e in estimates], dtype=np.float64)
        high = np.array([e.high for e in estimates], dtype=np.float64)
    value = np.array([e.value for e in estimates], dtype=np.float64)
    fewest = min(len(r.returns) for r in runs)
    return Band(label, grid, value, low, high, len(runs), window, fewest)


def seeds_text(n: int) -> str:
    """``"1 seed"``, ``"5 seeds"``."""
    return f"{n} seed" if n == 1 else f"{n} seeds"


def smoothing_text(window: int, min_episodes: int, when: str = "finished by then") -> str:
    """What a seed's value at a point is, with the real window.

    >>> smoothing_text(10, 40)
    "each seed's mean return over its last 10 episodes finished by then"
    >>> smoothing_text(100, 40, "of training")[-65:]
    'of training (over all of them where it has fewer: the fewest, 40)'
    """
    text = f"each seed's mean return over its last {window} episodes {when}"
    if min_episodes < window:
        text += f" (over all of them where it has fewer: the fewest, {min_episodes})"
    return text


def legend_label(band: Band) -> str:
    """``"ppo (5 seeds)"``; ``"ppo (1 seed, no interval)"``."""
    return _legend(band.label, band.seeds, band.low is not None)


def _legend(label: str, seeds: int, interval: bool) -> str:
    return f"{label} ({seeds_text(seeds)}{'' if interval else ', no interval'})"


def _seeds_per_variant(pairs: list[tuple[str, int]]) -> str:
    return "Seeds per variant: " + ", ".join(f"{label} {n}" for label, n in pairs) + "."


def figure_text(bands: list[Band], title: str) -> dict[str, Any]:
    """The words of the compare figure: what the line and the band are, over how many seeds,
    with what smoothing. ``plot_compare`` draws exactly these (and returns them for the
    record, ``summary.json``)."""
    windows = sorted({b.window for b in bands})
    window = ", ".join(str(w) for w in windows)
    fewest = min((b.min_episodes for b in bands), default=0)
    legend = [legend_label(b) for b in bands]
    level = f"{CONFIDENCE_LEVEL:.0%}"
    footnote = (
        f"Line: {STATISTIC} over seeds of {smoothing_text(int(windows[0]), fewest)}"
        if len(windows) == 1
        else f"Line: {STATISTIC} over seeds of each seed's rolling mean return ({window} episodes)"
    )
    footnote += (
        f".\nBand: {level} confidence interval, {INTERVAL_METHOD}, {RESAMPLES:,} resamples; "
        "none with 1 seed"
        # P(a resample of n seeds is all the lowest) = n^-n >= 1/27 > 2.5% for n <= 3
        + ("; with 2 or 3 seeds, their whole range" if any(1 < b.seeds < 4 for b in bands) else "")
        + ". "
        + _seeds_per_variant([(b.label, b.seeds) for b in bands])
    )
    return {
        "title": f"{title}: IQM over seeds, {level} bootstrap CI",
        "ylabel": f"return (mean of last {window} episodes)",
        "legend": legend,
        "footnote": footnote,
    }


def plot_compare(
    bands: list[Band], path: Path, title: str, time_bands: list[Band] | None = None
) -> dict[str, Any]:
    """Every variant's IQM curve with its confidence band against env steps; with
    ``time_bands``, a second plot beside it against training wall-clock seconds. Returns the
    figure's words (:func:`figure_text`)."""
    plt = _pyplot()
    text = figure_text(bands, title)
    panels = [(bands, "env steps")]
    if time_bands:
        panels.append((time_bands, "wall-clock seconds of training"))
    fig, axes = plt.subplots(1, len(panels), figsize=(8 * len(panels), 5), squeeze=False)
    for ax, (panel, xlabel) in zip(axes[0], panels):
        for band in panel:
            (line,) = ax.plot(band.steps, band.iqm, lw=2, label=legend_label(band))
            if band.low is not None and band.high is not None:
                ax.fill_between(band.steps, band.low, band.high, color=line.get_color(), alpha=0.2)
        ax.set(xlabel=xlabel, ylabel=text["ylabel"])
        ax.legend(loc="best")
    fig.suptitle(text["title"])
    _footnote(fig, text["footnote"])
    save_figure(fig, path)
    return text


def _footnote(fig: Any, text: str) -> None:
    """``text`` in small print along the bottom of ``fig``, wrapped, with room kept for it
    below the axes (the lines it wraps to estimated from the figure's width)."""
    fig.text(0.01, 0.01, text, fontsize=8, va="bottom", ha="left", wrap=True)
    width_in, height_in = fig.get_size_inches()
    per_line = int(width_in * 16)  # 8-point characters per inch of width (~17.5), rounded down
    lines = sum(-(-max(len(p), 1) // per_line) for p in text.split("\n"))
    bottom = (0.15 + lines * 8 * 1.3 / 72) / height_in  # inches of text over the height
    fig.tight_layout(rect=(0, min(bottom, 0.5), 1, 1))


def profile_text(
    profiles: list[tuple[str, Profile]], title: str, window: int, min_episodes: int
) -> dict[str, Any]:
    """The words of the performance-profile figure: what the line and the band are, over
    how many seeds, and what a run's final return is. ``plot_profile`` draws exactly these
    (and returns them for ``summary.json``)."""
    level = f"{CONFIDENCE_LEVEL:.0%}"
    footnote = (
        f"Line: {PROFILE_STATISTIC} τ; a run's final return is "
        f"{smoothing_text(window, min_episodes, 'of training')}.\n"
        f"Band: {level} confidence interval, {PROFILE_INTERVAL_METHOD}; none with 1 seed. "
        + _seeds_per_variant([(label, p.seeds) for label, p in profiles])
    )
    return {
        "title": f"{title}: performance profile of final returns, {level} bootstrap CI",
        "xlabel": f"final return τ (mean of last {window} episodes)",
        "ylabel": "fraction of runs with final return > τ",
        "legend": [_legend(label, p.seeds, p.low is not None) for label, p in profiles],
        "footnote": footnote,
    }


def plot_profile(
    profiles: list[tuple[str, Profile]], path: Path, title: str, window: int, min_episodes: int
) -> dict[str, Any]:
    """Each variant's performance profile (Agarwal et al. 2021): the fraction of its runs
    whose final return is above each threshold, a step at every run's value, with its
    confidence band. Returns the figure's words (:func:`profile_text`)."""
    plt = _pyplot()
    text = profile_text(profiles, title, window, min_episodes)
    fig, ax = plt.subplots(figsize=(8, 5))
    for (_, profile), legend in zip(profiles, text["legend"]):
        # fraction above tau drops at each run's value: constant from one threshold to the next
        (line,) = ax.step(profile.thresholds, profile.fraction, where="post", lw=2, label=legend)
        if profile.low is not None and profile.high is not None:
            ax.fill_between(profile.thresholds, profile.low, profile.high, step="post",
                            color=line.get_color(), alpha=0.2)  # fmt: skip
    ax.set(xlabel=text["xlabel"], ylabel=text["ylabel"], ylim=(-0.03, 1.03))
    ax.set_yticks([0.0, 0.25, 0.5, 0.75, 1.0])
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best")
    fig.suptitle(text["title"])
    _footnote(fig, text["footnote"])
    save_figure(fig, path)
    return text
