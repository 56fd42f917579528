"""``AsyncVectorEnv``: one worker process per env, observations in shared memory."""

from __future__ import annotations

import multiprocessing as mp
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from palaestra import logger
from palaestra.core import Env
from palaestra.error import AlreadyPendingCallError, NoAsyncCallError
from palaestra.vector.engine_env import EngineVectorEnv
from palaestra.vector.infos import stack_infos
from palaestra.vector.process_engine import ProcessEngine
from palaestra.vector.vector_env import AutoresetMode, StepReturn

__all__ = ["AsyncVectorEnv"]


class AsyncVectorEnv(EngineVectorEnv):
    """Runs each env in its own process (Gymnasium's signature and ``*_async``/``*_wait`` API).

    ``context`` is the multiprocessing start method ("fork", "spawn", "forkserver"; None: the
    platform default, as in Gymnasium). "spawn" and "forkserver" run the script again in each
    worker: build the env under ``if __name__ == "__main__":`` (``MissingMainGuardError`` says
    so otherwise). ``shared_memory=False`` pickles observations instead (for custom spaces). A
    worker that raises re-raises here with its class and traceback; one that dies raises
    ``WorkerDiedError`` at once.
    """

    engine: ProcessEngine

    def __init__(
        self,
        env_fns: Sequence[Callable[[], Env[Any, Any]]],
        shared_memory: bool = True,
        copy: bool = True,
        context: str | None = None,
        daemon: bool = True,
        worker: Callable[..., None] | None = None,
        observation_mode: str | tuple[Any, Any] = "same",
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
    ) -> None:
        if worker is not None:
            raise NotImplementedError(
                "AsyncVectorEnv(worker=...) is not supported: palaestra's workers speak their "
                "own protocol. Wrap the env instead."
            )
        self.env_fns = env_fns
        self.shared_memory = shared_memory
        self.observation_mode = observation_mode
        engine = ProcessEngine(env_fns, shared_memory, context, daemon, observation_mode)
        self._state = "default"  # or the name of the call in flight
        self._reset_mask: np.ndarray | None = None  # of the reset in flight
        super().__init__(engine, copy=copy, autoreset_mode=autoreset_mode)

    def _start(self, name: str) -> None:
        self._check_open()
        if self._state != "default":
            raise AlreadyPendingCallError(
                f"Calling `{name}_async` while waiting for a pending call to `{self._state}` "
                "to complete",
                self._state,
            )
        self._state = name

    def _finish(self, name: str) -> None:
        self._check_open()
        if self._state != name:
            raise NoAsyncCallError(
                f"Calling `{name}_wait` without any prior call to `{name}_async`.", name
            )
        self._state = "default"

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset all workers' envs (or those in ``options["reset_mask"]``)."""
        self.reset_async(seed=seed, options=options)
        return self.reset_wait()

    def reset_async(
        self, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> None:
        """Send the reset: the workers reset while the caller does something else."""
        self._start("reset")
        try:
            self._reset_mask = self._driver.begin_reset(seed, options)
        except BaseException:
            self._state = "default"  # bad seeds or mask: nothing was sent
            raise

    def reset_wait(self, timeout: float | None = None) -> tuple[Any, dict[str, Any]]:
        """Collect the reset sent by :meth:`reset_async` (``multiprocessing.TimeoutError``
        after ``timeout`` seconds; the workers are then stopped)."""
        self._finish("reset")
        obs, raw = self._driver.finish_reset(self._reset_mask, timeout)
        return self._out(obs), stack_infos(raw, self.num_envs)

    def step(self, actions: Any) -> StepReturn:
        """Step all workers' envs."""
        self.step_async(actions)
        return self.step_wait()

    def step_async(self, actions: Any) -> None:
        """Send the actions; the workers step while the caller does something else."""
        self._start("step")
        try:
            self._driver.begin_step(actions)
        except BaseException:
            self._state = "default"  # nothing was sent: bad actions leave the env usable
            raise

    def step_wait(self, timeout: float | None = None) -> StepReturn:
        """Collect the step sent by :meth:`step_async` (``multiprocessing.TimeoutError`` after
        ``timeout`` seconds)."""
        self._finish("step")
        return self._step_return(self._driver.finish_step(timeout))

    def call_async(self, name: str, *args: Any, **kwargs: Any) -> None:
        """Start calling ``name`` in every worker."""
        self._start("call")
        self.engine.call_send(name, args, kwargs)

    def call_wait(self, timeout: float | None = None) -> tuple[Any, ...]:
        """The results of the call started by :meth:`call_async`."""
        self._finish("call")
        return self.engine.call_recv(timeout)

    def close_extras(
        self, timeout: float | None = None, terminate: bool = False, **kwargs: Any
    ) -> None:
        """Stop the workers: politely (waiting up to ``timeout`` s), or at once with
        ``terminate``; no child process outlives this call."""
        engine = getattr(self, "engine", None)
        if not isinstance(engine, ProcessEngine):
            return
        pending = getattr(self, "_state", "default")
        if pending != "default" and not engine.closed:
            # Gymnasium's order: warn, then collect the pending answers so that the workers'
            # pipes are empty for "close"; a timeout means stopping them instead.
            logger.warn(
                f"Calling `close` while waiting for a pending call to `{pending}` to complete."
            )
            try:
                getattr(self, f"{pending}_wait")(0 if terminate else timeout)
            except mp.TimeoutError:
                terminate = True
            except Exception:  # the pending call failed: its answer has been read anyway
                pass
        if not engine.closed:
            engine.close(terminate=terminate, timeout=5.0 if timeout is None else timeout)
