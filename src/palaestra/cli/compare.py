"""``palaestra compare``: runs that differ only by seed form one variant; a table of final
returns with 95% t-intervals over seeds and the training wall time, and the learning curves of
all variants on one plot against env steps and on a second against wall-clock seconds.

``palaestra compare algos --env CartPole-v1 --algos a2c ppo dqn --seeds 0 1 2 3 4`` trains
each algorithm's preset on each seed first (see :mod:`palaestra.cli.variants`)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from palaestra.cli.common import CONFIG_FILE, STATUS_FILE, CLIError, is_goal_env, read_json

__all__ = ["Variant", "add_parser", "group_runs", "run"]

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
            raise CLIError(f"no run folder at {str(run)!r}", "pass folders written by train")
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


def add_parser(sub: Any) -> None:
    """Register ``compare`` on the subcommand parsers."""
    p = sub.add_parser(
        "compare",
        help="compare runs: table with confidence intervals, and learning curves",
        description="Group runs that differ only by seed into variants; print each variant's "
        "final mean return with a 95% confidence interval over seeds (t-distribution) and "
        "success rate, and plot every variant's learning curve (mean ± 95% CI band). "
        "Settings files among the arguments are variants trained first, one run per seed: "
        "palaestra compare preset shaped.yaml --algo dqn --env MountainCar-v0 --seeds 0 1 2 "
        "(shaped.yaml: env_wrapper: shaping:BetterRewardShaping). 'algos' compares "
        "algorithms, each on its preset: palaestra compare algos --env CartPole-v1 "
        "--algos a2c ppo dqn --seeds 0 1 2 3 4.",
    )
    p.add_argument(
        "runs",
        nargs="+",
        metavar="RUN_DIR|SETTINGS",
        help="run folders written by train; or variants to train first on each of --seeds: "
        "settings files (.yaml/.json, as for train --config) or 'preset' (the preset alone); "
        "or 'algos': each of --algos on its preset",
    )
    p.add_argument("--algo", metavar="ALGO", help="algorithm the variants train (e.g. dqn)")
    p.add_argument(
        "--algos", nargs="+", metavar="ALGO", help="algorithms to compare (with 'algos')"
    )
    p.add_argument("--env", metavar="ENV", help="env id the variants train on")
    p.add_argument("--seeds", nargs="+", type=int, metavar="S", help="seeds each variant trains on")
    p.add_argument("--timesteps", type=int, metavar="N", help="steps per variant run")
    p.add_argument(
        "--runs-dir",
        metavar="DIR",
        help="where variant runs go, DIR/<variant>/seed<S> (default: runs/compare-ALGO-ENV); "
        "finished runs there are reused",
    )
    p.add_argument(
        "--labels",
        nargs="+",
        metavar="LABEL",
        help="one name per variant, in order of first appearance (default: the settings in "
        "which they differ)",
    )
    p.add_argument(
        "--out",
        default="compare.png",
        metavar="PLOT.png",
        help="where to write the plot (default: compare.png)",
    )
    p.add_argument(
        "--last",
        type=int,
        default=100,
        metavar="N",
        help="final return = mean of each run's last N episodes (default: 100)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The ``compare`` command."""
    from palaestra.cli.curves import plot_compare, read_episodes, variant_band
    from palaestra.cli.stats import confidence_interval

    if args.last < 1:
        raise CLIError(f"--last must be at least 1, got {args.last}", "e.g. --last 100")
    from palaestra.cli.variants import train_variants

    folders, names = train_variants(args)
    variants = group_runs(folders)
    labels = default_labels(variants)
    for i, variant in enumerate(variants):  # a trained variant is named after its file
        named = {names.get(run) for run in variant.runs}
        if len(named) == 1 and None not in named:
            labels[i] = str(named.pop())
    if args.labels is not None:
        if len(args.labels) != len(variants):
            raise CLIError(
                f"{len(args.labels)} labels for {len(variants)} variants",
                "give one label per variant, in order of first appearance: " + "; ".join(labels),
            )
        labels = list(args.labels)
    rows, bands, time_bands = [], [], []
    for label, variant in zip(labels, variants):
        episodes = [read_episodes(r) for r in variant.runs]
        finals = [float(np.mean(e.returns[-args.last :])) for e in episodes if len(e.returns)]
        mean, low, high = confidence_interval(finals)
        env_id = str(variant.config.get("env_id", ""))
        known = [e.terminated for e in episodes if e.terminated is not None and len(e.returns)]
        success = (
            100.0 * float(np.mean([t[-args.last :].mean() for t in known]))
            if is_goal_env(env_id) and known
            else None
        )
        rows.append((label, len(variant.runs), mean, low, high, success, _wall_time(variant)))
        band = variant_band(label, episodes)
        if band is not None:
            bands.append(band)
        band = variant_band(label, episodes, x="times")
        if band is not None:
            time_bands.append(band)
    _print_table(rows, args.last)
    for label, variant in zip(labels, variants):
        print(f"  {label}: {', '.join(str(r) for r in variant.runs)}")
    from palaestra.cli.pipeline import atari_kwargs

    if any(atari_kwargs(v.config) is not None for v in variants):
        from palaestra.cli.evaluate import GAMES_NOTE

        print(f"(Atari runs: training {GAMES_NOTE})")
    envs = sorted({str(v.config.get("env_id")) for v in variants if v.config})
    # Against wall-clock time only when every variant's runs logged their times.
    timed = time_bands if len(time_bands) == len(bands) else None
    plot_compare(bands, Path(args.out), " / ".join(envs) or "learning curves", timed)
    print(f"wrote {args.out}")
    return 0


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


def _print_table(rows: list[tuple[Any, ...]], last: int) -> None:
    width = max(len("variant"), *(len(r[0]) for r in rows))
    print(f"{'variant':<{width}}  seeds  final mean return  {'95% CI':<20}  success  wall time")
    for label, n, mean, low, high, success, wall in rows:
        ci = "n/a (one seed)" if np.isnan(low) else f"[{low:.2f}, {high:.2f}]"
        rate = "-" if success is None else f"{success:.1f}%"
        seconds = "-" if wall is None else f"{wall:.1f} s"
        print(f"{label:<{width}}  {n:>5}  {mean:>17.2f}  {ci:<20}  {rate:>7}  {seconds:>9}")
    print(
        f"(final mean return: mean of each run's last {last} episodes, averaged over seeds; "
        "wall time: training seconds per run, averaged over seeds)"
    )
