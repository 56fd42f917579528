"""Runs compared: runs that differ only by seed form one variant; each variant's final return
as the interquartile mean over seeds with a 95% percentile-bootstrap interval
(:mod:`palaestra.runs.stats`), its success rate (goal envs) and training wall time; and the
record of a comparison, ``summary.json`` and ``curves.csv``, beside its plot; and each
variant's performance profile (Agarwal et al. 2021): the fraction of its seeds whose final
return is above each threshold, with a bootstrap band.

A seed's final return is its mean return over its last ``last`` episodes (all of them when it
has fewer): the same rolling mean the curves plot (:func:`palaestra.runs.curves.variant_band`),
whose last point is therefore the table's figure.
"""

from __future__ import annotations

import csv
import dataclasses
import json
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from palaestra.runs.curves import Band, Episodes, read_episodes, rolling_mean, smoothing_text
from palaestra.runs.errors import RunError
from palaestra.runs.files import CONFIG_FILE, STATUS_FILE, is_goal_env, read_json, write_json
from palaestra.runs.stats import (
    BOOTSTRAP_SEED,
    CONFIDENCE_LEVEL,
    INTERVAL_METHOD,
    PROFILE_INTERVAL_METHOD,
    PROFILE_STATISTIC,
    RESAMPLES,
    STATISTIC,
    Profile,
    iqm_interval,
    performance_profile,
    profile_thresholds,
)
from palaestra.utils.atomic_write import atomic_write

__all__ = [
    "CURVES_FILE",
    "SUMMARY_FILE",
    "Row",
    "Variant",
    "default_labels",
    "group_runs",
    "profiles",
    "summarize",
    "write_curves",
    "write_summary",
]

SUMMARY_FILE = "summary.json"
CURVES_FILE = "curves.csv"

# Config keys that do not make two runs different variants.
_IGNORED = {"seed", "device", "palaestra_version"}


class Variant(NamedTuple):
    """Runs with the same settings but for the seed."""

    key: str
    config: dict[str, Any]
    runs: list[Path]


def _flatten(config: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in config.items():
        name = key if prefix in ("", "hyperparams.") else prefix + key
        if isinstance(value, dict) and value:
            out.update(_flatten(value, f"{name}."))
        else:
            out[name] = value
    return out


def group_runs(runs: list[Path]) -> list[Variant]:
    """Variants in order of first appearance; a run without config.json is its own variant."""
    variants: dict[str, Variant] = {}
    for run in runs:
        if not run.is_dir():
            raise RunError(f"no run folder at {str(run)!r}", "pass folders written by train")
        config_path = run / CONFIG_FILE
        if config_path.is_file():
            config = read_json(config_path, "run config")
            kept = {k: v for k, v in config.items() if k not in _IGNORED}
            key = json.dumps(kept, sort_keys=True, default=str)
        else:
            config, key = {}, f"run:{run.resolve()}"
        variants.setdefault(key, Variant(key, config, []))
        variants[key].runs.append(run)
    return list(variants.values())


def default_labels(variants: list[Variant]) -> list[str]:
    """Each variant named by the settings in which the variants differ.

    >>> a = Variant("a", {"algo": "ppo", "hyperparams": {"gamma": 0.9}}, [])
    >>> b = Variant("b", {"algo": "ppo", "hyperparams": {"gamma": 0.99}}, [])
    >>> default_labels([a, b])
    ['gamma=0.9', 'gamma=0.99']
    """
    flat = [_flatten({k: v for k, v in v.config.items() if k not in _IGNORED}) for v in variants]
    keys = sorted({k for f in flat for k in f})
    differing = [k for k in keys if len({json.dumps(f.get(k), default=str) for f in flat}) > 1]
    labels = []
    for variant, values in zip(variants, flat):
        if not variant.config:
            labels.append(variant.runs[0].name)
        elif differing:
            parts = [
                str(values.get(k)) if k in ("algo", "env_id") else f"{k}={values.get(k)}"
                for k in differing
            ]
            labels.append(", ".join(parts))
        else:
            labels.append(f"{values.get('algo')} {values.get('env_id')}")
    return labels


def _wall_time(variant: Variant) -> float | None:
    """Mean training seconds per run (``status.json``); None when a run has none."""
    seconds = []
    for run in variant.runs:
        path = run / STATUS_FILE
        if not path.is_file():
            return None
        wall = read_json(path, "run status").get("wall_time_s")
        if isinstance(wall, bool) or not isinstance(wall, (int, float)):
            return None
        seconds.append(float(wall))
    return float(np.mean(seconds)) if seconds else None


@dataclasses.dataclass
class Row:
    """One variant's line of the comparison, and its curves' data."""

    label: str
    variant: Variant
    runs: list[Path]  # the runs with episodes, in the order of ``finals``
    finals: list[float]  # each run's mean return over its last ``window`` episodes
    episodes_per_run: list[int]
    window: int
    value: float  # IQM of ``finals`` (nan when no run has an episode)
    low: float | None  # its 95% percentile-bootstrap interval; None below 2 seeds
    high: float | None
    success: float | None  # percent of the last episodes that reached the goal (goal envs)
    wall_time_s: float | None  # training seconds per run, averaged over seeds
    episodes: list[Episodes]  # each run's episodes

    @property
    def seeds(self) -> int:
        """Runs that count: those with at least one finished episode."""
        return len(self.finals)


def summarize(variants: list[Variant], labels: list[str], last: int = 100) -> list[Row]:
    """The comparison's rows: a run's final return = mean of its last ``last`` episodes; a
    variant's figure = IQM over its runs, with a percentile-bootstrap interval."""
    if last < 1:
        raise RunError(f"--last must be at least 1, got {last}", "e.g. --last 100")
    rows = []
    for label, variant in zip(labels, variants):
        episodes = [read_episodes(r) for r in variant.runs]
        counted = [(run, e) for run, e in zip(variant.runs, episodes) if len(e.returns)]
        # rolling_mean's last value, not np.mean(returns[-last:]): the curve's last point is
        # this same float, so the table and the plot agree to the last bit.
        finals = [float(rolling_mean(e.returns, last)[-1]) for _, e in counted]
        if finals:
            value, low, high = iqm_interval(finals)
        else:
            value, low, high = float("nan"), None, None
        env_id = str(variant.config.get("env_id", ""))
        known = [e.terminated for e in episodes if e.terminated is not None and len(e.returns)]
        success = (
            100.0 * float(np.mean([t[-last:].mean() for t in known]))
            if known and is_goal_env(env_id)
            else None
        )
        rows.append(
            Row(
                label=label,
                variant=variant,
                runs=[run for run, _ in counted],
                finals=finals,
                episodes_per_run=[len(e.returns) for _, e in counted],
                window=last,
                value=value,
                low=low,
                high=high,
                success=success,
                wall_time_s=_wall_time(variant),
                episodes=episodes,
            )
        )
    return rows


def profiles(rows: list[Row]) -> list[Profile | None]:
    """Each row's performance profile of its final returns, all at the same thresholds (every
    final return of every variant, and one point beyond each end); None for a row without
    runs."""
    finals = [value for row in rows for value in row.finals]
    if not finals:
        return [None for _ in rows]
    thresholds = profile_thresholds(finals)
    return [performance_profile(row.finals, thresholds) if row.finals else None for row in rows]


def _profile_record(profile: Profile | None) -> dict[str, Any] | None:
    if profile is None:
        return None
    low, high = profile.low, profile.high
    return {
        "thresholds": profile.thresholds.tolist(),
        "fraction": profile.fraction.tolist(),
        "low": None if low is None else low.tolist(),
        "high": None if high is None else high.tolist(),
    }


def _number(value: float | None) -> float | None:
    return None if value is None or not np.isfinite(value) else float(value)


def write_summary(
    path: Path,
    rows: list[Row],
    figure: dict[str, Any],
    files: dict[str, str],
    row_profiles: list[Profile | None] | None = None,
    profile_figure: dict[str, Any] | None = None,
) -> None:
    """``summary.json``: what was computed, how, and from which runs, per variant; with
    ``row_profiles`` (one per row, :func:`profiles`), each variant's performance profile and
    how it was computed."""
    row_profiles = row_profiles or [None for _ in rows]
    last = rows[0].window if rows else None
    fewest = min((n for r in rows for n in r.episodes_per_run), default=last or 0)
    variants = []
    for row, profile in zip(rows, row_profiles):
        variants.append(
            {
                "label": row.label,
                "seed_count": row.seeds,
                "runs": [str(r) for r in row.runs],
                "seeds": [_run_seed(r) for r in row.runs],
                "per_seed_values": row.finals,
                "episodes_per_seed": row.episodes_per_run,
                "value": _number(row.value),
                "interval": None if row.low is None else [row.low, row.high],
                "success_percent": row.success,
                "wall_time_s": row.wall_time_s,
                "profile": _profile_record(profile),
            }
        )
    profile_record = None
    if any(p is not None for p in row_profiles):
        profile_record = {
            "statistic": PROFILE_STATISTIC,
            "interval_method": PROFILE_INTERVAL_METHOD,
            "confidence_level": CONFIDENCE_LEVEL,
            "no_interval_below_seeds": 2,
            "figure": profile_figure,
        }
    write_json(
        path,
        {
            "statistic": STATISTIC,
            "per_seed_value": smoothing_text(last, fewest, "of training") if last else None,
            "smoothing_window_episodes": last,
            "interval_method": INTERVAL_METHOD,
            "confidence_level": CONFIDENCE_LEVEL,
            "bootstrap_resamples": RESAMPLES,
            "bootstrap_seed": BOOTSTRAP_SEED,
            "no_interval_below_seeds": 2,
            "files": files,
            "figure": figure,
            "profile": profile_record,
            "variants": variants,
        },
    )


def _run_seed(run: Path) -> int | None:
    path = run / CONFIG_FILE
    seed = read_json(path, "run config").get("seed") if path.is_file() else None
    return seed if isinstance(seed, int) and not isinstance(seed, bool) else None


CURVES_COLUMNS = ("variant", "axis", "x", "seeds", "iqm", "low", "high")


def write_curves(path: Path, panels: dict[str, list[Band]]) -> None:
    """``curves.csv``: the plotted points, one row per variant and grid point of each axis
    (``env_steps``, ``wall_seconds``); ``low``/``high`` empty with one seed. Floats are
    written in full (``repr``), so they read back as the plotted values."""
    with atomic_write(path, "w", encoding="utf-8", newline="") as file:
        out = csv.writer(file, lineterminator="\n")
        out.writerow(CURVES_COLUMNS)
        for axis, bands in panels.items():
            for band in bands:
                for i, x in enumerate(band.steps):
                    low = "" if band.low is None else repr(float(band.low[i]))
                    high = "" if band.high is None else repr(float(band.high[i]))
                    out.writerow(
                        [band.label, axis, repr(float(x)), band.seeds,
                         repr(float(band.iqm[i])), low, high]
                    )  # fmt: skip
