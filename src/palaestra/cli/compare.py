"""``palaestra compare``: runs that differ only by seed form one variant; a table of each
variant's final return (interquartile mean over seeds, 95% percentile-bootstrap interval) and
training wall time, and the learning curves of all variants (the same statistic at every point)
on one plot against env steps and on a second against wall-clock seconds; each variant's
performance profile (the fraction of its seeds whose final return is above each threshold) in
``<plot>_profile.png``; ``summary.json`` and ``curves.csv`` beside the plot
(:mod:`palaestra.runs.compare` computes them).

``palaestra compare algos --env CartPole-v1 --algos a2c ppo dqn --seeds 0 1 2 3 4`` trains
each algorithm's preset on each seed first (see :mod:`palaestra.cli.variants`), locally or on
Ray (``--backend ray``)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from palaestra.cli.common import CLIError, add_address, add_allow_import, add_timesteps
from palaestra.cli.evaluate import GAMES_NOTE
from palaestra.cli.variants import train_variants
from palaestra.runs.compare import (
    CURVES_FILE,
    SUMMARY_FILE,
    default_labels,
    group_runs,
    profiles,
    summarize,
    write_curves,
    write_summary,
)
from palaestra.runs.curves import plot_compare, plot_profile, variant_band
from palaestra.runs.recipe import atari_kwargs
from palaestra.runs.stats import CONFIDENCE_LEVEL, method_note

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Register ``compare`` on the subcommand parsers."""
    p = sub.add_parser(
        "compare",
        help="compare runs: table with confidence intervals, and learning curves",
        description="Group runs that differ only by seed into variants; print each variant's "
        "final return as the interquartile mean (IQM) over seeds with a 95% percentile-bootstrap "
        "confidence interval (Agarwal et al. 2021; no interval with one seed) and its success "
        "rate, and plot every variant's learning curve (the same IQM and interval at each "
        "point), and each variant's performance profile (the fraction of its seeds whose final "
        "return is above each threshold, with a bootstrap band) in PLOT_profile.png; "
        "summary.json and curves.csv beside the plot record the numbers. "
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
    add_timesteps(p, "N", "steps per variant run")
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
        help="where to write the plot (default: compare.png); the performance profile "
        "(PLOT_profile.png), summary.json and curves.csv go beside it",
    )
    p.add_argument(
        "--last",
        type=int,
        default=100,
        metavar="N",
        help="smoothing window: a seed's value at each point of the curves is its mean return "
        "over its last N episodes finished by then, and its final return the value at the end "
        "of training (default: 100)",
    )
    p.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="where variant runs train: one after another in this process (local, the "
        "default), or as Ray tasks (ray: a local Ray on this machine's cores, or the cluster "
        "at --address)",
    )
    add_address(p)
    add_allow_import(p, "compare (a settings file's env_wrapper)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The ``compare`` command."""
    if args.last < 1:
        raise CLIError(f"--last must be at least 1, got {args.last}", "e.g. --last 100")
    plot = Path(args.out)
    # Before training: a folder that cannot be made fails now, not after the runs.
    plot.parent.mkdir(parents=True, exist_ok=True)
    folders, names, failed = train_variants(args)
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
    rows = summarize(variants, labels, args.last)
    _print_table(rows, args.last)
    for row in rows:
        print(f"  {row.label}: {', '.join(str(r) for r in row.variant.runs)}")
        if len(row.runs) < len(row.variant.runs):
            print(f"    ({len(row.variant.runs) - len(row.runs)} run(s) without episodes left out)")
    for outcome in failed:
        print(f"  failed: {outcome.run.label} seed {outcome.run.spec.seed}: {outcome.error}")
    if any(atari_kwargs(v.config) is not None for v in variants):
        print(f"(Atari runs: training {GAMES_NOTE})")
    last = args.last
    bands, time_bands = [], []
    for row in rows:
        if (band := variant_band(row.label, row.episodes, window=last)) is not None:
            bands.append(band)
        if (band := variant_band(row.label, row.episodes, x="times", window=last)) is not None:
            time_bands.append(band)
    envs = sorted({str(v.config.get("env_id")) for v in variants if v.config})
    # Against wall-clock time only when every variant's runs logged their times.
    timed = time_bands if len(time_bands) == len(bands) else None
    title = " / ".join(envs) or "learning curves"
    figure = plot_compare(bands, plot, title, timed)
    summary, curves = plot.with_name(SUMMARY_FILE), plot.with_name(CURVES_FILE)
    write_curves(curves, {"env_steps": bands, **({"wall_seconds": timed} if timed else {})})
    files = {"plot": plot.name, "curves": curves.name}
    row_profiles = profiles(rows)
    drawn = [(row.label, p) for row, p in zip(rows, row_profiles) if p is not None]
    profile_figure, written = None, [plot]
    if drawn:
        profile_png = plot.with_name(f"{plot.stem}_profile{plot.suffix}")
        fewest = min(n for row in rows for n in row.episodes_per_run)
        profile_figure = plot_profile(drawn, profile_png, title, last, fewest)
        files["profile"] = profile_png.name
        written.append(profile_png)
    write_summary(summary, rows, figure, files, row_profiles, profile_figure)
    print(f"wrote {', '.join(str(p) for p in [*written, summary, curves])}")
    return 1 if failed else 0


def _print_table(rows: list[Any], last: int) -> None:
    width = max(len("variant"), *(len(r.label) for r in rows))
    ci_head = f"{CONFIDENCE_LEVEL:.0%} CI"
    print(f"{'variant':<{width}}  seeds  IQM final return  {ci_head:<20}  success  wall time")
    for row in rows:
        label, n, value, low, high = row.label, row.seeds, row.value, row.low, row.high
        success, wall = row.success, row.wall_time_s
        ci = f"[{low:.2f}, {high:.2f}]" if low is not None else "n/a (one seed)" if n else "n/a"
        rate = "-" if success is None else f"{success:.1f}%"
        seconds = "-" if wall is None else f"{wall:.2f} s"
        print(f"{label:<{width}}  {n:>5}  {value:>16.2f}  {ci:<20}  {rate:>7}  {seconds:>9}")
    print(
        f"(final return: each seed's mean return over its last {last} episodes; "
        f"{method_note()}; wall time: training seconds per run, averaged over seeds)"
    )
