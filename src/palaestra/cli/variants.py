"""``palaestra compare SETTINGS... --seeds``: train each variant on each seed, then compare.

A variant is a settings file (``.yaml``/``.yml``/``.json``, the format of ``train --config``)
or the word ``preset`` (the preset alone, the baseline). Variant ``v`` on seed ``s`` trains as
``palaestra train ALGO ENV --config v --seed s --out RUNS/<v's stem>/seed<s>`` would, so the
tutorial's baseline-vs-reward-shaping study is one command::

    palaestra compare preset naive.yaml better.yaml --algo dqn --env MountainCar-v0 --seeds 0 1 2

with ``naive.yaml`` holding ``env_wrapper: shaping:NaiveRewardShaping``. A run that already
finished is reused, so a second call only trains what is missing.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from palaestra.cli.common import CONFIG_FILE, STATUS_FILE, CLIError, read_json

__all__ = ["BASELINE", "is_variant", "train_variants"]

BASELINE = "preset"
_SUFFIXES = (".yaml", ".yml", ".json")


def is_variant(item: str) -> bool:
    """Whether a ``compare`` argument names a variant to train rather than a run folder."""
    return item == BASELINE or Path(item).suffix.lower() in _SUFFIXES


def _label(item: str) -> str:
    return BASELINE if item == BASELINE else Path(item).stem


def _train_argv(args: argparse.Namespace, item: str, seed: int, out: Path) -> list[str]:
    argv = ["train", args.algo, args.env, "--seed", str(seed), "--out", str(out)]
    if item != BASELINE:
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
    from palaestra.cli import build_parser

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
    parser = build_parser()
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
            if (out / CONFIG_FILE).is_file():
                if not _finished(out):
                    raise CLIError(
                        f"{out} holds an unfinished run", f"palaestra train --resume {out}"
                    )
                print(f"{_label(item)} seed {seed}: reusing {out}")
                continue
            print(f"{_label(item)} seed {seed}: training -> {out}", flush=True)
            train_args = parser.parse_args(_train_argv(args, item, seed, out))
            train_args.func(train_args)
    return folders, names
