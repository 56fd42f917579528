"""``palaestra train``: train an algorithm of ``settings.ALGOS`` from a preset, a config file
and ``--set`` overrides, into a run folder that ``eval``, ``record``, ``compare`` and
``--resume`` read.

Run folder: ``config.json`` (resolved settings), ``status.json`` (steps done, total, wall
time), ``progress.csv`` (SB3's log), ``episodes.csv`` (every episode: steps, return, length,
terminated, training seconds), ``model.zip``, ``replay_buffer.zip`` (DQN), ``checkpoints/``,
``learning_curve.png``, ``tb/`` (when tensorboard is installed).

The env comes from :mod:`palaestra.cli.pipeline` (SB3's Atari recipe when the settings say
``atari``), which ``eval`` and ``record`` use to rebuild it.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path
from typing import Any

from palaestra.cli import run_folder
from palaestra.cli import settings as settings_mod
from palaestra.cli.common import (
    CONFIG_FILE,
    EPISODES_FILE,
    MODEL_FILE,
    NORMALIZE_FILE,
    REPLAY_FILE,
    STATUS_FILE,
    CLIError,
    eprint,
    write_json,
)

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
    run_folder.add_allow_import(p, "--resume")
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


# -- settings ----------------------------------------------------------------------------------
def _new_run_config(args: argparse.Namespace) -> tuple[dict[str, Any], list[str]]:
    if args.algo is None or args.env is None:
        raise CLIError("train needs ALGO and ENV", "e.g. palaestra train ppo CartPole-v1")
    algo = settings_mod.check_algo(args.algo)
    import palaestra

    palaestra.spec(args.env)  # an unknown id fails here, with Gymnasium's "did you mean"
    settings, preset, notes = settings_mod.resolve_settings(
        algo, args.env, args.preset, args.config, args.assignments
    )
    for flag, key in (("n_envs", "n_envs"), ("timesteps", "n_timesteps"), ("seed", "seed")):
        if getattr(args, flag) is not None:
            settings[key] = getattr(args, flag)
    settings.setdefault("seed", None)
    settings_mod.check_settings(settings, args.env)
    config = {
        "algo": algo,
        "env_id": args.env,
        "preset": preset,
        **settings,
        "device": args.device,
        "palaestra_version": palaestra.__version__,
    }
    return config, notes


def _resumed_config(args: argparse.Namespace, run_dir: Path) -> dict[str, Any]:
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
    # Checked, and refused if it names a module the command line did not allow, before
    # check_settings below imports its env_wrapper.
    config = run_folder.read_run_config(
        run_dir / CONFIG_FILE, args.allow_import, run_folder.RESUME_KEYS
    )
    for key, value in (("algo", args.algo), ("env_id", args.env)):
        if value is not None and str(value).lower() != str(config.get(key)).lower():
            raise CLIError(
                f"{run_dir} is a run of {config.get(key)}, not {value}",
                f"palaestra train --resume {run_dir}",
            )
    if args.timesteps is not None:
        config["n_timesteps"] = args.timesteps
    settings_mod.check_settings(config, str(config.get("env_id")))
    return config


def _default_out(algo: str, env_id: str) -> Path:
    stamp = time.strftime("%Y%m%d-%H%M%S")
    base = Path("runs") / f"{algo}-{env_id.replace('/', '_')}-{stamp}"
    out, n = base, 1
    while out.exists():
        n += 1
        out = base.with_name(f"{base.name}-{n}")
    return out


# -- building ----------------------------------------------------------------------------------
def _make_env(config: dict[str, Any], seed: int | None, saved: Path | None = None) -> Any:
    """The run's vector env; ``saved``: the folder whose ``vecnormalize.npz`` to continue."""
    from palaestra.cli.pipeline import make_vec
    from palaestra.vec_env import VecNormalize

    venv = make_vec(config, config["n_envs"], seed)
    normalize = config.get("normalize") or False
    if normalize is False:
        return venv
    if saved is not None and (saved / NORMALIZE_FILE).is_file():
        return VecNormalize.load(str(saved / NORMALIZE_FILE), venv)
    kwargs = dict(normalize) if isinstance(normalize, dict) else {}
    kwargs.setdefault("gamma", config["hyperparams"].get("gamma", 0.99))
    return VecNormalize(venv, **kwargs)


def _resume(config: dict[str, Any], run_dir: Path) -> tuple[Any, str | None]:
    """The model and env of the newest complete checkpoint (or, for run folders written before
    checkpoints held the env, the run folder's own files); None when the resume is exact, else
    why it starts new episodes."""
    from palaestra.algos.model_io import ModelFileError
    from palaestra.cli.checkpoint import latest_checkpoint, load_env_state

    folder = latest_checkpoint(run_dir) or run_dir
    venv = _make_env(config, config["seed"], folder)
    inexact = load_env_state(folder, venv)
    cls = settings_mod.algo_class(config["algo"])
    try:
        model = cls.load(folder / MODEL_FILE, env=venv, device=config["device"])
        if config["algo"] in settings_mod.REPLAY_ALGOS and (folder / REPLAY_FILE).is_file():
            model.load_replay_buffer(folder / REPLAY_FILE)
    except FileNotFoundError:
        raise CLIError(f"{run_dir} has no {MODEL_FILE} to resume from", "check DIR") from None
    except (ModelFileError, ValueError) as exc:
        raise CLIError(f"cannot resume {run_dir}: {exc}", "start a new run") from None
    seed = config["seed"]
    if inexact and seed is not None:
        venv.seed(seed + model.num_timesteps)  # new episodes, not a replay of the first ones
    return model, inexact


def _make_model(config: dict[str, Any], venv: Any) -> Any:
    from palaestra import presets

    cls = settings_mod.algo_class(config["algo"])
    try:
        hyper = presets.resolve(config["hyperparams"])
        return cls(
            config["policy"],
            venv,
            seed=config["seed"],
            device=config["device"],
            verbose=0,
            **hyper,
        )
    except presets.PresetError as exc:
        raise CLIError(str(exc), "fix the setting") from None
    except TypeError as exc:
        if "does not support" not in str(exc):
            raise CLIError(
                f"invalid {config['algo']} settings: {exc}", "check the values"
            ) from None
        # Discrete-only (DQN) or Box-only (SAC, TD3, DDPG): PPO and A2C take both.
        other = "ppo" if config["algo"] in settings_mod.REPLAY_ALGOS else "another algorithm"
        raise CLIError(
            f"cannot train {config['algo']} on {config['env_id']}: {exc}", f"use {other}"
        ) from None
    except (ValueError, NotImplementedError, RuntimeError) as exc:
        raise CLIError(
            f"invalid {config['algo']} settings: {exc}", "check --set/--config values"
        ) from None


def _make_logger(run_dir: Path, verbose: bool) -> Any:
    from palaestra.algos.logger import HumanOutputFormat, Logger, TensorBoardOutputFormat
    from palaestra.cli.progress import AppendingCSV

    formats: list[Any] = [AppendingCSV(str(run_dir / "progress.csv"))]
    if importlib.util.find_spec("tensorboard") is not None:
        formats.append(TensorBoardOutputFormat(str(run_dir / "tb")))
    if verbose:
        formats.append(HumanOutputFormat(sys.stdout))
    return Logger(str(run_dir), formats)


def _progress_mode(requested: str) -> str:
    if requested != "auto":
        if requested == "bar" and importlib.util.find_spec("tqdm") is None:
            raise CLIError("--progress bar needs tqdm", 'pip install "palaestra[progress]"')
        return requested
    return "bar" if importlib.util.find_spec("tqdm") is not None else "line"


# -- the command -------------------------------------------------------------------------------
def run(args: argparse.Namespace) -> int:
    """The ``train`` command."""
    resume = args.resume is not None
    notes: list[str] = []
    if resume:
        run_dir = Path(args.resume)
        config = _resumed_config(args, run_dir)
        status = run_folder.read_status(run_dir / STATUS_FILE)  # before any env or model
    else:
        if args.allow_import:
            raise CLIError(
                "--allow-import applies to --resume (a new run imports what its --config "
                "and --set name)",
                "drop --allow-import",
            )
        config, notes = _new_run_config(args)
        run_dir = Path(args.out) if args.out else _default_out(config["algo"], config["env_id"])
        if (run_dir / CONFIG_FILE).exists():
            raise CLIError(
                f"{run_dir} already holds a run", f"choose another --out, or --resume {run_dir}"
            )
        status = {"num_timesteps": 0, "wall_time_s": 0.0}
    if args.checkpoint_every is not None and args.checkpoint_every < 0:
        raise CLIError(
            f"--checkpoint-every must be >= 0, got {args.checkpoint_every}", "e.g. 10000"
        )
    if args.eval_episodes < 0:
        raise CLIError(f"--eval-episodes must be >= 0, got {args.eval_episodes}", "e.g. 10")
    progress_mode = _progress_mode(args.progress)

    import torch

    torch.set_num_threads(1)  # the small nets here are fastest on one thread
    total = config["n_timesteps"]
    if resume:
        model, inexact = _resume(config, run_dir)
        if model.num_timesteps >= total:
            raise CLIError(
                f"{run_dir} already trained {model.num_timesteps:,} of its {total:,} steps",
                f"pass --timesteps larger than {model.num_timesteps} to train further",
            )
        if inexact:
            notes.append(f"{inexact}: the resume starts new episodes (not an exact resume)")
        from palaestra.cli.checkpoint import trim_logs

        trim_logs(run_dir, model.num_timesteps)  # rows of a run that died past its checkpoint
        if total > int(status.get("total_timesteps", total)):
            notes.append(
                f"extending the run from {status['total_timesteps']:,} to {total:,} steps: the "
                f"schedules continue as a {total:,}-step run would from step "
                f"{model.num_timesteps:,} (progress remaining "
                f"{1 - model.num_timesteps / total:.3f})"
            )
    else:
        model = _make_model(config, _make_env(config, config["seed"]))
    for note in notes:  # after every check: bad input gets its error line only
        eprint(f"note: {note}")
    run_dir.mkdir(parents=True, exist_ok=True)
    write_json(run_dir / CONFIG_FILE, config)
    return _train(args, config, status, model, run_dir, total, resume, progress_mode)


def _train(
    args: argparse.Namespace,
    config: dict[str, Any],
    status: dict[str, Any],
    model: Any,
    run_dir: Path,
    total: int,
    resume: bool,
    progress_mode: str,
) -> int:
    """Train to ``total`` steps, ending ``learn`` at each checkpoint to write it between two
    consistent steps and continuing (exactly: see :mod:`palaestra.cli.checkpoint`)."""
    from palaestra.algos.callbacks import CallbackList
    from palaestra.cli.checkpoint import (
        CheckpointDue,
        checkpoint_steps,
        latest_checkpoint,
        publish,
        write_checkpoint,
    )
    from palaestra.cli.progress import EpisodeLog, GracefulStop, LiveProgress
    from palaestra.cli.run_files import print_summary, write_status

    model.set_logger(_make_logger(run_dir, args.verbose))
    episodes = EpisodeLog(run_dir / EPISODES_FILE, float(status.get("wall_time_s", 0.0)))
    stop = GracefulStop()
    stop.finish_at = total
    every = args.checkpoint_every if args.checkpoint_every is not None else total // 10
    due = CheckpointDue(every, total)
    callbacks: list[Any] = [episodes, stop, due]
    progress = None
    if progress_mode != "none":
        progress = LiveProgress(total, progress_mode)
        callbacks.append(progress)
    callbacks.extend(EXTRA_CALLBACKS)
    start_steps = model.num_timesteps
    eprint(
        f"training {config['algo']} on {config['env_id']} "
        f"({model.n_envs} env{'s' * (model.n_envs > 1)}, "
        f"{'preset ' + config['preset'] if config.get('preset') else 'no preset'}) "
        f"{'from step ' + format(start_steps, ',') + ' ' if resume else ''}to {total:,} steps "
        f"-> {run_dir}"
    )
    wall_before = float(status.get("wall_time_s", 0.0))
    saved = latest_checkpoint(run_dir)  # what a stop at once leaves to resume from
    at_once = stopped = False
    stop.install()
    start = time.perf_counter()
    try:
        first = not resume
        while model.num_timesteps < total:
            due.plan(model.num_timesteps)
            model.learn(
                total - model.num_timesteps,
                callback=CallbackList(callbacks),
                reset_num_timesteps=first,
            )
            first = False
            if model.num_timesteps >= total or not due.reached(model.num_timesteps):
                stopped = model.num_timesteps < total  # Ctrl-C, SIGTERM or a callback
                break
            saved, _ = write_checkpoint(model, run_dir, config["algo"])
            wall = wall_before + time.perf_counter() - start
            write_status(
                run_dir, "running", model.num_timesteps, total, wall, _relative(saved, run_dir)
            )
    except KeyboardInterrupt:  # a second Ctrl-C: the model may be mid-update, so not saved
        at_once = True
    finally:
        seconds = time.perf_counter() - start
        stop.uninstall()
        episodes.close()
        if progress is not None:
            progress.close()
        model.logger.close()
    wall = wall_before + seconds
    if at_once:
        steps = checkpoint_steps(saved) if saved else 0
        write_status(run_dir, "interrupted", steps, total, wall, _relative(saved, run_dir))
        where = f"the checkpoint at {steps:,} steps" if saved else "nothing (no checkpoint yet)"
        eprint(
            f"palaestra: stopped at once at {model.num_timesteps:,}/{total:,} steps; "
            f"--resume continues from {where} (palaestra train --resume {run_dir})"
        )
        return stop.exit_code
    folder, _ = write_checkpoint(model, run_dir, config["algo"])
    publish(folder, run_dir)
    state = "interrupted" if stopped else "finished"
    write_status(run_dir, state, model.num_timesteps, total, wall, _relative(folder, run_dir))
    if stopped:
        eprint(
            f"palaestra: interrupted at {model.num_timesteps:,}/{total:,} steps; checkpoint "
            f"saved in {run_dir} (resume with: palaestra train --resume {run_dir})"
        )
        return stop.exit_code  # 130 after Ctrl-C, 143 after SIGTERM
    print_summary(
        args.eval_episodes, config, model, run_dir, model.num_timesteps - start_steps, seconds
    )
    return 0


def _relative(folder: Path | None, run_dir: Path) -> str | None:
    return None if folder is None else folder.relative_to(run_dir).as_posix()
