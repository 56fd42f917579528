"""Train many runs: one process after another, or as Ray tasks on this machine or a cluster.

A grid is a list of :class:`GridRun` (a label, a :class:`~palaestra.runs.spec.RunSpec`, a run
folder). :func:`run_grid` trains each one that has not finished yet and reports an
:class:`Outcome` per run, in the grid's order:

- ``backend="local"``: in this process, one after another.
- ``backend="ray"``: each run is one Ray task (``num_cpus=1``) that trains into its run
  folder; ``address=None`` starts a local Ray in this process using this machine's cores,
  ``"auto"`` or ``"ray://host:10001"`` joins a cluster (whose nodes must see the same
  filesystem path for the run folders, or the folders stay on the node that trained them).

The same spec trains the same bits either way: a run's randomness comes from its seed only
and every run trains with one torch thread. A Ray worker that dies (killed, out of memory) is
retried (``max_retries``). Either way a run trains in a fresh folder beside its run folder and
takes the run folder's name only when it finishes, so a killed or failed attempt leaves nothing
half-written behind and a rerun of the grid trains it again.
A run that raises is reported as failed with its error; the other runs go on.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from palaestra.runs.errors import RunError, first_line, one_line
from palaestra.runs.files import CONFIG_FILE, STATUS_FILE, read_json
from palaestra.runs.spec import RunSpec

__all__ = ["GridRun", "Outcome", "check_backend", "connect_ray", "is_finished", "run_grid"]

BACKENDS = ("local", "ray")


@dataclasses.dataclass
class GridRun:
    """One run of a grid: its label in tables (a variant or algorithm), spec and folder."""

    label: str
    spec: RunSpec
    run_dir: Path


@dataclasses.dataclass
class Outcome:
    """How a grid run ended: ``"trained"``, ``"reused"`` (it had finished before) or
    ``"failed"`` (``error`` says why)."""

    run: GridRun
    status: str
    seconds: float = 0.0
    error: str | None = None


def is_finished(run_dir: Path) -> bool:
    """Whether ``run_dir`` holds a run that trained to its budget."""
    status = run_dir / STATUS_FILE
    return status.is_file() and read_json(status, "run status").get("status") == "finished"


def _train_into(spec_json: str, run_dir: str) -> float:
    """Train a spec into a fresh folder beside ``run_dir`` and move it there when finished;
    the training seconds. A Ray task's body (a retried attempt starts over)."""
    from palaestra.runs.training import train_run

    target = Path(run_dir)
    target.parent.mkdir(parents=True, exist_ok=True)
    scratch = target.parent / f".{target.name}.partial"
    if scratch.exists():  # left by an attempt that was killed: this one starts over
        shutil.rmtree(scratch)
    try:
        result = train_run(RunSpec.from_json(spec_json), scratch, checkpoint_every=0)
        if target.exists():  # an earlier attempt that did not finish
            shutil.rmtree(target)
        os.replace(scratch, target)
    finally:
        if scratch.exists():
            shutil.rmtree(scratch, ignore_errors=True)
    return result.session_seconds


def connect_ray(address: str | None, num_cpus: int | None = None) -> Any:
    """``ray`` initialised: a local Ray in this process (``address=None``) or the cluster at
    ``address`` (``"auto"``, ``"ray://host:port"``, ``"host:port"``). ``RunError`` with one
    line when it cannot be reached; ``DependencyNotInstalled`` without Ray."""
    from palaestra.error import dependency_not_installed

    try:
        import ray
    except ImportError:
        raise dependency_not_installed("ray", "ray", "running on Ray") from None
    if ray.is_initialized():
        return ray
    kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
    if address is None:
        kwargs["num_cpus"] = num_cpus or os.cpu_count() or 1
    # The workers import palaestra from where this process does (a source checkout works).
    kwargs["runtime_env"] = {"env_vars": {"PYTHONPATH": os.pathsep.join(_import_paths())}}
    if address not in (None, "auto", "local"):
        _probe(address)  # ray.init retries an unreachable address for minutes
    try:
        ray.init(address=address, **kwargs)
    except (ConnectionError, RuntimeError, ValueError, TimeoutError) as exc:
        raise RunError(
            f"cannot reach a Ray cluster at {address!r}: {first_line(exc)}",
            "start one with `ray start --head`, or drop --address for a local Ray",
            code=1,
        ) from None
    return ray


def _probe(address: str, timeout: float = 5.0) -> None:
    """``RunError`` unless something listens at ``address`` (``host:port`` or
    ``ray://host:port``)."""
    import socket

    where = address.removeprefix("ray://")
    host, sep, port = where.rpartition(":")
    if not sep or not host or not port.isdigit():
        raise RunError(
            f"cannot read the Ray address {address!r}",
            "use auto, HOST:PORT (the head's GCS, port 6379) or ray://HOST:10001",
        )
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except OSError as exc:
        raise RunError(
            f"cannot reach a Ray cluster at {address!r}: {exc.strerror or exc}",
            "start one with `ray start --head`, or drop --address for a local Ray",
            code=1,
        ) from None


def _import_paths() -> list[str]:
    import palaestra

    src = str(Path(palaestra.__file__).resolve().parents[1])
    existing = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    return [src, *[p for p in existing if p != src]]


def check_backend(backend: str, address: str | None) -> None:
    """``RunError`` unless ``backend`` is one of ``BACKENDS`` and ``address`` goes with Ray."""
    if backend not in BACKENDS:
        raise RunError(f"unknown backend {backend!r}", f"choose one of {', '.join(BACKENDS)}")
    if backend == "local" and address is not None:
        raise RunError(
            "--address applies to the ray backend", "add --backend ray, or drop --address"
        )


def run_grid(
    runs: Sequence[GridRun],
    backend: str = "local",
    address: str | None = None,
    num_cpus: int | None = None,
    max_retries: int = 2,
    on_event: Callable[[str, GridRun, Outcome | None], None] | None = None,
) -> list[Outcome]:
    """Train every run of ``runs`` that has not finished; one :class:`Outcome` per run, in
    order. ``on_event(kind, run, outcome)`` hears ``"reused"``, ``"start"`` and ``"done"``
    as they happen (for progress lines). A run folder that holds an unfinished run is an
    error (resume it first), checked before anything trains."""
    if backend not in BACKENDS:
        raise RunError(f"unknown backend {backend!r}", f"choose one of {', '.join(BACKENDS)}")
    if backend == "local" and address is not None:
        raise RunError(
            "--address applies to the ray backend", "add --backend ray, or drop --address"
        )
    event = on_event or (lambda kind, run, outcome: None)
    outcomes: dict[int, Outcome] = {}
    todo: list[int] = []
    for i, run in enumerate(runs):
        if (run.run_dir / CONFIG_FILE).is_file():
            if not is_finished(run.run_dir):
                raise RunError(
                    f"{run.run_dir} holds an unfinished run",
                    f"palaestra train --resume {run.run_dir}",
                )
            outcomes[i] = Outcome(run, "reused")
            event("reused", run, outcomes[i])
        else:
            todo.append(i)
    if backend == "local":
        for i in todo:
            outcomes[i] = _train_local(runs[i], event)
    else:
        outcomes.update(
            _train_ray([(i, runs[i]) for i in todo], address, num_cpus, max_retries, event)
        )
    return [outcomes[i] for i in range(len(runs))]


def _train_local(run: GridRun, event: Callable[..., None]) -> Outcome:
    event("start", run, None)
    start = time.perf_counter()
    try:
        seconds = _train_into(run.spec.to_json(), str(run.run_dir))
    except Exception as exc:  # a run that raises is reported; the others go on
        outcome = Outcome(run, "failed", time.perf_counter() - start, one_line(exc))
    else:
        outcome = Outcome(run, "trained", seconds)
    event("done", run, outcome)
    return outcome


def _train_ray(
    todo: list[tuple[int, GridRun]],
    address: str | None,
    num_cpus: int | None,
    max_retries: int,
    event: Callable[..., None],
) -> dict[int, Outcome]:
    ray = connect_ray(address, num_cpus)
    task = ray.remote(num_cpus=1, max_retries=max_retries)(_train_into)
    pending: dict[Any, tuple[int, GridRun, float]] = {}
    for i, run in todo:
        ref = task.remote(run.spec.to_json(), str(run.run_dir.resolve()))
        pending[ref] = (i, run, time.perf_counter())
        event("start", run, None)
    out: dict[int, Outcome] = {}
    while pending:
        done, _ = ray.wait(list(pending), num_returns=1)
        i, run, _started = pending.pop(done[0])
        try:
            seconds = float(ray.get(done[0]))
        except (
            Exception
        ) as exc:  # RayTaskError (the run raised), WorkerCrashedError (retries spent)
            cause = getattr(exc, "cause", None) or exc
            out[i] = Outcome(run, "failed", 0.0, one_line(cause))
        else:
            out[i] = Outcome(run, "trained", seconds)
        event("done", run, out[i])
    return out
