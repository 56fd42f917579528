"""Train many runs: one process after another, or as Ray tasks on this machine or a cluster.

A grid is a list of :class:`GridRun` (a label, a :class:`~palaestra.runs.spec.RunSpec`, a run
folder). :func:`run_grid` trains each one that has not finished yet and reports an
:class:`Outcome` per run, in the grid's order:

- ``backend="local"``: in this process, one after another.
- ``backend="ray"``: each run is one Ray task (``num_cpus=1``) that trains into its run
  folder; ``address=None`` starts a local Ray in this process using this machine's cores,
  ``"auto"`` or ``"head:6379"`` joins a cluster (whose nodes must see the same
  filesystem path for the run folders, or the folders stay on the node that trained them).

The same spec trains the same bits either way: a run's randomness comes from its seed only
and every run trains with one torch thread. A Ray worker that dies (killed, out of memory) is
retried (``max_retries``). Either way a run trains in a fresh folder beside its run folder and
takes the run folder's name only when it finishes, so a killed or failed attempt leaves nothing
half-written behind and a rerun of the grid trains it again.
A run that raises is reported as failed with its error; the other runs go on.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import re
import shutil
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import palaestra
from palaestra.error import dependency_not_installed
from palaestra.runs import reaper
from palaestra.runs.errors import RunError, first_line, one_line
from palaestra.runs.files import CONFIG_FILE, STATUS_FILE, read_json
from palaestra.runs.lock import FolderLock
from palaestra.runs.spec import RunSpec
from palaestra.runs.training import train_run

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
    """``ray`` initialised: a local Ray in this process (``address=None``; without the
    dashboard) or the cluster at ``address`` (``"auto"``, ``"ray://host:port"``,
    ``"host:port"``). ``RunError`` with one line, Ray's own cause and its fix when it cannot
    be reached; ``DependencyNotInstalled`` without Ray. :func:`ray_session` also shuts a local
    Ray down when the work is done, however it ends."""
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
    before = _handlers()
    try:
        ray.init(address=address, **kwargs)
    except (ConnectionError, RuntimeError, ValueError, TimeoutError) as exc:
        raise _unreachable(address, exc) from None
    finally:
        # ray.init sets a SIGTERM handler that exits at once: a command's own (train's and
        # sweep's graceful stop) stays in charge; without one, Ray's exit (atexit) stands.
        for signum, handler in before.items():
            if callable(handler):
                signal.signal(signum, handler)
    return ray


def _handlers() -> dict[int, Any]:
    """The handlers of SIGTERM and SIGHUP now (none off the main thread, where they cannot be
    set)."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    return {s: signal.getsignal(s) for s in _STOP_SIGNALS}


_STOP_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)
)


def _unreachable(address: str | None, exc: BaseException) -> RunError:
    """The one line for a Ray that ``ray.init`` could not start or join: Ray's own cause (the
    last exception of the chain: its "Failed to connect" hides it) and the fix for it."""
    causes: list[BaseException] = [exc]
    while (cause := causes[-1].__cause__) is not None and len(causes) < 10:
        causes.append(cause)
    text = " ".join(str(c) for c in causes)
    where = "start a local Ray" if address is None else f"join the Ray cluster at {address!r}"
    if "InvalidAuthToken" in text or "AuthenticationError" in text or "auth token" in text:
        match = re.search(
            r"(InvalidAuthToken: [^.\n]*|Token authentication is enabled[^.\n]*)", text
        )
        refused = match.group(1) if match else "the authentication token was refused"
        return RunError(
            f"cannot {where}: the cluster uses token authentication and refused this "
            f"process ({refused})",
            "export RAY_AUTH_MODE=token here, with the cluster's token in ~/.ray/auth_token, "
            "RAY_AUTH_TOKEN_PATH or RAY_AUTH_TOKEN (`ray get-auth-token` on the head prints it)",
            code=1,
        )
    deepest = first_line(causes[-1])
    if len(causes) > 1 and deepest.startswith("Failed to connect to GCS. Last connection error"):
        deepest = first_line(causes[-2])  # a traceback follows: the line above says enough
    if address is None:
        return RunError(f"cannot {where}: {deepest}", "see Ray's message above", code=1)
    return RunError(
        f"cannot {where}: {deepest}",
        "start one with `ray start --head`, or drop --address for a local Ray",
        code=1,
    )


@contextlib.contextmanager
def ray_session(address: str | None, num_cpus: int | None = None) -> Iterator[Any]:
    """``ray`` connected (:func:`connect_ray`) for the block. A local Ray the block starts is
    shut down when it ends, however it ends: an error, Ctrl-C, and SIGTERM or SIGHUP too (while
    no handler of the command's own takes them, they exit through ``SystemExit``, so the
    shutdown runs instead of leaving Ray's processes behind); :mod:`palaestra.runs.reaper`
    kills what a SIGKILLed command leaves."""
    started = address is None and not _initialized()
    before = _handlers()
    ray = connect_ray(address, num_cpus)
    if not started:
        yield ray
        return
    received: list[int] = []

    def exit_on_signal(signum: int, frame: Any) -> None:
        received.append(signum)
        name = signal.Signals(signum).name
        print(
            f"\npalaestra: {name} received: stopping the runs and the local Ray (finished runs "
            "are kept; the same command trains the rest)",
            file=sys.stderr,
            flush=True,
        )
        raise SystemExit(128 + signum)

    installed = [s for s, handler in before.items() if handler in (signal.SIG_DFL, None)]
    for signum in installed:
        signal.signal(signum, exit_on_signal)
    watcher = reaper.start()  # for the ends no handler sees: SIGKILL, the OOM killer
    try:
        yield ray
    except SystemExit:
        if received:  # raised inside ray.wait, Ray turns it into SystemExit(1): the signal's
            raise SystemExit(128 + received[0]) from None
        raise
    finally:
        ray.shutdown()
        reaper.stop(watcher)
        for signum in installed:
            signal.signal(signum, before[signum])


def _initialized() -> bool:
    try:
        import ray
    except ImportError:
        return False  # connect_ray says which extra to install
    return bool(ray.is_initialized())


def _probe(address: str, timeout: float = 5.0) -> None:
    """``RunError`` unless something listens at ``address`` (``host:port`` or
    ``ray://host:port``)."""
    import socket

    where = address.removeprefix("ray://")
    host, sep, port = where.rpartition(":")
    if not sep or not host or not port.isdigit():
        raise RunError(
            f"cannot read the Ray address {address!r}",
            "use auto, HOST:PORT (the head's GCS, port 6379) or ray://HOST:10001 (Ray Client: "
            'pip install "ray[client]")',
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
    with contextlib.ExitStack() as locks:
        # Each folder the runs train in, locked for the call: two grids writing one run
        # would delete each other's scratch folder (train_run locks that one too).
        for folder in sorted({runs[i].run_dir.parent for i in todo}):
            locks.enter_context(FolderLock(folder, "grid folder"))
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
    out: dict[int, Outcome] = {}
    with ray_session(address, num_cpus) as ray:
        task = ray.remote(num_cpus=1, max_retries=max_retries)(_train_into)
        pending: dict[Any, tuple[int, GridRun, float]] = {}
        for i, run in todo:
            ref = task.remote(run.spec.to_json(), str(run.run_dir.resolve()))
            pending[ref] = (i, run, time.perf_counter())
            event("start", run, None)
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            i, run, _started = pending.pop(done[0])
            try:
                seconds = float(ray.get(done[0]))
            except Exception as exc:  # RayTaskError (it raised), WorkerCrashedError (retries)
                cause = getattr(exc, "cause", None) or exc
                out[i] = Outcome(run, "failed", 0.0, one_line(cause))
            else:
                out[i] = Outcome(run, "trained", seconds)
            event("done", run, out[i])
    return out
