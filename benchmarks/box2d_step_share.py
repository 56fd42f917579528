"""CPU per step of palaestra's and Gymnasium's Box2D single envs, and the share of it spent inside
Box2D's ``b2World.Step`` and ``b2World.RayCast`` (the walker's lidar: Box2D's tree walk, SWIG's
calls of the Python callback, the callback itself) (the thread's CPU clock read around each
call, the clock's own cost calibrated and subtracted). Prints BENCHMARKS.md rows.

Run from the repository root::

    .venv/bin/python benchmarks/box2d_step_share.py                     # the four Box2D ids
    .venv/bin/python benchmarks/box2d_step_share.py BipedalWalker-v3    # some of them

Both libraries step the same 4,000 ``action_space.sample()`` actions (resetting at episode
ends); each figure is the minimum of 3 runs (the plain CPU per step from untimed runs, the
shares from runs with the clocks around the calls), the two libraries' runs alternating.
Needs ``box2d`` and ``gymnasium`` (a benchmark only: palaestra never imports gymnasium).
"""

from __future__ import annotations

import argparse
import os
import time
from types import ModuleType
from typing import Any

import Box2D
import gymnasium

import palaestra

IDS = ["LunarLander-v3", "LunarLanderContinuous-v3", "BipedalWalker-v3", "BipedalWalkerHardcore-v3"]
_WRAPPED = {name: Box2D.b2World.__dict__[name] for name in ("Step", "RayCast")}  # put back
_C_STEP, _C_RAY_CAST = Box2D.b2World.Step, Box2D.b2World.RayCast  # the C functions themselves
_spent = [0, 0]  # nanoseconds inside Step, RayCast in the current run
_calls = [0, 0]


def _timed_step(self: Any, *args: Any) -> Any:
    start = time.thread_time_ns()
    result = _C_STEP(self, *args)
    _spent[0] += time.thread_time_ns() - start
    _calls[0] += 1
    return result


def _timed_ray_cast(self: Any, *args: Any) -> Any:
    start = time.thread_time_ns()
    result = _C_RAY_CAST(self, *args)
    _spent[1] += time.thread_time_ns() - start
    _calls[1] += 1
    return result


def clock_pair_ns(reads: int = 20000) -> float:
    """The CPU cost of the two clock reads around one ``Step``."""
    start = time.thread_time_ns()
    for _ in range(reads):
        time.thread_time_ns()
        time.thread_time_ns()
    return (time.thread_time_ns() - start) / reads


def run(
    lib: ModuleType, env_id: str, actions: list[Any], timed: bool, pair_ns: float = 0.0
) -> tuple[float, float, float]:
    """(CPU µs per step, µs per step inside ``Step``, inside ``RayCast``) of one run of
    ``actions``, less ``pair_ns`` per timed call."""
    env = lib.make(env_id)
    env.reset(seed=0)
    _spent[:] = _calls[:] = [0, 0]
    if timed:
        Box2D.b2World.Step, Box2D.b2World.RayCast = _timed_step, _timed_ray_cast
    try:
        start = time.process_time()
        for action in actions:
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                env.reset()
        elapsed = time.process_time() - start
    finally:
        Box2D.b2World.Step, Box2D.b2World.RayCast = _WRAPPED["Step"], _WRAPPED["RayCast"]
    step, ray_cast = ((spent - pair_ns * calls) for spent, calls in zip(_spent, _calls))
    return elapsed / len(actions) * 1e6, step / len(actions) / 1e3, ray_cast / len(actions) / 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("ids", nargs="*", default=IDS)
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    pair_ns = clock_pair_ns()
    print(f"clock pair {pair_ns:.0f} ns, load average {os.getloadavg()[0]:.2f}")
    print("| env | palaestra µs/step | `Step` µs | share | `RayCast` share | gymnasium µs/step "
          "| its `Step` share | its `RayCast` share | ratio |")  # fmt: skip
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for env_id in args.ids:
        space = palaestra.make(env_id).action_space
        space.seed(0)
        actions = [space.sample() for _ in range(args.steps)]
        plain: dict[str, list[float]] = {"palaestra": [], "gymnasium": []}
        timed: dict[str, list[tuple[float, float, float]]] = {"palaestra": [], "gymnasium": []}
        for _ in range(args.repeats):  # the libraries alternate, so a change of load hits both
            for lib in (palaestra, gymnasium):
                plain[lib.__name__].append(run(lib, env_id, actions, False)[0])
                timed[lib.__name__].append(run(lib, env_id, actions, True, pair_ns))
        rows = {
            name: (min(plain[name]), min(t[1] for t in timed[name]), min(t[2] for t in timed[name]))
            for name in plain
        }
        (ours, step, ray), (theirs, their_step, their_ray) = rows["palaestra"], rows["gymnasium"]
        print(f"| `{env_id}` | {ours:.1f} | {step:.1f} | {step / ours:.0%} | {ray / ours:.0%} "
              f"| {theirs:.1f} | {their_step / theirs:.0%} | {their_ray / theirs:.0%} "
              f"| {theirs / ours:.2f}x |")  # fmt: skip
    print(f"load average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
