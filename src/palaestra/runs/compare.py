"""Runs compared: runs that differ only by seed form one variant; each variant's final mean
return with a 95% t-interval over seeds, its success rate (goal envs) and training wall time.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from palaestra.runs.errors import RunError
from palaestra.runs.files import CONFIG_FILE, STATUS_FILE, is_goal_env, read_json

__all__ = ["Row", "Variant", "default_labels", "group_runs", "summarize"]

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
    seeds: int
    mean: float
    low: float  # 95% t-interval of the mean final return over seeds (nan below 2 seeds)
    high: float
    success: float | None  # percent of the last episodes that reached the goal (goal envs)
    wall_time_s: float | None  # training seconds per run, averaged over seeds
    episodes: list[Any]  # each run's Episodes (runs.curves)


def summarize(variants: list[Variant], labels: list[str], last: int = 100) -> list[Row]:
    """The comparison's rows: final return = mean of each run's last ``last`` episodes."""
    from palaestra.runs.curves import read_episodes
    from palaestra.runs.stats import confidence_interval

    if last < 1:
        raise RunError(f"--last must be at least 1, got {last}", "e.g. --last 100")
    rows = []
    for label, variant in zip(labels, variants):
        episodes = [read_episodes(r) for r in variant.runs]
        finals = [float(np.mean(e.returns[-last:])) for e in episodes if len(e.returns)]
        mean, low, high = confidence_interval(finals)
        env_id = str(variant.config.get("env_id", ""))
        known = [e.terminated for e in episodes if e.terminated is not None and len(e.returns)]
        success = (
            100.0 * float(np.mean([t[-last:].mean() for t in known]))
            if known and is_goal_env(env_id)
            else None
        )
        rows.append(
            Row(
                label,
                variant,
                len(variant.runs),
                mean,
                low,
                high,
                success,
                _wall_time(variant),
                episodes,
            )
        )
    return rows
