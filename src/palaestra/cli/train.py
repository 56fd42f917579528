"""``palaestra train``: train an algorithm of ``settings.ALGOS`` from a preset, a config file
and ``--set`` overrides, into a run folder that ``eval``, ``record``, ``compare`` and
``--resume`` read.

Run folder: ``config.json`` (resolved settings), ``status.json`` (steps done, total, wall
time), ``progress.csv`` (SB3's log), ``episodes.csv`` (every episode: steps, return, length,
terminated, training seconds), ``model.zip``, ``replay_buffer.zip`` (DQN), ``checkpoints/``,
``learning_curve.png``, ``tb/`` (when tensorboard is installed).

The env comes from :mod:`palaestra.runs.recipe` (SB3's Atari recipe when the settings say
``atari``), which ``eval`` and ``record`` use to rebuild it.
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from pathlib import Path
from typing import Any

from palaestra.cli.common import CLIError, add_allow_import, eprint
from palaestra.runs import settings as settings_mod

__all__ = ["EXTRA_CALLBACKS", "add_parser", "run"]

# Test hook: callbacks added to every ``learn`` call (e.g. one that raises KeyboardInterrupt).
EXTRA_CALLBACKS: list[Any] = []


def add_parser(sub: Any) -> None:
    """Register ``train`` on the subcommand parsers."""
    p = sub.add_parser(
        "train",
        help="train an agent (" + ", ".join(settings_mod.ALGOS) + ") on an env",
        description="Train an agent. Settings come from the preset (the 'default' preset when "
        "one exists for ALGO and ENV, else the algorithm's defaults), overridden by --config, "
        "then by --set, then by --n-envs/--timesteps/--seed. Atari ids (ALE/Breakout-v5) train "
        "on SB3's Atari recipe: AtariWrapper envs, 4 stacked frames, CnnPolicy. Ctrl-C or SIGTERM "
        "stops at the next step and saves a checkpoint that --resume continues (exit code 130, "
        "143 for SIGTERM); a second signal stops at once.",
    )
    p.add_argument(
        "algo",
        nargs="?",
        metavar="ALGO",
        help=" or ".join(settings_mod.ALGOS) + " (any case); not needed with --resume",
    )
    p.add_argument(
        "env", nargs="?", metavar="ENV", help="env id, e.g. CartPole-v1 (see palaestra envs)"
    )
    p.add_argument("--preset", metavar="NAME", help="preset name (default: 'default' if any)")
    p.add_argument(
        "--config",
        metavar="FILE",
        help="settings file, .json or .yaml (PyYAML): preset keys (hyperparams, n_envs, "
        "n_timesteps, policy, env_kwargs, normalize, env_wrapper ('module:Class'), atari, "
        "frame_stack, seed) or hyperparameters at top level",
    )
    p.add_argument("--n-envs", type=int, metavar="N", help="number of parallel envs")
    p.add_argument("--timesteps", type=int, metavar="N", help="total env steps to train for")
    p.add_argument("--seed", type=int, metavar="S", help="random seed (default: none)")
    p.add_argument(
        "--out", metavar="DIR", help="run folder (default: runs/<algo>-<env>-<timestamp>)"
    )
    p.add_argument(
        "--set",
        dest="assignments",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override one setting; repeatable; VALUE is JSON or a Python literal; dotted "
        "keys reach inside dicts, e.g. policy_kwargs.net_arch=[128,128]",
    )
    p.add_argument(
        "--resume",
        metavar="DIR",
        help="continue the run in DIR (after Ctrl-C, or to a larger --timesteps) with its "
        "saved settings, model and replay buffer",
    )
    add_allow_import(p, "--resume")
    p.add_argument(
        "--device", default="auto", metavar="DEV", help="torch device: auto (default), cpu, cuda"
    )
    p.add_argument(
        "--checkpoint-every",
        type=int,
        metavar="N",
        help="save checkpoints/model_<steps>_steps.zip every N steps (default: a tenth of "
        "the budget; 0: never)",
    )
    p.add_argument(
        "--eval-episodes",
        type=int,
        default=10,
        metavar="N",
        help="deterministic evaluation episodes at the end (default: 10; 0: skip)",
    )
    p.add_argument(
        "--progress",
        choices=("auto", "bar", "line", "none"),
        default="auto",
        help="live progress: a tqdm bar, a plain line every 2 s, or nothing "
        "(default auto: the bar when tqdm is installed)",
    )
    p.add_argument(
        "--verbose", action="store_true", help="also print the SB3-style log table to stdout"
    )
    p.set_defaults(func=run)


# -- the command -------------------------------------------------------------------------------
def _default_out(algo: str, env_id: str) -> Path:
    stamp = time.strftime("%Y%m%d-%H%M%S")
    base = Path("runs") / f"{algo}-{env_id.replace('/', '_')}-{stamp}"
    out, n = base, 1
    while out.exists():
        n += 1
        out = base.with_name(f"{base.name}-{n}")
    return out


def _refuse_resume_flags(args: argparse.Namespace) -> None:
    given = [
        flag
        for flag, value in (
            ("--preset", args.preset),
            ("--config", args.config),
            ("--set", args.assignments),
            ("--n-envs", args.n_envs),
            ("--seed", args.seed),
            ("--out", args.out),
        )
        if value
    ]
    if given:
        raise CLIError(
            f"--resume continues a run with its saved settings; "
            f"{', '.join(given)} cannot change them",
            "drop them, or start a new run",
        )


def _check_flags(args: argparse.Namespace) -> str:
    if args.checkpoint_every is not None and args.checkpoint_every < 0:
        raise CLIError(
            f"--checkpoint-every must be >= 0, got {args.checkpoint_every}", "e.g. 10000"
        )
    if args.eval_episodes < 0:
        raise CLIError(f"--eval-episodes must be >= 0, got {args.eval_episodes}", "e.g. 10")
    if args.progress != "auto":
        if args.progress == "bar" and importlib.util.find_spec("tqdm") is None:
            raise CLIError("--progress bar needs tqdm", 'pip install "palaestra[progress]"')
        return str(args.progress)
    return "bar" if importlib.util.find_spec("tqdm") is not None else "line"


def run(args: argparse.Namespace) -> int:
    """The ``train`` command."""
    from palaestra.runs import open_resume, open_run, resolve_spec

    if args.resume is not None:
        _refuse_resume_flags(args)
        progress_mode = _check_flags(args)
        run_ = open_resume(
            args.resume,
            args.timesteps,
            args.allow_import,
            expect={"algo": args.algo, "env_id": args.env},
        )
    else:
        if args.allow_import:
            raise CLIError(
                "--allow-import applies to --resume (a new run imports what its --config "
                "and --set name)",
                "drop --allow-import",
            )
        if args.algo is None or args.env is None:
            raise CLIError("train needs ALGO and ENV", "e.g. palaestra train ppo CartPole-v1")
        spec, notes = resolve_spec(
            args.algo,
            args.env,
            args.preset,
            config=args.config,
            assignments=args.assignments,
            seed=args.seed,
            n_envs=args.n_envs,
            n_timesteps=args.timesteps,
            device=args.device,
        )
        run_dir = Path(args.out) if args.out else _default_out(spec.algo, spec.env_id)
        progress_mode = _check_flags(args)
        run_ = open_run(spec, run_dir)  # a folder in use or holding a run: its error line
        run_.notes[:0] = notes
    for note in run_.notes:  # after every check: bad input gets its error line only
        eprint(f"note: {note}")
    return _train(args, run_, progress_mode)


def _train(args: argparse.Namespace, run_: Any, progress_mode: str) -> int:
    """Train with the live progress and the graceful stop on Ctrl-C/SIGTERM, then print the
    summary."""
    from palaestra.cli.progress import GracefulStop, LiveProgress
    from palaestra.cli.run_files import print_summary
    from palaestra.runs.files import STATUS_FILE, read_json

    spec, run_dir, model = run_.spec, run_.run_dir, run_.model
    total = spec.n_timesteps
    stop = GracefulStop()
    stop.finish_at = total
    callbacks: list[Any] = [stop]
    progress = None
    if progress_mode != "none":
        progress = LiveProgress(total, progress_mode)
        callbacks.append(progress)
    callbacks.extend(EXTRA_CALLBACKS)
    start_steps = model.num_timesteps
    eprint(
        f"training {spec.algo} on {spec.env_id} "
        f"({model.n_envs} env{'s' * (model.n_envs > 1)}, "
        f"{'preset ' + spec.preset if spec.preset else 'no preset'}) "
        f"{'from step ' + format(start_steps, ',') + ' ' if run_.resumed else ''}to {total:,} "
        f"steps -> {run_dir}"
    )
    stop.install()
    try:
        result = run_.train(callbacks, args.checkpoint_every, args.verbose)
    except KeyboardInterrupt:  # a second Ctrl-C: the model may be mid-update, so not saved
        steps = read_json(run_dir / STATUS_FILE, "run status")["num_timesteps"]
        where = f"the checkpoint at {steps:,} steps" if steps else "nothing (no checkpoint yet)"
        eprint(
            f"palaestra: stopped at once at {model.num_timesteps:,}/{total:,} steps; "
            f"--resume continues from {where} (palaestra train --resume {run_dir})"
        )
        return stop.exit_code
    finally:
        stop.uninstall()
        if progress is not None:
            progress.close()
    if result.status == "interrupted":
        eprint(
            f"palaestra: interrupted at {model.num_timesteps:,}/{total:,} steps; checkpoint "
            f"saved in {run_dir} (resume with: palaestra train --resume {run_dir})"
        )
        return stop.exit_code  # 130 after Ctrl-C, 143 after SIGTERM
    print_summary(args.eval_episodes, result)
    return 0
