"""Train a :class:`~palaestra.runs.spec.RunSpec` into a run folder, and resume one.

``train_run(spec, "runs/x")`` is what ``palaestra train`` does: build the env recipe and the
model, train to the budget while writing ``progress.csv`` and ``episodes.csv``, save a complete
checkpoint every ``checkpoint_every`` steps (ending ``learn`` between two consistent steps and
continuing exactly: :mod:`palaestra.runs.checkpoint`), publish the final model, replay buffer and
normalization statistics, and write ``status.json``. ``resume_run("runs/x")`` continues from
the newest checkpoint, exactly where the run stopped when the checkpoint holds the env state.
``eval_freq``/``eval_episodes`` add evaluations during training (``evaluations.csv``,
``best_model.zip``: :mod:`palaestra.runs.periodic_eval`), recorded in ``config.json`` so that a
resume continues them.

For the notes a command prints between building and training (a resume that starts new
episodes, an extended budget) use the two steps: :func:`open_run`/:func:`open_resume`, then
:meth:`Run.train`.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from palaestra import presets
from palaestra.error import UnsupportedSpace
from palaestra.runs import folder as run_folder
from palaestra.runs import run_callbacks, settings
from palaestra.runs.errors import RunError, one_line
from palaestra.runs.files import (
    CONFIG_FILE,
    EPISODES_FILE,
    MODEL_FILE,
    NORMALIZE_FILE,
    REPLAY_ALGOS,
    REPLAY_FILE,
    STATUS_FILE,
    write_json,
    write_status,
)
from palaestra.runs.lock import FolderLock
from palaestra.runs.recipe import make_vec
from palaestra.runs.settings import algo_class
from palaestra.runs.spec import RunSpec

if TYPE_CHECKING:
    from palaestra.runs.periodic_eval import PeriodicEvaluation

__all__ = [
    "Run",
    "TrainResult",
    "make_env",
    "make_model",
    "open_resume",
    "open_run",
    "resume_run",
    "train_run",
]


@dataclasses.dataclass
class TrainResult:
    """What a training session left: ``status`` is ``"finished"`` or ``"interrupted"`` (a
    callback stopped ``learn``; the checkpoint saved then is what a resume continues)."""

    run_dir: Path
    spec: RunSpec
    status: str
    num_timesteps: int
    total_timesteps: int
    session_steps: int  # steps trained by this call
    session_seconds: float  # wall-clock seconds of this call's training
    wall_time_s: float  # of the whole run, earlier sessions included
    model: Any


def make_env(spec: RunSpec, seed: int | None, saved: Path | None = None) -> Any:
    """The run's training vector env (under ``VecNormalize`` when the spec says
    ``normalize``); ``saved``: the folder whose ``vecnormalize.npz`` to continue."""
    from palaestra.vec_env import VecNormalize  # lazy: import-time — multiprocessing

    config = spec.to_config()
    venv = make_vec(config, spec.n_envs, seed)
    if spec.normalize is False:
        return venv
    if saved is not None and (saved / NORMALIZE_FILE).is_file():
        return VecNormalize.load(str(saved / NORMALIZE_FILE), venv)
    kwargs = dict(spec.normalize) if isinstance(spec.normalize, dict) else {}
    kwargs.setdefault("gamma", spec.hyperparams.get("gamma", 0.99))
    return VecNormalize(venv, **kwargs)


def make_model(spec: RunSpec, venv: Any) -> Any:
    """The spec's algorithm on ``venv`` (``RunError`` naming the setting a constructor
    refused)."""
    cls = algo_class(spec.algo)
    try:
        hyper = presets.resolve(spec.hyperparams)
        return cls(spec.policy, venv, seed=spec.seed, device=spec.device, verbose=0, **hyper)
    except presets.PresetError as exc:
        raise RunError(str(exc), "fix the setting") from None
    except UnsupportedSpace as exc:
        # Discrete-only (DQN) or Box-only (SAC, TD3, DDPG): PPO and A2C take both.
        other = "ppo" if spec.algo in REPLAY_ALGOS else "another algorithm"
        raise RunError(
            f"cannot train {spec.algo} on {spec.env_id}: {exc}", f"use {other}"
        ) from None
    except TypeError as exc:
        raise RunError(f"invalid {spec.algo} settings: {exc}", "check the values") from None
    except (ValueError, NotImplementedError, RuntimeError) as exc:
        raise RunError(
            f"invalid {spec.algo} settings: {exc}", "check --set/--config values"
        ) from None


def _logger(run_dir: Path, verbose: bool) -> Any:
    from palaestra.algos.common.logger import (  # lazy: import-time — torch
        HumanOutputFormat,
        Logger,
        TensorBoardOutputFormat,
    )
    from palaestra.runs.logs import AppendingCSV  # lazy: import-time — torch

    formats: list[Any] = [AppendingCSV(str(run_dir / "progress.csv"))]
    if importlib.util.find_spec("tensorboard") is not None:
        formats.append(TensorBoardOutputFormat(str(run_dir / "tb")))
    if verbose:
        formats.append(HumanOutputFormat(sys.stdout))
    return Logger(str(run_dir), formats)


@dataclasses.dataclass
class Run:
    """A run folder with its model built, ready to train (:func:`open_run`,
    :func:`open_resume`). It holds the folder's lock (:mod:`palaestra.runs.lock`) until
    :meth:`train` ends or :meth:`close` is called (also a context manager), so no other
    process writes the folder meanwhile."""

    spec: RunSpec
    run_dir: Path
    model: Any
    resumed: bool
    wall_before: float  # training seconds of earlier sessions
    notes: list[str]
    evaluation: PeriodicEvaluation | None = None  # evaluations during training

    @property
    def final_timesteps(self) -> int:
        """The step count training will end at: ``spec.n_timesteps`` rounded up to whole
        rollouts (PPO, A2C) or ``train_freq`` collections (off-policy), as SB3's loops do."""
        return int(self.model.final_timesteps(self.spec.n_timesteps))

    lock: FolderLock | None = dataclasses.field(default=None, repr=False)

    def close(self) -> None:
        """Release the run folder's lock (idempotent; :meth:`train` does it when it ends)."""
        if self.lock is not None:
            self.lock.release()

    def __enter__(self) -> Run:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def train(
        self,
        callbacks: Sequence[Any] = (),
        checkpoint_every: int | None = None,
        verbose: bool = False,
        evaluate_every: int = 0,
        on_evaluate: Callable[[Any], bool] | None = None,
    ) -> TrainResult:
        """Train to ``spec.n_timesteps``, with a complete checkpoint every
        ``checkpoint_every`` steps (default: a tenth of the budget; 0: only at the end).
        ``on_evaluate(model)`` runs every ``evaluate_every`` steps between two whole steps
        (``learn`` ends there and continues exactly, as at a checkpoint); returning False stops
        training as a callback would (a search pruning a run).

        A callback returning False stops training: the run is saved and its status is
        ``"interrupted"``. A ``KeyboardInterrupt`` inside ``learn`` (the model may be
        mid-update) saves nothing new: ``status.json`` points at the last checkpoint, and the
        exception propagates."""
        from palaestra.algos.common.callbacks import CallbackList  # lazy: import-time — torch
        from palaestra.runs.checkpoint import (  # lazy: import-time — torch
            CheckpointDue,
            checkpoint_steps,
            latest_checkpoint,
            publish,
            write_checkpoint,
        )
        from palaestra.runs.logs import EpisodeLog  # lazy: import-time — torch

        if checkpoint_every is not None and checkpoint_every < 0:
            self.close()
            raise RunError(f"checkpoint_every must be >= 0, got {checkpoint_every}", "e.g. 10000")
        model, run_dir, total = self.model, self.run_dir, self.spec.n_timesteps
        model.set_logger(_logger(run_dir, verbose))
        episodes = EpisodeLog(run_dir / EPISODES_FILE, self.wall_before)
        every = checkpoint_every if checkpoint_every is not None else total // 10
        due = CheckpointDue(every, total)
        evaluation = CheckpointDue(evaluate_every if on_evaluate is not None else 0, total)
        periodic = [] if self.evaluation is None else [self.evaluation]
        callbacks = [*run_callbacks.build_callbacks(self.spec.to_config()), *callbacks]
        start_steps = model.num_timesteps
        saved = latest_checkpoint(run_dir)  # what a stop at once leaves to resume from
        stopped = False
        start = time.perf_counter()

        def leave(state: str, error: str | None = None) -> None:
            """``status.json`` for a session that ends early: it points at the checkpoint
            a resume continues, never at what was half-done."""
            wall = self.wall_before + time.perf_counter() - start
            steps = checkpoint_steps(saved) if saved else 0
            write_status(run_dir, state, steps, total, wall, _rel(saved, run_dir), error)

        try:
            try:
                # Inside the try: an eval env that fails to build still releases the lock
                # and leaves a "failed" status, as a failure in training does.
                for each in periodic:
                    each.open(self.spec.to_config(), model)
                first = not self.resumed
                while model.num_timesteps < total:
                    due.plan(model.num_timesteps)
                    evaluation.plan(model.num_timesteps)
                    model.learn(
                        total - model.num_timesteps,
                        callback=CallbackList([episodes, due, evaluation, *periodic, *callbacks]),
                        reset_num_timesteps=first,
                    )
                    first = False
                    steps = model.num_timesteps
                    checkpoint, evaluate = due.reached(steps), evaluation.reached(steps)
                    if steps >= total or not (checkpoint or evaluate):
                        stopped = steps < total  # a callback stopped learn
                        break
                    if checkpoint:
                        saved, _ = write_checkpoint(model, run_dir, self.spec.algo)
                        wall = self.wall_before + time.perf_counter() - start
                        write_status(run_dir, "running", steps, total, wall, _rel(saved, run_dir))
                    if evaluate and on_evaluate is not None and not on_evaluate(model):
                        stopped = True
                        break
            finally:
                seconds = time.perf_counter() - start
                episodes.close()
                for each in periodic:
                    each.close()
                model.logger.close()
            folder, _ = write_checkpoint(model, run_dir, self.spec.algo)
            publish(folder, run_dir)
            state = "interrupted" if stopped else "finished"
            wall = self.wall_before + seconds
            write_status(run_dir, state, model.num_timesteps, total, wall, _rel(folder, run_dir))
        except KeyboardInterrupt:  # the model may be mid-update: the last checkpoint stands
            _quietly(leave, "interrupted")
            raise
        except BaseException as exc:  # a disk that filled up, an env that raised, sys.exit
            _quietly(leave, "failed", one_line(exc))
            raise
        finally:
            self.close()  # the folder is complete: another command may write it now
        return TrainResult(
            run_dir,
            self.spec,
            state,
            model.num_timesteps,
            total,
            model.num_timesteps - start_steps,
            seconds,
            wall,
            model,
        )


def _quietly(write: Callable[..., None], *args: Any) -> None:
    """Record how a session ended, unless that write fails too (the disk that filled up):
    the error being raised is the one to report."""
    try:
        write(*args)
    except OSError:
        pass


def _rel(folder: Path | None, run_dir: Path) -> str | None:
    return None if folder is None else folder.relative_to(run_dir).as_posix()


def _one_thread() -> None:
    import torch

    torch.set_num_threads(1)  # the small nets here are fastest on one thread


def open_run(
    spec: RunSpec, run_dir: str | Path, *, eval_freq: int = 0, eval_episodes: int = 10
) -> Run:
    """Check ``spec``, lock ``run_dir`` (``RunError`` naming the PID of a process that holds
    it), build its env and model, and write ``config.json`` into ``run_dir`` (``RunError``
    when ``run_dir`` already holds a run). ``eval_freq`` > 0: evaluate ``eval_episodes``
    deterministic episodes every ``eval_freq`` env steps counted over all envs
    (:mod:`palaestra.runs.periodic_eval`)."""
    from palaestra.runs.periodic_eval import (  # lazy: import-time — torch
        EvalSchedule,
        PeriodicEvaluation,
    )

    run_dir = Path(run_dir)
    spec.validate()
    schedule = EvalSchedule.from_arguments(eval_freq, eval_episodes)
    existed = run_dir.exists()
    lock = FolderLock(run_dir).acquire()  # before the check: two processes cannot both pass it
    try:
        if (run_dir / CONFIG_FILE).exists():
            raise RunError(
                f"{run_dir} already holds a run", f"choose another --out, or --resume {run_dir}"
            )
        _one_thread()
        model = make_model(spec, make_env(spec, spec.seed))
        config = spec.to_config()
        if schedule is not None:
            config["evaluation"] = schedule.to_config()
        write_json(run_dir / CONFIG_FILE, config)
    except BaseException:
        lock.release()
        if not existed:  # bad settings leave no folder behind
            try:
                run_dir.rmdir()
            except OSError:
                pass
        raise
    run = Run(spec, run_dir, model, False, 0.0, [], lock=lock)
    if schedule is not None:
        run.evaluation = PeriodicEvaluation(run_dir, schedule)
    run.notes.extend(_rounding_note(run))
    return run


def _rounding_note(run: Run) -> list[str]:
    """The note saying that training ends past ``n_timesteps``, and where (or nothing)."""
    from palaestra.algos.common.off_policy import OffPolicyAlgorithm  # lazy: import-time — torch
    from palaestra.algos.common.on_policy import OnPolicyAlgorithm  # lazy: import-time — torch

    model, total, end = run.model, run.spec.n_timesteps, run.final_timesteps
    name, n_envs = run.spec.algo.upper(), model.n_envs
    if isinstance(model, OffPolicyAlgorithm) and model.train_freq[1] == "episode":
        return [
            f"{name} collects whole episodes between updates (train_freq "
            f"{model.train_freq[0]} episode): the run ends when the episodes under way at "
            f"{total:,} steps end"
        ]
    if end == total:
        return []
    if isinstance(model, OnPolicyAlgorithm):
        how = f"whole rollouts of n_steps {model.n_steps} x {n_envs} envs"
        chunk = model.n_steps * n_envs
    elif isinstance(model, OffPolicyAlgorithm):
        how = f"whole collections of train_freq {model.train_freq[0]} x {n_envs} envs"
        chunk = model.train_freq[0] * n_envs
    else:
        how, chunk = f"steps of all {n_envs} envs at once", n_envs
    return [f"{name} trains on {how} = {chunk:,} steps: the run ends at {end:,}, not {total:,}"]


def open_resume(
    run_dir: str | Path,
    n_timesteps: int | None = None,
    allow_import: Sequence[str] = (),
    expect: dict[str, str] | None = None,
) -> Run:
    """The run in ``run_dir`` with the model and env of its newest complete checkpoint (a
    resume is exact when the checkpoint holds the env's state; ``Run.notes`` says when it is
    not). ``n_timesteps`` extends the budget; ``allow_import``: the modules its config may
    import; ``expect``: ``{"algo": ..., "env_id": ...}`` the caller believes it resumes.
    The folder is locked as :func:`open_run` locks it."""
    run_dir = Path(run_dir)
    # A missing folder is read_run_config's error to report; an existing one is locked first.
    lock = FolderLock(run_dir).acquire() if run_dir.is_dir() else None
    try:
        run = _open_resume(run_dir, n_timesteps, allow_import, expect)
    except BaseException:
        if lock is not None:
            lock.release()
        raise
    run.lock = lock
    return run


def _open_resume(
    run_dir: Path,
    n_timesteps: int | None,
    allow_import: Sequence[str],
    expect: dict[str, str] | None,
) -> Run:
    from palaestra.algos.common.model_io import ModelFileError  # lazy: import-time — torch
    from palaestra.runs.checkpoint import (  # lazy: import-time — torch
        latest_checkpoint,
        load_env_state,
        trim_logs,
    )
    from palaestra.runs.periodic_eval import (  # lazy: import-time — torch
        EvalSchedule,
        PeriodicEvaluation,
        best_return,
    )

    config = run_folder.read_run_config(run_dir / CONFIG_FILE, allow_import, run_folder.RESUME_KEYS)
    for key, value in (expect or {}).items():
        if value is not None and str(value).lower() != str(config.get(key)).lower():
            raise RunError(
                f"{run_dir} is a run of {config.get(key)}, not {value}",
                f"palaestra train --resume {run_dir}",
            )
    if n_timesteps is not None:
        config["n_timesteps"] = n_timesteps
    schedule = None
    if "evaluation" in config:
        schedule = EvalSchedule.from_config(config["evaluation"], str(run_dir / CONFIG_FILE))
    settings.check_settings(config, str(config.get("env_id")))
    status = run_folder.read_status(run_dir / STATUS_FILE)  # before any env or model
    spec = RunSpec.from_config(config, str(run_dir / CONFIG_FILE))
    _one_thread()
    checkpoint = latest_checkpoint(run_dir) or run_dir
    venv = make_env(spec, spec.seed, checkpoint)
    inexact = load_env_state(checkpoint, venv)
    try:
        model = settings.algo_class(spec.algo).load(
            checkpoint / MODEL_FILE, env=venv, device=spec.device
        )
        if spec.algo in REPLAY_ALGOS and (checkpoint / REPLAY_FILE).is_file():
            # an exact resume continues the saved episodes; where learn() resets the env
            # instead, a HerReplayBuffer ends its open episodes itself
            model.load_replay_buffer(checkpoint / REPLAY_FILE, truncate_last_traj=False)
    except FileNotFoundError:
        raise RunError(f"{run_dir} has no {MODEL_FILE} to resume from", "check DIR") from None
    except (ModelFileError, ValueError) as exc:
        raise RunError(f"cannot resume {run_dir}: {exc}", "start a new run") from None
    if inexact and spec.seed is not None:
        venv.seed(spec.seed + model.num_timesteps)  # new episodes, not a replay of the first ones
    total = spec.n_timesteps
    if model.num_timesteps >= total:
        raise RunError(
            f"{run_dir} already trained {model.num_timesteps:,} of its {total:,} steps",
            f"pass --timesteps larger than {model.num_timesteps} to train further",
        )
    notes = []
    if inexact:
        notes.append(f"{inexact}: the resume starts new episodes (not an exact resume)")
    trim_logs(run_dir, model.num_timesteps)  # rows of a run that died past its checkpoint
    if total > int(status.get("total_timesteps", total)):
        notes.append(
            f"extending the run from {status['total_timesteps']:,} to {total:,} steps: the "
            f"schedules continue as a {total:,}-step run would from step "
            f"{model.num_timesteps:,} (progress remaining {1 - model.num_timesteps / total:.3f})"
        )
    write_json(run_dir / CONFIG_FILE, {**config, "n_timesteps": total})
    run = Run(spec, run_dir, model, True, float(status.get("wall_time_s", 0.0)), notes)
    if schedule is not None:  # the rows past the checkpoint are gone: their steps run again
        best = best_return(run_dir)
        run.evaluation = PeriodicEvaluation(run_dir, schedule, best)
        period = schedule.period(model.n_envs)
        after = (model.num_timesteps // period + 1) * period
        notes.append(
            f"evaluating every {period:,} steps on {schedule.episodes} episodes as before: "
            f"next at {after:,} steps; best mean return so far "
            + (f"{best:.2f}" if best > -math.inf else "none (no evaluation yet)")
        )
    notes.extend(_rounding_note(run))
    return run


def train_run(
    spec: RunSpec,
    run_dir: str | Path,
    callbacks: Sequence[Any] = (),
    checkpoint_every: int | None = None,
    verbose: bool = False,
    *,
    eval_freq: int = 0,
    eval_episodes: int = 10,
) -> TrainResult:
    """Train ``spec`` into the new run folder ``run_dir``: ``palaestra train`` as a call
    (``eval_freq``, ``eval_episodes``: evaluations during training, see :func:`open_run`)."""
    run = open_run(spec, run_dir, eval_freq=eval_freq, eval_episodes=eval_episodes)
    return run.train(callbacks, checkpoint_every, verbose)


def resume_run(
    run_dir: str | Path,
    n_timesteps: int | None = None,
    allow_import: Sequence[str] = (),
    callbacks: Sequence[Any] = (),
    checkpoint_every: int | None = None,
    verbose: bool = False,
) -> TrainResult:
    """Continue the run in ``run_dir`` (to ``n_timesteps`` when given), its evaluations during
    training included: ``palaestra train --resume`` as a call."""
    run = open_resume(run_dir, n_timesteps, allow_import)
    return run.train(callbacks, checkpoint_every, verbose)
