"""CPU per step of palaestra's and Gymnasium's Box2D single envs, and the share of it spent inside
Box2D's ``b2World.Step`` (the thread's CPU clock read around each call, the clock's own cost
calibrated and subtracted). Prints BENCHMARKS.md rows.

Run from the repository root::

    .venv/bin/python benchmarks/box2d_step_share.py                     # the four Box2D ids
    .venv/bin/python benchmarks/box2d_step_share.py BipedalWalker-v3    # some of them

Both libraries step the same 4,000 ``action_space.sample()`` actions (resetting at episode
ends); each figure is the minimum of 3 runs. Needs ``box2d`` and ``gymnasium`` (a benchmark
only: palaestra never imports gymnasium).
"""

from __future__ import annotations

import argparse
import time
from types import ModuleType
from typing import Any

import Box2D
import gymnasium

import palaestra

IDS = ["LunarLander-v3", "LunarLanderContinuous-v3", "BipedalWalker-v3", "BipedalWalkerHardcore-v3"]
_WRAPPED_STEP = Box2D.b2World.__dict__["Step"]  # SWIG's method wrapper, put back after a run
_C_STEP = Box2D.b2World.Step  # the C function itself
_spent = [0]  # nanoseconds inside Step in the current run


def _timed_step(self: Any, *args: Any) -> Any:
    start = time.thread_time_ns()
    result = _C_STEP(self, *args)
    _spent[0] += time.thread_time_ns() - start
    return result


def clock_pair_ns(reads: int = 20000) -> float:
    """The CPU cost of the two clock reads around one ``Step``."""
    start = time.thread_time_ns()
    for _ in range(reads):
        time.thread_time_ns()
        time.thread_time_ns()
    return (time.thread_time_ns() - start) / reads


def run(lib: ModuleType, env_id: str, actions: list[Any], timed: bool) -> tuple[float, float]:
    """(CPU µs per step, µs per step inside ``Step``) of one run of ``actions``."""
    env = lib.make(env_id)
    env.reset(seed=0)
    _spent[0] = 0
    Box2D.b2World.Step = _timed_step if timed else _WRAPPED_STEP
    try:
        start = time.process_time()
        for action in actions:
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                env.reset()
        elapsed = time.process_time() - start
    finally:
        Box2D.b2World.Step = _WRAPPED_STEP
    return elapsed / len(actions) * 1e6, _spent[0] / len(actions) / 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("ids", nargs="*", default=IDS)
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    pair_us = clock_pair_ns() / 1e3
    print(f"clock pair {pair_us * 1e3:.0f} ns")
    print("| env | palaestra µs/step | `Step` µs | share | gymnasium µs/step | its `Step` share "
          "| ratio |")  # fmt: skip
    for env_id in args.ids:
        space = palaestra.make(env_id).action_space
        space.seed(0)
        actions = [space.sample() for _ in range(args.steps)]
        rows = {}
        for lib in (palaestra, gymnasium):
            plain = min(run(lib, env_id, actions, False)[0] for _ in range(args.repeats))
            step = min(run(lib, env_id, actions, True)[1] for _ in range(args.repeats)) - pair_us
            rows[lib.__name__] = (plain, step)
        (ours, ours_step), (theirs, theirs_step) = rows["palaestra"], rows["gymnasium"]
        print(f"| `{env_id}` | {ours:.1f} | {ours_step:.1f} | {ours_step / ours:.0%} | "
              f"{theirs:.1f} | {theirs_step / theirs:.0%} | {theirs / ours:.2f}x |")  # fmt: skip


if __name__ == "__main__":
    main()
