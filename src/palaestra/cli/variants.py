"""``palaestra compare SETTINGS... --seeds``: train each variant on each seed, then compare.

A variant is a settings file (``.yaml``/``.yml``/``.json``, the format of ``train --config``)
or the word ``preset`` (the preset alone, the baseline). Variant ``v`` on seed ``s`` trains as
``palaestra train ALGO ENV --config v --seed s --out RUNS/<v's stem>/seed<s>`` would, so the
tutorial's baseline-vs-reward-shaping study is one command::

    palaestra compare preset naive.yaml better.yaml --algo dqn --env MountainCar-v0 --seeds 0 1 2

with ``naive.yaml`` holding ``env_wrapper: shaping:NaiveRewardShaping`` (a settings file runs
no code unless the command line allows it: add ``--allow-import shaping``). The word ``algos``
compares algorithms instead, each on its own preset for the env (``settings.ALGOS`` lists
them)::

    palaestra compare algos --env CartPole-v1 --algos a2c ppo dqn --seeds 0 1 2 3 4

Algorithm ``a`` on seed ``s`` trains as ``palaestra train a ENV --seed s --out
RUNS/a/seed<s>``. A run that already finished is reused, so a second call only trains what is
missing. :mod:`palaestra.runs.variants` makes the grid; the runs train through
:func:`palaestra.runs.grid.run_grid`, one after another or as Ray tasks (``--backend ray``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from palaestra.cli.common import CLIError
from palaestra.runs.grid import GridRun, Outcome, run_grid
from palaestra.runs.settings import ALGOS
from palaestra.runs.variants import BASELINE, algo_runs, is_variant, variant_label, variant_runs

__all__ = ["ALGOS_WORD", "BASELINE", "is_variant", "train_variants"]

ALGOS_WORD = "algos"  # compare algorithms, each on its preset


def train_variants(args: argparse.Namespace) -> tuple[list[Path], dict[Path, str], list[Outcome]]:
    """Run folders for ``args.runs`` (folders as given, variants trained on ``args.seeds``),
    the variant name of each trained one, and the runs that failed."""
    if ALGOS_WORD in args.runs:
        return _train(args, _algo_runs(args))
    if getattr(args, "algos", None):
        raise CLIError("--algos only applies to 'algos'", "palaestra compare algos --algos ...")
    variants = [item for item in args.runs if is_variant(item)]
    if not variants:
        given = [f for f in ("algo", "env", "seeds", "timesteps", "runs_dir") if getattr(args, f)]
        if args.backend != "local" or args.address:
            given += ["backend", "address"][: 1 + bool(args.address)]
        if given:
            flags = ", ".join("--" + f.replace("_", "-") for f in given)
            raise CLIError(
                f"{flags} only apply to variants to train (settings files or 'preset')",
                "drop them to compare the run folders as they are",
            )
        return [Path(item) for item in args.runs], {}, []
    if args.algo is None or args.env is None or not args.seeds:
        raise CLIError(
            f"training the variants {variants} needs --algo, --env and --seeds",
            "e.g. --algo dqn --env MountainCar-v0 --seeds 0 1 2",
        )
    root = Path(args.runs_dir or f"runs/compare-{args.algo.lower()}-{args.env.replace('/', '_')}")
    grid = variant_runs(
        variants, args.algo, args.env, args.seeds, root, args.timesteps, args.allow_import
    )
    items: list[Path | GridRun] = []  # run folders as given, and runs to train, in that order
    for item in args.runs:
        if is_variant(item):
            items += [run for run in grid if run.label == variant_label(item)]
        else:
            items.append(Path(item))
    return _train(args, items)


def _algo_runs(args: argparse.Namespace) -> list[Path | GridRun]:
    """``compare algos``: each of ``args.algos`` on its preset for ``args.env``, per seed."""
    if args.runs != [ALGOS_WORD]:
        others = [r for r in args.runs if r != ALGOS_WORD]
        raise CLIError(
            f"'{ALGOS_WORD}' compares algorithms alone, not with {others}",
            "compare run folders or settings files in a separate command",
        )
    if not args.algos or args.env is None or not args.seeds:
        raise CLIError(
            "comparing algorithms needs --algos, --env and --seeds",
            f"e.g. --algos {' '.join(ALGOS)} --env CartPole-v1 --seeds 0 1 2",
        )
    if args.algo is not None:
        raise CLIError("--algo does not apply to 'algos'", "list them with --algos")
    root = Path(args.runs_dir or f"runs/compare-algos-{args.env.replace('/', '_')}")
    return list(algo_runs(args.algos, args.env, args.seeds, root, args.timesteps))


def _train(
    args: argparse.Namespace, items: list[Path | GridRun]
) -> tuple[list[Path], dict[Path, str], list[Outcome]]:
    """Train the ``GridRun`` items on the chosen backend; folders in the order given."""

    def report(kind: str, run: GridRun, outcome: Outcome | None) -> None:
        where = f"{run.label} seed {run.spec.seed}"
        if kind == "reused":
            print(f"{where}: reusing {run.run_dir}", flush=True)
        elif kind == "start":
            print(f"{where}: training -> {run.run_dir}", flush=True)
        elif outcome is not None and outcome.status == "failed":
            print(f"{where}: failed: {outcome.error}", flush=True)

    grid = [item for item in items if isinstance(item, GridRun)]
    outcomes = run_grid(grid, args.backend, args.address, on_event=report)
    failed = [o for o in outcomes if o.status == "failed"]
    lost = {o.run.run_dir for o in failed}
    folders = [
        item.run_dir if isinstance(item, GridRun) else item
        for item in items
        if not (isinstance(item, GridRun) and item.run_dir in lost)
    ]
    names = {item.run_dir: item.label for item in grid}
    return folders, names, failed
