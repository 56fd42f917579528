"""Callbacks ``palaestra train`` adds to ``learn``: the episode log behind the learning curve,
the live progress line, and the graceful stop on Ctrl-C or SIGTERM."""

from __future__ import annotations

import signal
import sys
import time
from types import FrameType
from typing import Any

import numpy as np

from palaestra.algos.common.callbacks import BaseCallback
from palaestra.cli.common import format_duration

__all__ = ["GracefulStop", "LiveProgress", "format_duration"]

LINE_INTERVAL_S = 2.0  # seconds between two plain progress lines


class LiveProgress(BaseCallback):
    """A tqdm bar (``mode="bar"``) or a plain line every ``interval`` seconds (``"line"``,
    default ``LINE_INTERVAL_S``) on stderr: steps, fps, mean return of the recent episodes,
    the latest evaluation's mean return (``evaluation``: the run's ``PeriodicEvaluation``, whose
    ``last`` is read), time left. ``total``: the step count training will end at (the run's
    ``final_timesteps``, past its budget after a whole last rollout)."""

    def __init__(
        self,
        total: int,
        mode: str = "bar",
        interval: float | None = None,
        evaluation: Any = None,
    ) -> None:
        super().__init__()
        self.total, self.mode, self.evaluation = total, mode, evaluation
        self.interval = LINE_INTERVAL_S if interval is None else interval
        self.bar: Any = None
        self._start_time = self._last_print = 0.0
        self._start_steps = 0

    def _mean_return(self) -> str:
        """Mean return of the last (up to 100) episodes, ``-`` before the first one ends; then
        the latest evaluation's, when the run has one."""
        buffer = self.model.ep_info_buffer
        text = f"{np.mean([e['r'] for e in buffer]):.2f}" if buffer else "-"
        last = None if self.evaluation is None else self.evaluation.last
        return text if last is None else f"{text} | eval {last[1]:.2f}"

    def _on_training_start(self) -> None:
        if self._start_time:  # learn goes on after a checkpoint: one bar, one clock
            return
        self._start_time = self._last_print = time.perf_counter()
        self._start_steps = self.model.num_timesteps
        if self.mode == "bar":
            from tqdm.auto import tqdm

            self.bar = tqdm(
                total=self.total,
                initial=self._start_steps,
                unit="step",
                unit_scale=True,
                dynamic_ncols=True,
                file=sys.stderr,
                mininterval=0.5,
            )

    def _on_step(self) -> bool:
        now = time.perf_counter()
        if self.bar is not None:
            if self.model.num_timesteps > self.bar.total:  # train_freq in episodes: unknown end
                self.bar.total = self.model.num_timesteps
            self.bar.update(self.model.num_timesteps - self.bar.n)
            if now - self._last_print >= 1.0:
                self._last_print = now
                self.bar.set_postfix_str(f"mean return {self._mean_return()}", refresh=False)
        elif self.mode == "line" and now - self._last_print >= self.interval:
            self._last_print = now
            print(self.status_line(now), file=sys.stderr, flush=True)
        return True

    def status_line(self, now: float) -> str:
        """``"  4,096/10,000 steps | 2,310 fps | mean return -200.00 | ETA 0:00:03"``."""
        steps = self.model.num_timesteps
        self.total = max(self.total, steps)  # train_freq in episodes: an end not known before
        fps = (steps - self._start_steps) / max(now - self._start_time, 1e-9)
        left = (self.total - steps) / fps if fps > 0 else float("inf")
        return (
            f"{steps:>9,}/{self.total:,} steps | {fps:,.0f} fps | "
            f"mean return {self._mean_return()} | ETA {format_duration(max(left, 0.0))}"
        )

    def close(self) -> None:
        """Finish the bar (idempotent)."""
        if self.bar is not None:
            self.bar.close()
            self.bar = None


class GracefulStop(BaseCallback):
    """The first Ctrl-C (SIGINT) or SIGTERM asks ``learn`` to stop at the next env step (so
    the model is saved between two consistent steps); a second one interrupts at once.

    SIGTERM is what ``timeout``, batch schedulers and ``docker stop`` send before they kill:
    it gets the same checkpoint as Ctrl-C. ``exit_code`` is the shell's 128 + signal number
    (130 for Ctrl-C, 143 for SIGTERM)."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        super().__init__()
        self.requested = False
        self.finish_at = sys.maxsize  # steps at which a stop no longer stops (the run's end)
        self.signum: int | None = None  # the first signal received
        self._previous: dict[int, Any] = {}

    @property
    def exit_code(self) -> int:
        """130 (Ctrl-C, or a KeyboardInterrupt raised inside ``learn``), 143 after SIGTERM."""
        return 128 + (self.signum or signal.SIGINT)

    def install(self) -> None:
        """Take over SIGINT and SIGTERM (main thread only; elsewhere they keep their
        handlers)."""
        for signum in self.SIGNALS:
            try:
                self._previous[signum] = signal.signal(signum, self._handle)
            except ValueError:  # not the main thread
                return

    def uninstall(self) -> None:
        """Give the signals back to whoever had them."""
        for signum, previous in self._previous.items():
            if previous is not None:  # None: a handler not set from Python, cannot restore
                signal.signal(signum, previous)
        self._previous = {}

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested, self.signum = True, signum
        if signum == signal.SIGINT:
            note = "stopping at the next step (Ctrl-C again to stop now)"
        else:
            name = signal.Signals(signum).name
            note = (
                f"{name} received: stopping at the next step ({name} or Ctrl-C again to stop now)"
            )
        print(f"\n{note}", file=sys.stderr, flush=True)

    def _on_step(self) -> bool:
        # A stop asked for during the last step lets the run finish (its final update).
        return not self.requested or self.num_timesteps >= self.finish_at
