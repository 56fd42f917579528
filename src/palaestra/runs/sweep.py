"""Hyperparameter search with Optuna, each trial scored over several seeds, locally or on Ray.

A search space (:mod:`palaestra.runs.space`) maps hyperparameter names (the algorithm's
constructor keywords, or ``n_envs``; dotted names reach inside dicts:
``policy_kwargs.net_arch``) to a list of choices or to a range ``{low: ..., high: ..., log:
true|false, step: ...}`` (integer bounds give an integer range)::

    learning_rate: {low: 1.0e-4, high: 3.0e-3, log: true}
    n_steps: [64, 128, 256]
    policy_kwargs.net_arch: [[64, 64], [128, 128]]

A trial samples one setting (TPE by default), trains it on each of the seeds on top of the
preset, and scores it by the mean over seeds of a deterministic evaluation at the end. The
first seed's run is evaluated ``evaluations`` times along the way; those values feed the pruner
(median by default), which stops a trial that is behind the others at the same step before its
other seeds train. Trials run one after another in this process, or as Ray tasks (one CPU
each). The study lives in ``study.db`` (SQLite) in the sweep folder, or in the database at
``storage`` (needed when the workers run on other machines): a sweep stopped and started again
with the same command continues it, losing at most the trials that were running.

The sweep folder: ``study.db``, ``trials/<n>/seed<s>/`` (each a run folder),
``trials.csv`` (every trial, best first), ``best.yaml`` (the best settings: ``palaestra train
ALGO ENV --config best.yaml``), ``history.png`` and ``importance.png``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import shutil
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from palaestra.error import dependency_not_installed
from palaestra.runs.errors import RunError, first_line, one_line
from palaestra.runs.evaluation import evaluate_run
from palaestra.runs.files import note
from palaestra.runs.folder import check_inside
from palaestra.runs.grid import check_backend, ray_session
from palaestra.runs.lock import FolderLock
from palaestra.runs.space import Param, distributions, settings_of
from palaestra.runs.spec import RunSpec, resolve_spec
from palaestra.runs.sweep_report import write_outputs
from palaestra.runs.training import open_run

__all__ = ["SweepResult", "run_sweep", "run_trial"]

STUDY_FILE = "study.db"
EVAL_SEED = 10_000  # evaluation episodes of seed s start from EVAL_SEED + s


# -- one trial ---------------------------------------------------------------------------------
def _evaluate(run: Any, episodes: int) -> float:

    seed = EVAL_SEED + (run.spec.seed or 0)
    result = evaluate_run(run.run_dir, episodes, seed=seed, model=run.model, spec=run.spec)
    return result.mean_return


def run_trial(
    specs_json: Sequence[str],
    folder: str,
    evaluations: int,
    eval_episodes: int,
    report: Callable[[float, int], bool] | None = None,
    callbacks: Sequence[Any] = (),
) -> dict[str, Any]:
    """Train one trial's runs (one per seed) into ``folder``/seed<s> and score them:
    ``{"state": "complete"|"pruned"|"interrupted", "value", "values", "seconds", "reason"}``.
    ``report(value, step)`` hears the first run's evaluations and returns False to prune the
    trial; ``callbacks`` go to every run's ``learn`` (one that stops it, as a Ctrl-C or
    SIGTERM handler does, ends the trial ``"interrupted"``). ``reason`` says why a trial
    ended early: where it was pruned or stopped."""
    start = time.perf_counter()
    values: list[float] = []
    for i, text in enumerate(specs_json):
        spec = RunSpec.from_json(text)
        run_dir = Path(folder) / f"seed{spec.seed}"
        if run_dir.exists():  # an attempt that was killed: this trial starts again
            shutil.rmtree(run_dir)
        run = open_run(spec, run_dir)
        pruned: tuple[int, float] | None = None  # (step, evaluation) where the pruner stopped it
        if i == 0 and report is not None and evaluations > 0:
            every = max(1, spec.n_timesteps // (evaluations + 1))

            def check(model: Any, run: Any = run) -> bool:
                nonlocal pruned
                value, step = _evaluate(run, eval_episodes), int(model.num_timesteps)
                keep = report(value, step)
                pruned = None if keep else (step, value)
                return keep

            result = run.train(
                callbacks, checkpoint_every=0, evaluate_every=every, on_evaluate=check
            )
        else:
            result = run.train(callbacks, checkpoint_every=0)
        if pruned is not None:
            step, value = pruned
            reason = (
                f"pruned at step {step:,} of {spec.n_timesteps:,}: seed {spec.seed}'s "
                f"evaluation {value:.2f} was behind the other trials' at that step"
            )
            return _ended("pruned", values, start, reason)
        if result.status == "interrupted":  # a callback stopped learn (Ctrl-C, SIGTERM)
            reason = (
                f"stopped at step {result.num_timesteps:,} of {spec.n_timesteps:,} "
                f"(seed {spec.seed})"
            )
            return _ended("interrupted", values, start, reason)
        values.append(_evaluate(run, eval_episodes))
    mean = float(sum(values) / len(values))
    return {
        "state": "complete",
        "value": mean,
        "values": values,
        "seconds": _since(start),
        "reason": None,
    }


def _ended(state: str, values: list[float], start: float, reason: str) -> dict[str, Any]:
    return {
        "state": state,
        "value": None,
        "values": values,
        "seconds": _since(start),
        "reason": reason,
    }


def _since(start: float) -> float:
    return round(time.perf_counter() - start, 3)


def _remote_trial(
    specs_json: list[str],
    folder: str,
    evaluations: int,
    eval_episodes: int,
    storage_url: str,
    study_name: str,
    trial_id: int,
    pruner: dict[str, Any],
) -> dict[str, Any]:
    """A trial as a Ray task: it reports to the study through the shared storage."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.load_study(
        study_name=study_name, storage=storage_url, pruner=_make_pruner(pruner)
    )
    trial = optuna.trial.Trial(study, trial_id)
    return run_trial(specs_json, folder, evaluations, eval_episodes, _reporter(trial))


def _reporter(trial: Any) -> Callable[[float, int], bool]:
    def report(value: float, step: int) -> bool:
        trial.report(value, step)
        return not trial.should_prune()

    return report


def _make_pruner(settings: dict[str, Any]) -> Any:
    import optuna

    if not settings.get("enabled", True):
        return optuna.pruners.NopPruner()
    return optuna.pruners.MedianPruner(n_startup_trials=settings.get("startup", 3))


# -- the study ---------------------------------------------------------------------------------
@dataclasses.dataclass
class SweepResult:
    """Every trial of the study (best first), the best settings and the files written."""

    folder: Path
    trials: list[dict[str, Any]]
    best: dict[str, Any] | None  # the best trial's row
    best_file: Path | None
    ran: int  # trials run by this call
    stopped: str | None = None  # why this call stopped early ("interrupted by SIGTERM"), if so


def _storage(url: str | None, folder: Path) -> tuple[Any, str]:
    import optuna

    url = url or f"sqlite:///{(folder / STUDY_FILE).resolve()}"
    try:
        storage = optuna.storages.RDBStorage(url, engine_kwargs=_engine_kwargs(url))
    except Exception as exc:  # sqlalchemy's errors: a bad URL, a missing driver, no server
        raise RunError(
            f"cannot open the study storage {url!r}: {first_line(exc)}",
            "pass --storage sqlite:///PATH or a database URL the workers can reach",
            code=1,
        ) from None
    return storage, url


def _engine_kwargs(url: str) -> dict[str, Any]:
    # Several processes write one SQLite file: wait for its lock rather than fail at once.
    return {"connect_args": {"timeout": 60}} if url.startswith("sqlite") else {}


def _mark_interrupted(storage: Any, study: Any) -> int:
    """Trials a killed sweep left running: marked failed (and ``interrupted``, with the
    reason) so that they are run again; their count."""
    from optuna.trial import TrialState

    lost = study.get_trials(deepcopy=False, states=(TrialState.RUNNING,))
    for trial in lost:
        storage.set_trial_user_attr(trial._trial_id, "interrupted", True)
        storage.set_trial_user_attr(
            trial._trial_id, "reason", "interrupted: the sweep was killed while it ran"
        )
        storage.set_trial_state_values(trial._trial_id, state=TrialState.FAIL)
    return len(lost)


def _finished(study: Any) -> int:
    from optuna.trial import TrialState

    done = 0
    for trial in study.get_trials(deepcopy=False):
        if trial.state in (TrialState.COMPLETE, TrialState.PRUNED):
            done += 1
        elif trial.state == TrialState.FAIL and not trial.user_attrs.get("interrupted"):
            done += 1
    return done


def run_sweep(
    space: Mapping[str, Param],
    algo: str,
    env_id: str,
    trials: int,
    seeds: int = 1,
    out: str | Path = "sweep",
    n_timesteps: int | None = None,
    preset: str | None = None,
    backend: str = "local",
    address: str | None = None,
    storage: str | None = None,
    evaluations: int = 4,
    eval_episodes: int = 10,
    sampler_seed: int | None = 0,
    prune: bool = True,
    on_trial: Callable[[dict[str, Any]], None] | None = None,
    callbacks: Sequence[Any] = (),
    stop_requested: Callable[[], str | None] | None = None,
) -> SweepResult:
    """Run the search until the study holds ``trials`` finished trials (see the module's
    docstring); continues the study already in ``out`` (or at ``storage``). The folder is
    locked for the call (:mod:`palaestra.runs.lock`).

    ``callbacks`` go to the ``learn`` of every local trial; ``stop_requested()`` returns why
    the search should stop (``"interrupted by SIGTERM"``) or None: a trial that a callback
    stopped, and then the search, end there, the trial recorded as interrupted (run again
    by the next call) and the outputs written; ``SweepResult.stopped`` holds the reason."""
    try:
        import optuna
    except ImportError:
        raise dependency_not_installed("optuna", "sweep", "hyperparameter sweeps") from None
    from optuna.trial import TrialState

    check_backend(backend, address)
    for name, value, low in (
        ("trials", trials, 1),
        ("seeds", seeds, 1),
        ("evaluations", evaluations, 0),
    ):
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise RunError(f"{name} must be an integer >= {low}, got {value!r}")
    base, _ = resolve_spec(algo, env_id, preset, n_timesteps=n_timesteps)
    searched = distributions(space)
    folder = Path(out)
    stopped_why = stop_requested or (lambda: None)
    # Ray first: a bad address fails before any file. Two sweeps in one folder would mark
    # each other's running trials lost: the folder is locked.
    session = ray_session(address) if backend == "ray" else contextlib.nullcontext()
    with session as ray, FolderLock(folder, "sweep folder"):
        check_inside(folder / "trials", folder, "the sweep's trials folder")
        optuna.logging.set_verbosity(optuna.logging.WARNING)
        rdb, url = _storage(storage, folder)
        study_name = f"{base.algo}-{base.env_id}"
        pruner = {"enabled": prune, "startup": 3}
        study = optuna.create_study(
            study_name=study_name,
            storage=rdb,
            direction="maximize",
            sampler=optuna.samplers.TPESampler(seed=sampler_seed),
            pruner=_make_pruner(pruner),
            load_if_exists=True,
        )
        _check_same_space(study, searched)
        _mark_interrupted(rdb, study)
        # A continued study draws new settings, not the first ones again.
        if sampler_seed is not None:
            study.sampler = optuna.samplers.TPESampler(seed=sampler_seed + len(study.trials))
        todo = max(0, trials - _finished(study))

        def specs(params: Mapping[str, Any]) -> list[str]:
            overrides = settings_of(params, space)
            return [
                resolve_spec(
                    base.algo,
                    base.env_id,
                    preset,
                    overrides=overrides,
                    seed=s,
                    n_timesteps=base.n_timesteps,
                )[0].to_json()
                for s in range(seeds)
            ]

        def tell(trial: Any, outcome: dict[str, Any]) -> None:
            trial_row = {
                "number": trial.number,
                **outcome,
                "params": settings_of(trial.params, space),
            }
            if outcome.get("reason"):
                rdb.set_trial_user_attr(trial._trial_id, "reason", outcome["reason"])
            if outcome["state"] == "complete":
                study.tell(trial, outcome["value"])
            elif outcome["state"] == "pruned":
                study.tell(trial, state=TrialState.PRUNED)
            else:  # failed, or interrupted (then run again by the next call)
                if outcome["state"] == "interrupted":
                    rdb.set_trial_user_attr(trial._trial_id, "interrupted", True)
                study.tell(trial, state=TrialState.FAIL)
            if on_trial is not None:
                on_trial(trial_row)

        def interrupted(trial: Any, where: str) -> None:
            why = stopped_why() or "interrupted"
            tell(trial, {"state": "interrupted", "value": None, "reason": f"{why}: {where}"})

        ran = 0
        stopped: str | None = None
        if backend == "local":
            for _ in range(todo):
                if (stopped := stopped_why()) is not None:
                    break
                trial = study.ask(searched)
                try:
                    outcome = run_trial(
                        specs(trial.params),
                        str(folder / "trials" / str(trial.number)),
                        evaluations,
                        eval_episodes,
                        _reporter(trial) if prune else None,
                        callbacks,
                    )
                except KeyboardInterrupt:  # stopped at once: mid-update, nothing of it is kept
                    interrupted(trial, "stopped at once, mid-trial")
                    raise
                except Exception as exc:  # a trial that raises is recorded; the study goes on
                    outcome = {"state": "failed", "value": None, "reason": one_line(exc)}
                if outcome["state"] == "interrupted":
                    interrupted(trial, outcome["reason"])
                    stopped = stopped_why() or "interrupted"
                    break
                tell(trial, outcome)
                ran += 1
        else:
            if url.startswith("sqlite") and address is not None:
                note(
                    "a SQLite study file is reachable only where this folder is: on a cluster, "
                    "pass --storage with a database URL (e.g. postgresql://...)"
                )
            assert ray is not None
            task = ray.remote(num_cpus=1, max_retries=2)(_remote_trial)
            slots = max(1, int(ray.available_resources().get("CPU", 1)))
            pending: dict[Any, Any] = {}
            asked = 0
            while asked < todo or pending:
                if (stopped := stopped_why()) is not None:
                    for ref, trial in pending.items():  # their workers stop; the next call reruns
                        ray.cancel(ref, force=True)
                        interrupted(trial, "cancelled while it ran on Ray")
                    break
                while asked < todo and len(pending) < slots:
                    trial = study.ask(searched)
                    ref = task.remote(
                        specs(trial.params),
                        str((folder / "trials" / str(trial.number)).resolve()),
                        evaluations,
                        eval_episodes,
                        url,
                        study_name,
                        trial._trial_id,
                        pruner,
                    )
                    pending[ref] = trial
                    asked += 1
                done, _ = ray.wait(list(pending), num_returns=1, timeout=0.5)  # signals get a look
                if not done:
                    continue
                trial = pending.pop(done[0])
                try:
                    outcome = ray.get(done[0])
                except Exception as exc:  # the trial raised, or its worker died past its retries
                    cause = getattr(exc, "cause", None) or exc
                    outcome = {"state": "failed", "value": None, "reason": one_line(cause)}
                tell(trial, outcome)
                ran += 1
        rows, best, best_file = write_outputs(study, space, folder, base, preset)
        return SweepResult(folder, rows, best, best_file, ran, stopped)


def _check_same_space(study: Any, searched: Mapping[str, Any]) -> None:
    """A study continued with another space would mix incomparable trials."""
    for trial in study.get_trials(deepcopy=False):
        if trial.distributions and set(trial.distributions) != set(searched):
            raise RunError(
                f"the study in this folder searched {sorted(trial.distributions)}, not "
                f"{sorted(searched)}",
                "use another --out for a different space",
            )
        return
