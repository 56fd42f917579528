"""The process engine: one worker process per env, observations in shared memory.

Every wait on a worker also watches its process sentinel, so a worker that dies (a segfault,
SIGKILL, the OOM killer) is reported at once with its exit code instead of hanging the parent.
An exception raised by an env is re-raised in the parent with its original type and the
worker's traceback text attached (``__notes__`` and ``__cause__``).

The "spawn" and "forkserver" start methods run the parent's script again in each worker (as
``__mp_main__``) to find the functions it defines. A script that builds a vector env at its top
level, outside ``if __name__ == "__main__":``, would then build one in every worker: the worker
leaves quietly instead (:data:`NO_MAIN_GUARD_EXIT`) and the parent raises
:class:`MissingMainGuardError`, one line that says what to add.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import pickle
import signal
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np

from palaestra.core import Env
from palaestra.error import CustomSpaceError, SharedMemoryError
from palaestra.spaces import Box, Discrete, MultiBinary, MultiDiscrete
from palaestra.spaces.batched_samples import concatenate, create_empty_array, iterate
from palaestra.spaces.batching import batch_space
from palaestra.vector.engine import (
    Infos,
    Rows,
    StepResult,
    batch_spaces,
    check_action_spaces,
    check_actions_batch,
    check_env_fns,
)
from palaestra.vector.shared_memory import (
    create_shared_memory,
    decode_views,
    needs_decoding,
    shared_views,
)
from palaestra.vector.worker import STEP, Payload, decode, run_worker

_ARRAY_SPACES = (Box, Discrete, MultiDiscrete, MultiBinary)
_POLL_SLICE = 0.5  # seconds between liveness checks while a worker is busy
NO_MAIN_GUARD_EXIT = 93  # a worker's exit code: it reached a vector env while importing main


@contextlib.contextmanager
def clear_mpi_env_vars() -> Iterator[None]:
    """Hide MPI's environment variables while workers start: an MPI-launched parent would
    otherwise make each worker's MPI import think it is part of the parent's job."""
    removed = {k: os.environ.pop(k) for k in list(os.environ) if k.startswith(("OMPI_", "PMI_"))}
    try:
        yield
    finally:
        os.environ.update(removed)


class WorkerDiedError(RuntimeError):
    """A worker process exited without answering; the vector env has been closed."""


class MissingMainGuardError(WorkerDiedError):
    """The workers ran the user's script again and reached the vector env at its top level."""


def importing_main() -> bool:
    """Whether this process is a spawn/forkserver worker still running the parent's main module.

    ``_inheriting`` is the flag multiprocessing itself checks before refusing to start a process
    from there (``spawn._check_not_importing_main``); it is cleared once the worker is set up,
    so a vector env made inside an env's own constructor is not affected.
    """
    return bool(getattr(mp.current_process(), "_inheriting", False))


def _main_guard_message(who: str, start_method: str) -> str:
    script = getattr(sys.modules["__main__"], "__file__", None) or "your script"
    return (
        f"{who}: each worker process runs {script} again (start method {start_method!r}) and "
        f"reached this {who} at its top level; put the code that creates and uses it under "
        '`if __name__ == "__main__":`'
    )


class RemoteTraceback(Exception):
    """The traceback text of an exception raised in a worker (the ``__cause__`` we attach)."""

    def __str__(self) -> str:
        return str(self.args[0])


def _exit_reason(code: int | None) -> str:
    if code is None:
        return "exited"
    if code < 0:
        try:
            return f"was killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"was killed by signal {-code}"
    return f"exited with code {code}"


class ProcessEngine:
    """Runs ``env_fns[i]()`` in worker process i; see the module doc for failure handling."""

    def __init__(
        self,
        env_fns: Sequence[Callable[[], Env[Any, Any]]],
        shared_memory: bool = True,
        context: str | None = None,
        daemon: bool = True,
        observation_mode: Any = "same",
        who: str = "AsyncVectorEnv",
    ) -> None:
        if importing_main():
            # This process is a worker re-running its parent's script, which builds vector
            # envs at its top level (no main guard). Going on would make workers of workers
            # (multiprocessing refuses, with a page of traceback from each): leave at once,
            # silently, with a code that the parent turns into one line. Nothing has been
            # started or opened here yet.
            os._exit(NO_MAIN_GUARD_EXIT)
        check_env_fns(env_fns, who)
        self.who = who
        self.num_envs = n = len(env_fns)
        self.closed = False
        self.processes: list[Any] = []
        self.conns: list[Any] = []
        ctx = mp.get_context(context)
        self.start_method = ctx.get_start_method()
        if self.start_method == "forkserver":
            # Workers fork from the server: with palaestra imported there once, each worker
            # starts in milliseconds instead of importing it again (no effect once it runs).
            # Not "__main__": that preload is dead code before CPython 3.13.8 (gh-126631), and
            # where it works the server itself runs the user's script, so a missing main guard
            # would kill the server with a traceback instead of the one-line error below.
            ctx.set_forkserver_preload(["palaestra.vector.worker"])
        # The spaces are needed before the workers start (to size shared memory): build one env
        # here and drop it, as Gymnasium does.
        dummy = env_fns[0]()
        self.metadata = dict(dummy.metadata)
        self.render_mode = dummy.render_mode
        single_obs, single_act = dummy.observation_space, dummy.action_space
        dummy.close()
        del dummy
        if isinstance(observation_mode, tuple):
            self.single_observation_space, self.observation_space = batch_spaces(
                [single_obs], observation_mode, who
            )
        else:
            self.single_observation_space = single_obs
            self.observation_space = batch_space(single_obs, n)
        self._observation_mode = observation_mode
        self.single_action_space = single_act
        self.action_space = batch_space(single_act, n)

        self.shared = shared_memory
        buffers: dict[str, Any] | None = None
        if shared_memory:
            try:
                obs_memory = create_shared_memory(self.single_observation_space, n, ctx)
            except CustomSpaceError as e:
                raise SharedMemoryError(
                    f"Using `{who}(..., shared_memory=True)` caused an error ({e}); you can "
                    "disable this feature with `shared_memory=False` however this is slower."
                ) from e
            buffers = {
                "obs": obs_memory,
                "actions": (
                    create_shared_memory(single_act, n, ctx)
                    if isinstance(single_act, _ARRAY_SPACES)
                    else None
                ),
                "rewards": ctx.Array("d", n, lock=False),
                "terminated": ctx.Array("b", n, lock=False),
                "truncated": ctx.Array("b", n, lock=False),
            }
            # Text/OneOf rows are decoded into the batch after each gather (_refresh_obs);
            # array spaces are read through the views themselves
            self._obs_views = shared_views(self.single_observation_space, buffers["obs"], n)
            self._decode = needs_decoding(self.single_observation_space)
            self.obs = decode_views(self.single_observation_space, self._obs_views)
            self._actions = (
                None
                if buffers["actions"] is None
                else shared_views(single_act, buffers["actions"], n)
            )
            self._rewards = np.frombuffer(buffers["rewards"], dtype=np.float64, count=n)
            self._terminated = np.frombuffer(buffers["terminated"], dtype=np.bool_, count=n)
            self._truncated = np.frombuffer(buffers["truncated"], dtype=np.bool_, count=n)
        else:
            self.obs = create_empty_array(self.single_observation_space, n)
            self._actions = None
            self._rewards = np.zeros(n)  # [N] float64
            self._terminated = np.zeros(n, dtype=bool)  # [N]
            self._truncated = np.zeros(n, dtype=bool)  # [N]
            self._env_obs: list[Any] = [None] * n
        self._buffers = buffers  # keeps the shared arrays alive as long as the engine
        spaces = (self.single_observation_space, single_act)
        try:
            for i, fn in enumerate(env_fns):
                parent, child = ctx.Pipe()
                proc = ctx.Process(  # type: ignore[attr-defined]
                    target=run_worker,
                    name=f"Worker<{who}>-{i}",
                    args=(i, Payload(fn), child, parent, buffers, n, spaces),
                    daemon=daemon,
                )
                self.conns.append(parent)
                self.processes.append(proc)
                with clear_mpi_env_vars():
                    proc.start()
                child.close()
            self._gather(range(n), "start")
            self._check_spaces()
        except WorkerDiedError:
            self.close(terminate=True)
            if any(proc.exitcode == NO_MAIN_GUARD_EXIT for proc in self.processes):
                # Raised here, without the pipe error as context: the user sees one short
                # traceback from their own line, ending in the line that says what to add.
                raise MissingMainGuardError(_main_guard_message(who, self.start_method)) from None
            raise
        except BaseException:
            self.close(terminate=True)
            raise
        self._step_rows: list[int] = []
        self._reset_rows: list[int] = []  # rows a step resets instead (NEXT_STEP)
        self._resetting: list[int] = []  # rows of the reset in flight (reset_send)

    def _check_spaces(self) -> None:
        answers = self.call_rows(range(self.num_envs), "spaces", None)
        obs_spaces = [a[0] for a in answers]
        if not isinstance(self._observation_mode, tuple):
            # "different": the batched space holds each worker's own bounds (read from the
            # workers, so no env is built twice here); shared memory was sized from env 0's,
            # which has the same shape and dtype as every other (batch_spaces checks).
            _, batched = batch_spaces(obs_spaces, self._observation_mode, self.who)
            if self._observation_mode == "different":
                self.observation_space = batched
        check_action_spaces([self.single_action_space] + [a[1] for a in answers], self.who)

    # -- talking to workers -------------------------------------------------------------------
    def _send(self, i: int, command: str, data: Any) -> None:
        message = STEP if command == "step" and data is None and self.shared else None
        if message is None:
            message = pickle.dumps((command, data), protocol=pickle.HIGHEST_PROTOCOL)
        try:
            self.conns[i].send_bytes(message)
        except (BrokenPipeError, ConnectionResetError, EOFError, OSError) as e:
            self._died(i, command, e)

    def _died(self, i: int, what: str, cause: BaseException | None = None) -> None:
        proc = self.processes[i]
        proc.join(timeout=1.0)
        reason = _exit_reason(proc.exitcode)
        self.close(terminate=True)
        raise WorkerDiedError(
            f"{self.who} worker {i} (pid {proc.pid}) {reason} while running {what!r}; the "
            "vector environment has been closed."
        ) from cause

    def _receive(self, i: int, what: str, deadline: float | None) -> tuple[bool, Any]:
        """Worker i's answer. A dead worker closes its pipe end, so ``recv`` sees EOF at once;
        polling in slices also catches a worker stuck without dying when a deadline is set."""
        conn = self.conns[i]
        while not conn.poll(
            _POLL_SLICE
            if deadline is None
            else min(_POLL_SLICE, max(0.0, deadline - time.monotonic()))
        ):
            if not self.processes[i].is_alive() and not conn.poll():
                self._died(i, what)
            if deadline is not None and time.monotonic() >= deadline:
                # Its late answer would be read as the answer to the next command: stop the
                # workers rather than let the pipes fall out of step.
                self.close(terminate=True)
                raise mp.TimeoutError(
                    f"{self.who}: worker {i} did not answer {what!r} in time; the vector "
                    "environment has been closed."
                )
        try:
            return decode(conn.recv_bytes())
        except (EOFError, ConnectionResetError, OSError) as e:
            self._died(i, what, e)
            raise  # unreachable: _died raises

    def _gather(self, rows: Any, what: str, timeout: float | None = None) -> list[Any]:
        """Every answer from ``rows`` (in order); raises the first worker error after all came."""
        rows = list(rows)
        deadline = None if timeout is None else time.monotonic() + timeout
        answers = []
        error: tuple[int, Any] | None = None
        for i in rows:
            ok, payload = self._receive(i, what, deadline)
            answers.append(payload)
            if not ok and error is None:
                error = (i, payload)
        if error is not None:
            i, (exc, text) = error
            _attach_remote_traceback(exc, text, f"{self.who} worker {i}")
            raise exc
        return answers

    def call_rows(self, rows: Any, command: str, data: Any) -> list[Any]:
        """Send ``command`` to each worker in ``rows`` and gather the answers."""
        rows = list(rows)
        for i in rows:
            self._send(i, command, data)
        return self._gather(rows, command)

    # -- the engine protocol ------------------------------------------------------------------
    def reset(self, mask: np.ndarray | None, seeds: list[int | None], options: Any) -> Infos:
        """Reset the masked workers' envs (all if None), each with its seed."""
        self.reset_send(mask, seeds, options)
        return self.reset_recv()

    def reset_send(self, mask: np.ndarray | None, seeds: list[int | None], options: Any) -> None:
        """Start the reset of the masked workers' envs (they reset while the caller goes on)."""
        self._resetting = (
            list(range(self.num_envs)) if mask is None else np.flatnonzero(mask).tolist()
        )
        for i in self._resetting:
            self._send(i, "reset", (seeds[i], options))

    def reset_recv(self, timeout: float | None = None) -> Infos:
        """Gather the reset started by :meth:`reset_send` (``multiprocessing.TimeoutError``
        after ``timeout`` seconds, the workers then stopped)."""
        rows = self._resetting
        answers = self._gather(rows, "reset", timeout)
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for i, answer in zip(rows, answers):
            if self.shared:
                infos[i] = answer
            else:
                self._env_obs[i], infos[i] = answer
        self._refresh_obs()
        return infos

    def _refresh_obs(self) -> None:
        """The batch after a gather: concatenated from the pipes, or decoded from shared
        memory where views alone do not hold it (Text, OneOf)."""
        if not self.shared:
            self.obs = concatenate(self.single_observation_space, self._env_obs, self.obs)
        elif self._decode:
            self.obs = decode_views(self.single_observation_space, self._obs_views)

    def step_send(self, actions: Any, reset_mask: np.ndarray | None) -> None:
        """Send each worker its action (through shared memory for array action spaces)."""
        check_actions_batch(self.action_space, actions, self.num_envs)
        per_row: Any = None
        shared = self._actions
        array = None if shared is None else np.asarray(actions)
        # Same shape too: np.copyto would broadcast a scalar to every row, where Sync and
        # Async without shared memory (and Gymnasium) raise TypeError from iterate().
        if (
            shared is not None
            and array is not None
            and array.dtype == shared.dtype
            and array.shape == shared.shape
        ):
            # One vectorised copy into shared memory; the pipe carries only "step".
            np.copyto(shared, array)
        else:
            # Other dtypes go by pipe, unconverted: the env sees what SyncVectorEnv's would
            # (a float64 action stays float64 under a float32 space, as in Gymnasium).
            per_row = list(iterate(self.action_space, actions))
        self._reset_rows = [] if reset_mask is None else np.flatnonzero(reset_mask).tolist()
        for i in range(self.num_envs):
            if reset_mask is not None and reset_mask[i]:
                self._send(i, "reset", (None, None))
            else:
                self._send(i, "step", None if per_row is None else per_row[i])

    def step_recv(self, timeout: float | None = None) -> StepResult:
        """Gather the workers' answers: infos by pipe, the rest is already in shared memory."""
        answers = self._gather(range(self.num_envs), "step", timeout)
        reset_rows = set(self._reset_rows)
        infos: list[dict[str, Any]] = [{}] * self.num_envs
        for i, answer in enumerate(answers):
            if self.shared:
                infos[i] = answer
            elif i in reset_rows:
                self._env_obs[i], infos[i] = answer
            else:
                obs, reward, term, trunc, infos[i] = answer
                self._env_obs[i] = obs
                self._rewards[i], self._terminated[i], self._truncated[i] = reward, term, trunc
        self._refresh_obs()
        return self._rewards, self._terminated, self._truncated, infos

    def final_observations(self, rows: np.ndarray) -> list[Any] | None:
        """The observations the workers in ``rows`` sent from their last step (unpickled, so
        already copies); None with shared memory, where only the batch holds them."""
        if self.shared:
            return None
        return [self._env_obs[i] for i in rows.tolist()]

    def call(
        self, name: str, args: tuple[Any, ...], kwargs: dict[str, Any], rows: Rows = None
    ) -> tuple[Any, ...]:
        """Call ``name`` in each worker of ``rows``."""
        rows = range(self.num_envs) if rows is None else rows
        return tuple(self.call_rows(rows, "call", (name, args, kwargs)))

    def call_send(self, name: str, args: tuple[Any, ...], kwargs: dict[str, Any]) -> None:
        """Start calling ``name`` in every worker."""
        for i in range(self.num_envs):
            self._send(i, "call", (name, args, kwargs))

    def call_recv(self, timeout: float | None = None) -> tuple[Any, ...]:
        """Gather the results of :meth:`call_send`."""
        return tuple(self._gather(range(self.num_envs), "call", timeout))

    def set_attr(self, name: str, values: Sequence[Any], rows: Rows = None) -> None:
        """Set ``name`` in each worker of ``rows``."""
        rows = list(range(self.num_envs) if rows is None else rows)
        for i, value in zip(rows, values):
            self._send(i, "set_attr", (name, value))
        self._gather(rows, "set_attr")

    def is_wrapped(self, wrapper_class: type, rows: Rows = None) -> list[bool]:
        """Whether each worker's env has a ``wrapper_class`` layer."""
        rows = range(self.num_envs) if rows is None else rows
        return self.call_rows(rows, "is_wrapped", wrapper_class)

    def render(self) -> tuple[Any, ...]:
        """Every worker's frame."""
        return self.call("render", (), {})

    def close(self, terminate: bool = False, timeout: float = 5.0) -> None:
        """Ask workers to close (or terminate them); kill any still alive after ``timeout``."""
        if self.closed:
            return
        self.closed = True
        if not terminate:
            for conn, proc in zip(self.conns, self.processes):
                if proc.is_alive():
                    try:
                        conn.send_bytes(pickle.dumps(("close", None)))
                    except (BrokenPipeError, ConnectionResetError, OSError):
                        pass
        deadline = time.monotonic() + (0.0 if terminate else timeout)
        for proc in self.processes:
            if proc.pid is None:
                continue  # never started
            proc.join(timeout=max(0.0, deadline - time.monotonic()))
            if proc.is_alive():
                proc.terminate()
                proc.join(timeout=1.0)
            if proc.is_alive():
                proc.kill()
                proc.join(timeout=1.0)
        for conn in self.conns:
            conn.close()


def _attach_remote_traceback(exc: BaseException, text: str, where: str) -> None:
    """Make the worker's traceback part of what the parent prints for ``exc``."""
    note = f"Raised in {where}; its traceback:\n{text.rstrip()}"
    add_note = getattr(exc, "add_note", None)  # Python 3.11+
    if add_note is not None:
        add_note(note)
    exc.__cause__ = RemoteTraceback(text)
