"""Evaluation during training (``train --eval-freq N --eval-episodes K``): the RL Zoo's
``EvalCallback`` set-up, kept in the run folder and continued by ``--resume``.

Every ``N`` env steps counted over all envs, as the RL Zoo counts (it gives SB3's
``EvalCallback`` ``N // n_envs`` vector steps: evaluations at the multiples of
``n_envs * (N // n_envs)`` steps), the model plays ``K`` deterministic episodes on a separate
one-env copy of the run's recipe. :class:`palaestra.algos.callbacks.EvalCallback` plays them,
first copying the training env's ``VecNormalize`` statistics into the eval env
(``sync_envs_normalization``), and logs ``eval/mean_reward`` to ``progress.csv`` and
TensorBoard. Before each evaluation the eval env is seeded with ``EVAL_SEED`` (0, as
``palaestra eval``): every evaluation plays the same episode starts, so two evaluations differ
by the model only, a resumed run evaluates as one never stopped, and ``palaestra eval
RUN/best_model.zip --episodes K`` replays the best row. Deterministic actions draw nothing from
the model's generators: a run trains the same with and without evaluations.

Each evaluation appends a row to ``evaluations.csv`` (:data:`EVALUATION_COLUMNS`; ``returns``
holds the per-episode returns separated by spaces). A mean return above every earlier one
saves the model as ``best_model.zip`` (with the statistics it was evaluated with as
``best_vecnormalize.npz`` for a normalized run), both atomically, before its row is written.

The schedule is a multiple of the step count, so a resumed run evaluates next at the next
multiple. A resume first drops the rows past its checkpoint (:func:`~palaestra.runs.checkpoint.
trim_logs`: a run killed after them replays those steps), then takes the best mean return of
the rows left as the best so far: ``best_model.zip`` is replaced only by a better model.
"""

from __future__ import annotations

import csv
import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np

from palaestra.algos.common.callbacks import BaseCallback, EvalCallback
from palaestra.runs.curves import read_evaluations
from palaestra.runs.errors import RunError
from palaestra.runs.evaluation import make_eval_env
from palaestra.runs.files import (
    BEST_MODEL_FILE,
    BEST_NORMALIZE_FILE,
    EVALUATIONS_FILE,
)
from palaestra.utils.atomic_write import open_append

__all__ = [
    "EVALUATION_COLUMNS",
    "EVAL_SEED",
    "EvalSchedule",
    "PeriodicEvaluation",
    "best_return",
]

EVALUATION_COLUMNS = ("timesteps", "mean_return", "std_return", "mean_length", "returns")
EVAL_SEED = 0
MAX_STEPS = 10**15  # as a run folder's n_timesteps
MAX_EPISODES = 100_000


def _count(value: Any, name: str, low: int, high: int, example: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise RunError(f"{name} must be an integer, got {value!r}", example)
    if not low <= value <= high:
        raise RunError(f"{name} must be from {low} to {high:,}, got {value!r}", example)
    return int(value)


@dataclasses.dataclass(frozen=True)
class EvalSchedule:
    """Evaluate every ``every`` env steps (over all envs) on ``episodes`` episodes."""

    every: int
    episodes: int

    @classmethod
    def from_arguments(cls, eval_freq: Any, eval_episodes: Any) -> EvalSchedule | None:
        """The schedule of ``eval_freq``/``eval_episodes`` as the run API and the CLI take
        them; None for ``eval_freq`` 0 (no evaluation during training). ``RunError`` naming
        the value otherwise."""
        every = _count(eval_freq, "eval_freq", 0, MAX_STEPS, "e.g. --eval-freq 10000")
        if every == 0:
            return None
        episodes = _count(
            eval_episodes, "eval_episodes", 1, MAX_EPISODES, "e.g. --eval-episodes 10"
        )
        return cls(every, episodes)

    @classmethod
    def from_config(cls, value: Any, source: str) -> EvalSchedule:
        """The ``evaluation`` entry of a run's ``config.json`` (``{"every": N, "episodes":
        K}``), checked as any value a run folder holds."""
        if not isinstance(value, dict) or set(value) != {"every", "episodes"}:
            raise RunError(
                f"{source}: evaluation must be a mapping with keys 'every' and 'episodes', "
                f"got {value!r}",
                "fix the file, or start a new run",
            )
        try:
            every = _count(value["every"], "evaluation.every", 1, MAX_STEPS, "")
            episodes = _count(value["episodes"], "evaluation.episodes", 1, MAX_EPISODES, "")
        except RunError as exc:
            raise RunError(f"{source}: {exc.args[0]}", "fix the file, or start a new run") from None
        return cls(every, episodes)

    def to_config(self) -> dict[str, int]:
        """The ``evaluation`` entry of ``config.json``."""
        return {"every": self.every, "episodes": self.episodes}

    def period(self, n_envs: int) -> int:
        """Env steps between two evaluations with ``n_envs`` envs (the RL Zoo's
        ``max(eval_freq // n_envs, 1)`` vector steps).

        >>> EvalSchedule(1000, 5).period(8), EvalSchedule(1000, 5).period(3)
        (1000, 999)
        """
        return n_envs * max(self.every // n_envs, 1)


def best_return(run_dir: Path) -> float:
    """The best mean return in ``evaluations.csv`` (``-inf`` without a row)."""
    evaluations = read_evaluations(run_dir)
    if evaluations is None or not len(evaluations.mean):
        return -math.inf
    return float(np.max(evaluations.mean))


class PeriodicEvaluation(BaseCallback):
    """The evaluations of a run into ``run_dir`` (see the module docstring); ``best``: the
    best mean return so far (a resumed run's). :meth:`open` before ``learn``, :meth:`close`
    after it. ``last``: ``(timesteps, mean return)`` of the latest evaluation, or None."""

    def __init__(self, run_dir: Path, schedule: EvalSchedule, best: float = -math.inf) -> None:
        super().__init__()
        self.run_dir, self.schedule, self.best = Path(run_dir), schedule, best
        self.last: tuple[int, float] | None = None
        self._evaluator: EvalCallback | None = None
        self._file: Any = None
        self._period = 0

    def open(self, config: dict[str, Any], model: Any) -> None:
        """Build the eval env for ``model`` (trained on the run ``config`` describes) and open
        ``evaluations.csv`` for appending."""
        if self._evaluator is not None:
            return
        eval_env = make_eval_env(config, model.get_env(), EVAL_SEED)
        self._evaluator = EvalCallback(
            eval_env,
            n_eval_episodes=self.schedule.episodes,
            eval_freq=1,  # when is decided here: on the step count, which a resume continues
            deterministic=True,
            verbose=0,
            warn=False,
        )
        self._evaluator.best_mean_reward = self.best
        self._file = open_append(
            self.run_dir / EVALUATIONS_FILE, ",".join(EVALUATION_COLUMNS) + "\r\n"
        )
        self._period = self.schedule.period(model.n_envs)

    def close(self) -> None:
        """Close the eval env and the file (idempotent)."""
        if self._evaluator is not None:
            self._evaluator.eval_env.close()
            self._evaluator = None
        if self._file is not None:
            self._file.close()
            self._file = None

    def _init_callback(self) -> None:
        if self._evaluator is None:
            raise RuntimeError("PeriodicEvaluation.open(config, model) must come before learn")
        self._evaluator.init_callback(self.model)

    def _on_step(self) -> bool:
        if self.num_timesteps % self._period == 0:
            self.evaluate()
        return True

    def evaluate(self) -> float:
        """Evaluate the model now: log, keep it if best, append the row; its mean return."""
        evaluator = self._evaluator
        assert evaluator is not None
        evaluator.eval_env.seed(EVAL_SEED)
        evaluator.on_step()  # plays the episodes on the synced eval env, logs eval/*
        returns = evaluator.evaluations_results[-1]
        lengths = evaluator.evaluations_length[-1]
        mean = float(np.mean(returns))
        if mean > self.best:
            self.best = mean
            self.model.save(self.run_dir / BEST_MODEL_FILE)
            normalize = self.model.get_vec_normalize_env()
            if normalize is not None:
                normalize.save(self.run_dir / BEST_NORMALIZE_FILE)
        writer = csv.writer(self._file)
        writer.writerow(
            [
                self.num_timesteps,
                mean,
                float(np.std(returns)),
                float(np.mean(lengths)),
                " ".join(repr(float(r)) for r in returns),
            ]
        )
        self._file.flush()
        self.last = (self.num_timesteps, mean)
        return mean
