"""Gymnasium's throughput benchmarks: env steps, vector env steps, constructions (with the
first reset) and renders per second, each measured for about ``target_duration`` seconds."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["benchmark_init", "benchmark_render", "benchmark_step", "benchmark_vector_step"]


def _duration(target_duration: float) -> float:
    if isinstance(target_duration, bool) or not isinstance(target_duration, (int, float)):
        raise TypeError(f"target_duration must be a number of seconds, got {target_duration!r}")
    if not target_duration >= 0:
        raise ValueError(f"target_duration must be >= 0 seconds, got {target_duration!r}")
    return float(target_duration)


def _rate(body: Callable[[], int], target_duration: float) -> float:
    """Run ``body`` (which returns how many units it did) until ``target_duration`` passed
    (at least once); units per second."""
    limit = _duration(target_duration)
    done, start = 0, time.perf_counter()
    while True:
        done += body()
        elapsed = time.perf_counter() - start
        if elapsed > limit:
            return done / elapsed


def benchmark_step(env: Any, target_duration: float = 5, seed: int | None = None) -> float:
    """Steps per second of ``env`` under random actions, resetting where episodes end;
    ``seed`` seeds the first reset and the action space."""
    env.reset(seed=seed)
    env.action_space.seed(seed)

    def step() -> int:
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()
        return 1

    return _rate(step, target_duration)


def benchmark_vector_step(env: Any, target_duration: float = 5, seed: int | None = None) -> float:
    """Env steps per second of a vector env under random actions (``num_envs`` per call; in
    the NEXT_STEP autoreset mode a step that only resets an env is not counted)."""
    from palaestra.vector import AutoresetMode  # lazy: import-time — multiprocessing

    env.action_space.seed(seed)
    env.reset(seed=seed)
    env.step(env.action_space.sample())  # warm-up, as Gymnasium's
    env.reset(seed=seed)
    mode = env.metadata.get("autoreset_mode", AutoresetMode.NEXT_STEP)
    previous_done = np.zeros(env.num_envs, dtype=bool)

    def step() -> int:
        nonlocal previous_done
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        done = np.logical_or(terminated, truncated)
        counted = env.num_envs
        if mode == AutoresetMode.NEXT_STEP:
            counted -= int(np.count_nonzero(previous_done))
            previous_done = done
        elif mode == AutoresetMode.DISABLED and np.any(done):
            env.reset(options={"reset_mask": done})
        return counted

    return _rate(step, target_duration)


def benchmark_init(
    env_lambda: Callable[[], Any], target_duration: float = 5, seed: int | None = None
) -> float:
    """Constructions (each followed by its first ``reset(seed=seed)``) per second."""

    def init() -> int:
        env_lambda().reset(seed=seed)
        return 1

    return _rate(init, target_duration)


def benchmark_render(env: Any, target_duration: float = 5) -> float:
    """``render()`` calls per second (an ``rgb_array`` env, not ``human``)."""

    def render() -> int:
        env.render()
        return 1

    return _rate(render, target_duration)
