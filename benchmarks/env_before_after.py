"""Single-env step speed of two palaestra trees against Gymnasium, alternated: did a change pay?

Run from the repository root, with the "before" tree's files beside this one::

    mkdir /tmp/before && git archive 70d08c2 src | tar -x -C /tmp/before
    .venv/bin/python benchmarks/env_before_after.py --before /tmp/before --after . --pairs 3

Each pair runs the ids once on the before tree and once on the after tree (the starting tree
alternates between pairs), each run in a fresh interpreter whose ``palaestra`` comes from that
tree's ``src``; within a run, palaestra and Gymnasium alternate as in ``env_step.py`` (its
``single_rate``, the median of ``--repeats``). The measuring code is this tree's, so both
trees step the same actions. Printed per id and tree: the ratio to Gymnasium of each run, its
median and range, and the median steps/s of both libraries, with the load average before
each pair. Needs ``gymnasium`` and ``box2d`` (a benchmark only).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

from child import last_json_line  # benchmarks/ is on sys.path when run as a script

BENCHMARKS = Path(__file__).resolve().parent
IDS = ["LunarLander-v3", "LunarLanderContinuous-v3", "BipedalWalker-v3", "BipedalWalkerHardcore-v3"]

_CHILD = """
import json, statistics, sys
import gymnasium
import env_step
import palaestra
steps, repeats = int(sys.argv[2]), int(sys.argv[3])
out = {}
for env_id in sys.argv[1].split(","):
    space = gymnasium.make(env_id).action_space
    space.seed(0)
    skip = env_step.FRAME_SKIP if env_id in env_step.FRAME_IDS else 0
    n = skip + env_step.FRAME_STEPS if skip else steps
    actions = [space.sample() for _ in range(n)]
    ours, ref = [], []
    for _ in range(repeats):
        ours.append(env_step.single_rate(palaestra, env_id, actions, skip))
        ref.append(env_step.single_rate(gymnasium, env_id, actions, skip))
    out[env_id] = (statistics.median(ours), statistics.median(ref))
print(json.dumps(out))
"""


def run_once(tree: Path, ids: list[str], steps: int, repeats: int) -> dict[str, list[float]]:
    """``{id: [palaestra steps/s, gymnasium steps/s]}`` of one run with ``tree``'s palaestra."""
    env = dict(os.environ, PYTHONPATH=f"{tree / 'src'}{os.pathsep}{BENCHMARKS}")
    argv = [sys.executable, "-c", _CHILD, ",".join(ids), str(steps), str(repeats)]
    return last_json_line(argv, env, BENCHMARKS.parent)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", type=Path, required=True)
    parser.add_argument("--after", type=Path, required=True)
    parser.add_argument("--ids", nargs="+", default=IDS)
    parser.add_argument("--pairs", type=int, default=3)
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    trees = {"before": args.before.resolve(), "after": args.after.resolve()}
    runs: dict[str, list[dict[str, list[float]]]] = {"before": [], "after": []}
    for pair in range(args.pairs):
        order = ["before", "after"] if pair % 2 == 0 else ["after", "before"]
        print(f"pair {pair + 1}: load average {os.getloadavg()[0]:.2f}", flush=True)
        for side in order:
            runs[side].append(run_once(trees[side], args.ids, args.steps, args.repeats))
    print(f"load average at the end {os.getloadavg()[0]:.2f}")
    print("| env id | tree | ratios to Gymnasium (each run) | median | palaestra steps/s "
          "| gymnasium steps/s |")  # fmt: skip
    print("|---|---|---|---:|---:|---:|")
    for env_id in args.ids:
        for side in ("before", "after"):
            rates = [run[env_id] for run in runs[side]]
            ratios = [ours / ref for ours, ref in rates]
            ours = statistics.median(r[0] for r in rates)
            ref = statistics.median(r[1] for r in rates)
            each = ", ".join(f"{r:.2f}" for r in ratios)
            print(f"| `{env_id}` | {side} | {each} | {statistics.median(ratios):.2f}x "
                  f"| {ours:,.0f} | {ref:,.0f} |")  # fmt: skip


if __name__ == "__main__":
    main()
