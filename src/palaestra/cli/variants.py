"""``palaestra compare SETTINGS... --seeds``: train each variant on each seed, then compare.

A variant is a settings file (``.yaml``/``.yml``/``.json``, the format of ``train --config``)
or the word ``preset`` (the preset alone, the baseline). Variant ``v`` on seed ``s`` trains as
``palaestra train ALGO ENV --config v --seed s --out RUNS/<v's stem>/seed<s>`` would, so the
tutorial's baseline-vs-reward-shaping study is one command::

    palaestra compare preset naive.yaml better.yaml --algo dqn --env MountainCar-v0 --seeds 0 1 2

with ``naive.yaml`` holding ``env_wrapper: shaping:NaiveRewardShaping``. The word ``algos``
compares algorithms instead, each on its own preset for the env (``settings.ALGOS`` lists
them)::

    palaestra compare algos --env CartPole-v1 --algos a2c ppo dqn --seeds 0 1 2 3 4

Algorithm ``a`` on seed ``s`` trains as ``palaestra train a ENV --seed s --out
RUNS/a/seed<s>``. A run that already finished is reused, so a second call only trains what is
missing.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from palaestra.cli.common import CONFIG_FILE, STATUS_FILE, CLIError, read_json

__all__ = ["ALGOS_WORD", "BASELINE", "is_variant", "train_variants"]

BASELINE = "preset"
ALGOS_WORD = "algos"  # compare algorithms, each on its preset
_SUFFIXES = (".yaml", ".yml", ".json")


def is_variant(item: str) -> bool:
    """Whether a ``compare`` argument names a variant to train rather than a run folder."""
    return item == BASELINE or Path(item).suffix.lower() in _SUFFIXES


def _label(item: str) -> str:
    return BASELINE if item == BASELINE else Path(item).stem


def _train_argv(
    args: argparse.Namespace, item: str, seed: int, out: Path, algo: str | None = None
) -> list[str]:
    """``train`` arguments for variant ``item`` (or, with ``algo``, that algorithm's preset)."""
    argv = ["train", algo or args.algo, args.env, "--seed", str(seed), "--out", str(out)]
    if algo is None and item != BASELINE:
        argv += ["--config", item]
    if args.timesteps is not None:
        argv += ["--timesteps", str(args.timesteps)]
    return [*argv, "--progress", "none", "--eval-episodes", "0"]


def _finished(run: Path) -> bool:
    status = run / STATUS_FILE
    return status.is_file() and read_json(status, "run status").get("status") == "finished"


def train_variants(args: argparse.Namespace) -> tuple[list[Path], dict[Path, str]]:
    """Run folders for ``args.runs`` (folders as given, variants trained on ``args.seeds``) and
    the variant name of each trained one."""
    if ALGOS_WORD in args.runs:
        return _train_algos(args)
    if getattr(args, "algos", None):
        raise CLIError("--algos only applies to 'algos'", "palaestra compare algos --algos ...")
    variants = [item for item in args.runs if is_variant(item)]
    if not variants:
        given = [f for f in ("algo", "env", "seeds", "timesteps", "runs_dir") if getattr(args, f)]
        if given:
            flags = ", ".join("--" + f.replace("_", "-") for f in given)
            raise CLIError(
                f"{flags} only apply to variants to train (settings files or 'preset')",
                "drop them to compare the run folders as they are",
            )
        return [Path(item) for item in args.runs], {}
    if args.algo is None or args.env is None or not args.seeds:
        raise CLIError(
            f"training the variants {variants} needs --algo, --env and --seeds",
            "e.g. --algo dqn --env MountainCar-v0 --seeds 0 1 2",
        )
    labels = [_label(v) for v in variants]
    if len(set(labels)) < len(labels):
        raise CLIError(f"two variants share a name: {labels}", "give the files different names")
    if len(set(args.seeds)) < len(args.seeds):
        raise CLIError(f"--seeds repeats a seed: {args.seeds}", "list each seed once")
    root = Path(args.runs_dir or f"runs/compare-{args.algo.lower()}-{args.env.replace('/', '_')}")
    folders: list[Path] = []
    names: dict[Path, str] = {}
    for item in args.runs:
        if not is_variant(item):
            folders.append(Path(item))
            continue
        for seed in args.seeds:
            out = root / _label(item) / f"seed{seed}"
            folders.append(out)
            names[out] = _label(item)
            _train_or_reuse(_label(item), seed, out, _train_argv(args, item, seed, out))
    return folders, names


def _train_algos(args: argparse.Namespace) -> tuple[list[Path], dict[Path, str]]:
    """``compare algos``: each of ``args.algos`` on its preset for ``args.env``, per seed."""
    from palaestra.cli.settings import ALGOS, check_algo

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
    if len(set(args.seeds)) < len(args.seeds):
        raise CLIError(f"--seeds repeats a seed: {args.seeds}", "list each seed once")
    root = Path(args.runs_dir or f"runs/compare-algos-{args.env.replace('/', '_')}")
    folders: list[Path] = []
    names: dict[Path, str] = {}
    for algo in algos:
        for seed in args.seeds:
            out = root / algo / f"seed{seed}"
            folders.append(out)
            names[out] = algo
            _train_or_reuse(algo, seed, out, _train_argv(args, algo, seed, out, algo=algo))
    return folders, names


def _train_or_reuse(label: str, seed: int, out: Path, argv: list[str]) -> None:
    """Train one variant run into ``out`` unless a finished run is already there."""
    from palaestra.cli import build_parser

    if (out / CONFIG_FILE).is_file():
        if not _finished(out):
            raise CLIError(f"{out} holds an unfinished run", f"palaestra train --resume {out}")
        print(f"{label} seed {seed}: reusing {out}")
        return
    print(f"{label} seed {seed}: training -> {out}", flush=True)
    train_args = build_parser().parse_args(argv)
    code = train_args.func(train_args)
    if code:
        raise CLIError(
            f"training {label} seed {seed} stopped (exit code {code})",
            f"palaestra train --resume {out}, then run compare again",
            code=code,
        )
