"""Atari env-steps per second: palaestra vs Gymnasium + ale-py, in one process.

Run from the repository root::

    .venv/bin/python benchmarks/atari.py                   # every case (~1 minute)
    .venv/bin/python benchmarks/atari.py --cases single    # one case
    .venv/bin/python benchmarks/atari.py --quick           # smoke run

Cases:

- ``single``: ``make("ALE/Breakout-v5")`` in both libraries (v5 defaults: frameskip 4, sticky
  actions 0.25, RGB observations, the wrappers ``make`` adds), random actions drawn once
  from a fixed seed (``np.int64``, as ``action_space.sample()`` gives them), reset at episode
  ends. Target: ratio >= 0.95 (the emulator dominates; the Python around it must not add).

Each figure is the median of ``--repeats`` runs, the two libraries interleaved. Time is the
process's CPU time (``time.process_time``): the shared machine is busy with other jobs, and
wall time there would measure their load as much as ours.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import palaestra

ENV_ID = "ALE/Breakout-v5"


def gymnasium_module() -> Any:
    """Gymnasium with ale-py's ids registered."""
    import ale_py
    import gymnasium

    gymnasium.register_envs(ale_py)
    return gymnasium


def single_rate(lib: Any, actions: np.ndarray) -> float:
    """Env-steps/s of one ``lib.make(ENV_ID)`` over ``actions``, resetting at episode ends."""
    env = lib.make(ENV_ID)
    env.reset(seed=0)
    step, reset = env.step, env.reset
    start = time.process_time()
    for action in actions:
        _, _, terminated, truncated, _ = step(action)
        if terminated or truncated:
            reset()
    elapsed = time.process_time() - start
    env.close()
    return len(actions) / elapsed


def bench_single(args: argparse.Namespace) -> None:
    """palaestra vs Gymnasium, one Breakout env each."""
    gymnasium = gymnasium_module()
    actions = np.random.default_rng(0).integers(0, 4, args.steps)  # Breakout: Discrete(4)
    ours, ref = [], []
    for _ in range(args.repeats):
        ours.append(single_rate(palaestra, actions))
        ref.append(single_rate(gymnasium, actions))
    p, g = statistics.median(ours), statistics.median(ref)
    print(f"{'single ' + ENV_ID:<34}{p:>12,.0f}{g:>12,.0f}{p / g:>7.2f}x   (target >= 0.95x)")
    runs = f"palaestra {[round(r) for r in ours]}, gymnasium {[round(r) for r in ref]}"
    print(f"{'':<34}runs: {runs}")


CASES: dict[str, Callable[[argparse.Namespace], None] | None] = {
    "single": bench_single,
    "preprocessed": None,  # AtariPreprocessing / make_atari_env stacks: not written yet
    "vector": None,  # native vector Atari: not written yet
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--quick", action="store_true", help="few steps, for a smoke test")
    args = parser.parse_args()
    if args.quick:
        args.repeats, args.steps = 1, 200
    import ale_py
    import gymnasium

    print(
        f"numpy {np.__version__}, gymnasium {gymnasium.__version__}, ale-py {ale_py.__version__}, "
        f"repeats {args.repeats}, {args.steps} steps each"
    )
    print(f"{'case':<34}{'palaestra':>12}{'gymnasium':>12}{'ratio':>8}   (env-steps/s)")
    for name in args.cases:
        case = CASES[name]
        if case is None:
            print(f"{name:<34}(not implemented yet)")
        else:
            case(args)


if __name__ == "__main__":
    main()
