"""``palaestra train``: train an algorithm of ``settings.ALGOS`` from a preset, a config file
and ``--set`` overrides, into a run folder that ``eval``, ``record``, ``compare`` and
``--resume`` read.

Run folder: ``config.json`` (resolved settings), ``status.json`` (steps done, total, wall
time), ``progress.csv`` (SB3's log), ``episodes.csv`` (every episode: steps, return, length,
terminated, training seconds), ``model.zip``, ``replay_buffer.zip`` (DQN), ``checkpoints/``,
``learning_curve.png``, ``tb/`` (when tensorboard is installed); with ``--eval-freq``,
``evaluations.csv`` and ``best_model.zip`` (:mod:`palaestra.runs.periodic_eval`).

The env comes from :mod:`palaestra.runs.recipe` (SB3's Atari recipe when the settings say
``atari``), which ``eval`` and ``record`` use to rebuild it.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import time
from pathlib import Path
from typing import Any

from palaestra import presets
from palaestra.cli.common import CLIError, add_allow_import, add_timesteps, eprint
from palaestra.cli.run_files import print_summary
from palaestra.runs import open_resume, open_run, resolve_spec
from palaestra.runs import settings as settings_mod
from palaestra.runs.files import STATUS_FILE, read_json
from palaestra.runs.settings import parse_value

__all__ = ["EXTRA_CALLBACKS", "add_parser", "run"]

# Test hook: callbacks added to every ``learn`` call (e.g. one that raises KeyboardInterrupt).
EXTRA_CALLBACKS: list[Any] = []
DEFAULT_EVAL_EPISODES = 10


def add_parser(sub: Any) -> None:
    """Register ``train`` on the subcommand parsers."""
    p = sub.add_parser(
        "train",
        help="train an agent (" + ", ".join(settings_mod.ALGOS) + ") on an env",
        description="Train an agent. Settings come from the preset (the 'default' preset when "
        "one exists for ALGO and ENV, else the algorithm's defaults with the policy picked "
        "from the observation space), overridden by --config, then by --set, then by "
        "--env-kwargs, then by --n-envs/--timesteps/--seed. Atari ids (ALE/Breakout-v5) train "
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
        "env",
        nargs="?",
        metavar="ENV",
        help="env id, e.g. CartPole-v1 (see palaestra envs), or your own as MODULE:Name-v0: "
        "MODULE (e.g. mygrid.py in the current folder) is imported and registers it",
    )
    p.add_argument("--preset", metavar="NAME", help="preset name (default: 'default' if any)")
    p.add_argument(
        "--config",
        metavar="FILE",
        help="settings file, .json or .yaml (PyYAML): preset keys (hyperparams, n_envs, "
        "n_timesteps, policy, env_kwargs, normalize, env_wrapper ('module:Class'), atari, "
        "frame_stack, seed) or hyperparameters at top level; a module its env_wrapper names "
        "is imported only with --allow-import MODULE (palaestra's own names need none: "
        "docs/known_names.md); the command line's values override the file's. An RL Zoo "
        "hyperparameter file (rl_zoo3/hyperparams/ppo.yml) is read as the Zoo reads it: the "
        "section for ENV (else atari, else default), in place of the preset",
    )
    p.add_argument("--n-envs", type=int, metavar="N", help="number of parallel envs")
    add_timesteps(
        p,
        "N",
        "total env steps to train for; PPO and A2C train on whole rollouts and off-policy "
        "algorithms on whole train_freq collections, so a run can end a little past N (a note "
        "says where at the start, and the progress counts to there)",
    )
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
    p.add_argument(
        "--env-kwargs",
        nargs="+",
        default=None,
        metavar="KEY:VALUE",
        help="keyword arguments for the env, RL Zoo style: --env-kwargs size:5 slippery:False "
        "(VALUE is JSON or a Python literal, else text); overrides the config file's env_kwargs",
    )
    add_allow_import(p, "train (a --config file's env_wrapper) and --resume")
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
        "--eval-freq",
        type=int,
        default=0,
        metavar="N",
        help="evaluate during training every N env steps counted over all envs, as the RL Zoo "
        "counts (every N // n_envs steps of the vector env), on a separate env seeded 0 each "
        "time, its VecNormalize statistics copied from the training env: writes "
        "evaluations.csv, keeps best_model.zip (the best mean return so far) and draws the "
        "evaluations on learning_curve.png (default: 0, never); --resume continues the run's "
        "schedule",
    )
    p.add_argument(
        "--eval-episodes",
        type=int,
        metavar="K",
        help="deterministic episodes of each evaluation: every --eval-freq one and the final "
        "one (default: 10, where the RL Zoo's --eval-episodes is 5; 0: no final evaluation); "
        "with --resume it sets the final one only, the periodic ones keep the run's K",
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
            ("--env-kwargs", args.env_kwargs),
            ("--seed", args.seed),
            ("--out", args.out),
            ("--eval-freq", args.eval_freq),
        )
        if value
    ]
    if given:
        raise CLIError(
            f"--resume continues a run with its saved settings; "
            f"{', '.join(given)} cannot change them",
            "drop them, or start a new run",
        )


def _env_kwargs(items: list[str]) -> dict[str, Any]:
    """``["size:5", "slippery:False"]`` -> ``{"size": 5, "slippery": False}`` (RL Zoo's
    ``--env-kwargs``; values that JSON cannot hold are refused, config.json records them)."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition(":")
        if not sep or not key.strip():
            raise CLIError(f"--env-kwargs {item!r} is not KEY:VALUE", "e.g. --env-kwargs size:5")
        value = parse_value(text)
        try:
            json.dumps(value, allow_nan=False)
        except (TypeError, ValueError):
            raise CLIError(
                f"--env-kwargs {item!r}: {value!r} is not plain data",
                "use numbers, true/false, text, lists or dicts",
            ) from None
        out[key.strip()] = value
    return out


def _check_flags(args: argparse.Namespace) -> str:
    if args.checkpoint_every is not None and args.checkpoint_every < 0:
        raise CLIError(
            f"--checkpoint-every must be >= 0, got {args.checkpoint_every}", "e.g. 10000"
        )
    if args.eval_freq < 0:
        raise CLIError(f"--eval-freq must be >= 0, got {args.eval_freq}", "e.g. 10000 (0: never)")
    if args.eval_episodes is None:
        args.eval_episodes = DEFAULT_EVAL_EPISODES
    if args.eval_episodes < 0:
        raise CLIError(f"--eval-episodes must be >= 0, got {args.eval_episodes}", "e.g. 10")
    if args.eval_freq > 0 and args.eval_episodes == 0:
        raise CLIError(
            "--eval-freq needs --eval-episodes of 1 or more, got 0", "e.g. --eval-episodes 5"
        )
    if args.progress != "auto":
        if args.progress == "bar" and importlib.util.find_spec("tqdm") is None:
            raise CLIError("--progress bar needs tqdm", 'pip install "palaestra[progress]"')
        return str(args.progress)
    return "bar" if importlib.util.find_spec("tqdm") is not None else "line"


def run(args: argparse.Namespace) -> int:
    """The ``train`` command."""
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
        if args.algo is None or args.env is None:
            raise CLIError("train needs ALGO and ENV", "e.g. palaestra train ppo CartPole-v1")
        spec, notes = resolve_spec(
            args.algo,
            args.env,
            args.preset,
            config=args.config,
            assignments=args.assignments,
            overrides={"env_kwargs": _env_kwargs(args.env_kwargs)} if args.env_kwargs else None,
            allow_import=args.allow_import,
            seed=args.seed,
            n_envs=args.n_envs,
            n_timesteps=args.timesteps,
            device=args.device,
        )
        run_dir = Path(args.out) if args.out else _default_out(spec.algo, spec.env_id)
        progress_mode = _check_flags(args)
        # a folder in use or holding a run: its error line
        run_ = open_run(spec, run_dir, eval_freq=args.eval_freq, eval_episodes=args.eval_episodes)
        shortfall = presets.measured_shortfall(spec.algo, spec.env_id, spec.preset, spec.seed)
        run_.notes[:0] = [*notes, *([shortfall] if shortfall else [])]
    for note in run_.notes:  # after every check: bad input gets its error line only
        eprint(f"note: {note}")
    return _train(args, run_, progress_mode)


def _train(args: argparse.Namespace, run_: Any, progress_mode: str) -> int:
    """Train with the live progress and the graceful stop on Ctrl-C/SIGTERM, then print the
    summary."""
    from palaestra.cli.progress import GracefulStop, LiveProgress  # lazy: import-time — torch

    spec, run_dir, model = run_.spec, run_.run_dir, run_.model
    total = run_.final_timesteps  # past spec.n_timesteps after a whole last rollout
    stop = GracefulStop()
    stop.finish_at = spec.n_timesteps  # a stop from there on lets the last update run
    callbacks: list[Any] = [stop]
    progress = None
    if progress_mode != "none":
        progress = LiveProgress(total, progress_mode, evaluation=run_.evaluation)
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
