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
missing. The runs train through :func:`palaestra.runs.grid.run_grid`, one after another or as
Ray tasks (``--backend ray``).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from palaestra.cli.common import CLIError

__all__ = ["ALGOS_WORD", "BASELINE", "is_variant", "train_variants"]

BASELINE = "preset"
ALGOS_WORD = "algos"  # compare algorithms, each on its preset
_SUFFIXES = (".yaml", ".yml", ".json")


def is_variant(item: str) -> bool:
    """Whether a ``compare`` argument names a variant to train rather than a run folder."""
    return item == BASELINE or Path(item).suffix.lower() in _SUFFIXES


def _label(item: str) -> str:
    return BASELINE if item == BASELINE else Path(item).stem


def _check_seeds(seeds: list[int]) -> None:
    if len(set(seeds)) < len(seeds):
        raise CLIError(f"--seeds repeats a seed: {seeds}", "list each seed once")


def train_variants(args: argparse.Namespace) -> tuple[list[Path], dict[Path, str], list[Any]]:
    """Run folders for ``args.runs`` (folders as given, variants trained on ``args.seeds``),
    the variant name of each trained one, and the runs that failed."""
    from palaestra.runs.grid import GridRun
    from palaestra.runs.spec import resolve_spec

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
    labels = [_label(v) for v in variants]
    if len(set(labels)) < len(labels):
        raise CLIError(f"two variants share a name: {labels}", "give the files different names")
    _check_seeds(args.seeds)
    root = Path(args.runs_dir or f"runs/compare-{args.algo.lower()}-{args.env.replace('/', '_')}")
    items: list[Any] = []  # run folders as given, and runs to train, in the order given
    for item in args.runs:
        if not is_variant(item):
            items.append(Path(item))
            continue
        for seed in args.seeds:
            spec, _ = resolve_spec(
                args.algo,
                args.env,
                config=None if item == BASELINE else item,
                allow_import=() if item == BASELINE else args.allow_import,
                seed=seed,
                n_timesteps=args.timesteps,
            )
            items.append(GridRun(_label(item), spec, root / _label(item) / f"seed{seed}"))
    return _train(args, items)


def _algo_runs(args: argparse.Namespace) -> list[Any]:
    """``compare algos``: each of ``args.algos`` on its preset for ``args.env``, per seed."""
    from palaestra.runs.grid import GridRun
    from palaestra.runs.settings import ALGOS, check_algo
    from palaestra.runs.spec import resolve_spec

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
    algos = [check_algo(a) for a in args.algos]
    if len(set(algos)) < len(algos):
        raise CLIError(f"--algos repeats an algorithm: {args.algos}", "list each once")
    _check_seeds(args.seeds)
    root = Path(args.runs_dir or f"runs/compare-algos-{args.env.replace('/', '_')}")
    runs = []
    for algo in algos:
        for seed in args.seeds:
            spec, _ = resolve_spec(algo, args.env, seed=seed, n_timesteps=args.timesteps)
            runs.append(GridRun(algo, spec, root / algo / f"seed{seed}"))
    return runs


def _train(
    args: argparse.Namespace, items: list[Any]
) -> tuple[list[Path], dict[Path, str], list[Any]]:
    """Train the ``GridRun`` items on the chosen backend; folders in the order given."""
    from palaestra.runs.grid import GridRun, run_grid

    def report(kind: str, run: Any, outcome: Any) -> None:
        where = f"{run.label} seed {run.spec.seed}"
        if kind == "reused":
            print(f"{where}: reusing {run.run_dir}", flush=True)
        elif kind == "start":
            print(f"{where}: training -> {run.run_dir}", flush=True)
        elif outcome.status == "failed":
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
