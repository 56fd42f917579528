"""The ``vector`` case of ``atari.py``: native vector Atari, palaestra vs ale-py.

``palaestra.make_vec("ALE/Breakout-v5", num_envs=n)`` against ``gymnasium.make_vec`` of the
same id (ale-py's ``AtariVectorEnv``): the same ``ALEVectorInterface`` and settings (v5: sticky
actions 0.25, frameskip 4, 84x84 grayscale stacks of 4), NEXT_STEP autoreset, random actions
drawn once. Env-steps/s for n = 2 and 4; the ratio measures what palaestra's Python around the
C++ batch costs. Target: ratio >= 0.90.

Time is CPU time of the whole process (``time.process_time``, ALE's worker threads included),
as in the other cases; wall-clock rates are printed beside it.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np

import palaestra

ENV_ID = "ALE/Breakout-v5"


def vector_rate(lib: Any, num_envs: int, actions: np.ndarray) -> tuple[float, float]:
    """``(CPU-time, wall-time)`` env-steps/s of ``lib.make_vec(ENV_ID, num_envs)``."""
    envs = lib.make_vec(ENV_ID, num_envs=num_envs)
    envs.reset(seed=0)
    step = envs.step
    cpu, wall = time.process_time(), time.perf_counter()
    for batch in actions:
        step(batch)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    envs.close()
    return actions.size / cpu, actions.size / wall


def bench_vector(args: argparse.Namespace) -> None:
    """palaestra vs Gymnasium/ale-py, 2 and 4 Breakout envs on ALE's vector interface."""
    import ale_py
    import gymnasium

    gymnasium.register_envs(ale_py)
    for n in (2, 4):
        actions = np.random.default_rng(0).integers(0, 4, (max(1, args.steps // n), n))
        ours, ref = [], []
        for _ in range(args.repeats):
            ours.append(vector_rate(palaestra, n, actions))
            ref.append(vector_rate(gymnasium, n, actions))
        p = statistics.median(r[0] for r in ours)
        g = statistics.median(r[0] for r in ref)
        name = f"vector {ENV_ID} x{n}"
        print(f"{name:<34}{p:>12,.0f}{g:>12,.0f}{p / g:>7.2f}x   (target >= 0.90x)")
        pw = statistics.median(r[1] for r in ours)
        gw = statistics.median(r[1] for r in ref)
        print(f"{'':<34}wall: palaestra {pw:,.0f}, gymnasium {gw:,.0f} ({pw / gw:.2f}x)")
        runs = f"palaestra {[round(r[0]) for r in ours]}, gymnasium {[round(r[0]) for r in ref]}"
        print(f"{'':<34}runs: {runs}")
