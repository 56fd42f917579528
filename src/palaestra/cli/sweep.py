"""``palaestra sweep SPACE.yaml --algo ALGO --env ENV --trials N --seeds K``: search
hyperparameters with Optuna (:mod:`palaestra.runs.sweep`), locally or on Ray."""

from __future__ import annotations

import argparse
import json
import signal
from pathlib import Path
from typing import Any

from palaestra.cli.common import CLIError, add_address, add_timesteps, eprint
from palaestra.runs.settings import check_algo
from palaestra.runs.space import load_space
from palaestra.runs.sweep import run_sweep

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Register ``sweep`` on the subcommand parsers."""
    p = sub.add_parser(
        "sweep",
        help="search hyperparameters (Optuna), each trial over several seeds",
        description="Search hyperparameters with Optuna's TPE sampler and a median pruner fed "
        "by periodic evaluations. SPACE.yaml maps each hyperparameter to a list of choices or "
        "to a range {low: .., high: .., log: true|false, step: ..}; dotted names reach inside "
        "dicts (policy_kwargs.net_arch). Each trial trains the preset with the sampled values "
        "on --seeds seeds and scores their mean deterministic return. The study is kept in "
        "OUT/study.db (or --storage): run the same command again to continue it. Writes "
        "OUT/trials.csv (best first), OUT/best.yaml (for train --config), history.png and "
        "importance.png. Ctrl-C or SIGTERM stops the trial in progress at the next step and "
        "ends the search with the study intact (exit code 130, 143 for SIGTERM): the same "
        "command continues it; a second signal stops at once.",
    )
    p.add_argument("space", metavar="SPACE.yaml", help="the search space (.yaml or .json)")
    p.add_argument("--algo", required=True, metavar="ALGO", help="algorithm to tune")
    p.add_argument("--env", required=True, metavar="ENV", help="env id")
    p.add_argument("--trials", type=int, required=True, metavar="N", help="trials in the study")
    p.add_argument(
        "--seeds", type=int, default=1, metavar="K", help="seeds per trial, 0..K-1 (default 1)"
    )
    add_timesteps(p, "T", "steps per run (default: preset)")
    p.add_argument("--preset", metavar="NAME", help="preset the trials start from")
    p.add_argument("--out", metavar="DIR", help="sweep folder (default: runs/sweep-ALGO-ENV)")
    p.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="trials one after another in this process, or as Ray tasks (default local)",
    )
    add_address(p)
    p.add_argument(
        "--storage",
        metavar="URL",
        help="Optuna storage URL (default: sqlite:///OUT/study.db; a cluster needs a database "
        "every worker reaches, e.g. postgresql://...)",
    )
    p.add_argument(
        "--evaluations",
        type=int,
        default=4,
        metavar="E",
        help="evaluations of the first seed's run during training, for the pruner (default 4)",
    )
    p.add_argument(
        "--eval-episodes", type=int, default=10, metavar="N", help="episodes per evaluation"
    )
    p.add_argument("--no-prune", action="store_true", help="train every trial to the end")
    p.add_argument("--sampler-seed", type=int, default=0, metavar="S", help="TPE's seed")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The ``sweep`` command."""
    from palaestra.cli.progress import GracefulStop  # lazy: import-time — torch

    algo = check_algo(args.algo)
    if args.eval_episodes < 1:
        raise CLIError(f"--eval-episodes must be at least 1, got {args.eval_episodes}")
    space = load_space(args.space, algo)
    out = args.out or f"runs/sweep-{algo}-{args.env.replace('/', '_')}"

    def progress(row: dict[str, Any]) -> None:
        value = "" if row.get("value") is None else f" {row['value']:.2f}"
        why = f": {row['reason']}" if row.get("reason") else ""
        params = json.dumps(row["params"], sort_keys=True)
        print(f"trial {row['number']}: {row['state']}{value} {params}{why}", flush=True)

    stop = GracefulStop()  # a stop between two steps of a trial, as train's
    study = args.storage or str(Path(out) / "study.db")
    kept = (
        f"the study in {study} keeps every finished trial (run the same command again to "
        "continue it)"
    )

    def stop_requested() -> str | None:
        if not stop.requested:
            return None
        return f"interrupted by {signal.Signals(stop.signum or signal.SIGINT).name}"

    stop.install()
    try:
        result = run_sweep(
            space,
            algo,
            args.env,
            args.trials,
            args.seeds,
            out,
            args.timesteps,
            args.preset,
            args.backend,
            args.address,
            args.storage,
            args.evaluations,
            args.eval_episodes,
            args.sampler_seed,
            not args.no_prune,
            on_trial=progress,
            callbacks=[stop],
            stop_requested=stop_requested,
        )
    except KeyboardInterrupt:  # a second signal: the trial in progress is lost, the rest kept
        eprint(f"palaestra: sweep stopped at once; {kept}")
        return stop.exit_code
    finally:
        stop.uninstall()
    _print_result(result, algo, args.env, out)
    if result.stopped is not None:
        eprint(f"palaestra: sweep {result.stopped}; {kept}")
        return stop.exit_code  # 130 after Ctrl-C, 143 after SIGTERM
    return 0


def _print_result(result: Any, algo: str, env: str, out: str) -> None:
    print(f"{len(result.trials)} trials in {out} ({result.ran} run now); best first:")
    print(f"{'rank':>4}  {'trial':>5}  {'state':<8}  {'mean return':>11}  settings")
    for rank, row in enumerate(result.trials[:10], 1):
        value = "-" if row["value"] is None else f"{row['value']:.2f}"
        print(
            f"{rank:>4}  {row['number']:>5}  {row['state']:<8}  {value:>11}  "
            f"{json.dumps(row['params'], sort_keys=True)}"
        )
    if result.best_file is not None:
        print(
            f"best settings: {result.best_file} (palaestra train {algo} {env} --config "
            f"{result.best_file})"
        )
