"""Training speed of two palaestra trees, alternated: is a restructuring free?

Run from the repository root, with a worktree of the "before" commit::

    git worktree add /tmp/before bf45ed5
    .venv/bin/python benchmarks/before_after.py --before /tmp/before --after . --pairs 5

Each pair runs every case of ``benchmarks/train_speed.py`` once on the before tree and once on
the after tree (the starting tree alternates between pairs), each run in a fresh interpreter
whose ``palaestra`` comes from that tree's ``src``. The case definitions are this tree's, so
both trees train the same settings. Printed per case: palaestra env-steps per CPU second of
each run, the median over the pairs on each side, the after/before ratio of the medians and
the median and range of the per-pair ratios (each pair ran under the same load), with the
load average beside each run. ``--scale K`` times K times each case's steps: longer runs, less
noise. SB3 runs once per
case at the start and once at the end, in the after tree's interpreter: a drift between the
two says the machine's load changed during the measurement.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

from child import last_json_line  # benchmarks/ is on sys.path when run as a script

BENCHMARKS = Path(__file__).resolve().parent

_CHILD = """
import dataclasses, json, sys, torch
import train_speed
torch.set_num_threads(1)
case = next(c for c in train_speed.CASES if c.name == sys.argv[1])
case = dataclasses.replace(case, steps=case.steps * int(sys.argv[3]))
cpu_rate, _ = train_speed.measure(sys.argv[2], case)
print(json.dumps(cpu_rate))
"""


def run_once(tree: Path, case: str, lib: str = "palaestra", scale: int = 1) -> float:
    """Env-steps per CPU second of one ``learn`` of ``case`` (its timed steps times
    ``scale``) with ``tree``'s palaestra."""
    env = dict(os.environ, PYTHONPATH=f"{tree / 'src'}{os.pathsep}{BENCHMARKS}")
    return float(last_json_line([sys.executable, "-c", _CHILD, case, lib, str(scale)], env, tree))


def run_sb3(tree: Path, case: str, scale: int, when: str) -> float:
    """SB3's rate on ``case``, printed at once (a run cut short keeps what it measured)."""
    rate = run_once(tree, case, "sb3", scale)
    print(
        f"sb3 {when:5s} {case:16s} {rate:9,.0f} steps/cpu-s  load {os.getloadavg()[0]:.2f}",
        flush=True,
    )
    return rate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True, help="the before tree's root")
    parser.add_argument("--after", type=Path, required=True, help="the after tree's root")
    parser.add_argument("--pairs", type=int, default=5)
    parser.add_argument("--cases", nargs="+", default=None)
    parser.add_argument(
        "--scale", type=int, default=1, help="time this many times each case's steps (less noise)"
    )
    args = parser.parse_args()
    sys.path.insert(0, str(BENCHMARKS))
    import train_speed

    names = args.cases or [case.name for case in train_speed.CASES]
    trees = {"before": args.before.resolve(), "after": args.after.resolve()}
    sb3_start = {name: run_sb3(trees["after"], name, args.scale, "start") for name in names}
    rates: dict[str, dict[str, list[float]]] = {n: {"before": [], "after": []} for n in names}
    for pair in range(args.pairs):
        order = ["before", "after"] if pair % 2 == 0 else ["after", "before"]
        for side in order:
            for name in names:
                rate = run_once(trees[side], name, scale=args.scale)
                rates[name][side].append(rate)
                load = os.getloadavg()[0]
                print(
                    f"pair {pair} {side:6s} {name:16s} {rate:9,.0f} steps/cpu-s  load {load:.2f}",
                    flush=True,
                )
    sb3_end = {name: run_sb3(trees["after"], name, args.scale, "end") for name in names}
    print(
        "\n| case | before (each run) | after (each run) | after/before (medians) "
        "| per-pair ratios: median, range | SB3 start, end |"
    )
    print("|---|---|---|---:|---|---|")
    for name in names:
        before, after = rates[name]["before"], rates[name]["after"]
        ratio = statistics.median(after) / statistics.median(before)
        pairs = [a / b for a, b in zip(after, before)]
        paired = statistics.median(pairs)
        print(
            f"| {name} | {', '.join(f'{r:,.0f}' for r in before)} "
            f"| {', '.join(f'{r:,.0f}' for r in after)} | {ratio:.2f} "
            f"| {paired:.2f}, {min(pairs):.2f}-{max(pairs):.2f} "
            f"| {sb3_start[name]:,.0f}, {sb3_end[name]:,.0f} |"
        )


if __name__ == "__main__":
    main()
