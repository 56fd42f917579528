"""Start-up: how long palaestra takes before its first env step, against Stable-Baselines3.

Run from the repository root::

    .venv/bin/python benchmarks/startup.py              # 5 repeats (about a minute)
    .venv/bin/python benchmarks/startup.py --repeats 9

Every case runs in a fresh interpreter (``sys.executable``), timed from just before the process
is started to its exit ("all told": interpreter start, imports, the work, interpreter
shutdown); cases that build a model also report "ready", the time until the statement finished
(the child prints the clock, ``time.time()``, then exits):

* ``import palaestra``; ``import palaestra.algos`` against ``import stable_baselines3`` (both
  import torch);
* ``PPO("MlpPolicy", "CartPole-v1")`` from ``palaestra.algos`` against the same from
  ``stable_baselines3`` (target: palaestra ready within 2.5 s);
* ``palaestra train ppo CartPole-v1 --timesteps 2048 --out TMP`` (8 envs, then a 10-episode
  evaluation, the model and checkpoint saved, the learning curve drawn in the background; target
  within 6 s all told) against SB3's ``PPO("MlpPolicy", "CartPole-v1").learn(2048)`` (1 env, no
  saving, no evaluation; one torch thread, as ``palaestra train`` and the training benchmarks
  use: with torch's default threads SB3 took 40 s here under load): the nearest SB3 has to a
  command. Before the next measurement starts,
  the background drawing of ``learning_curve.png`` is waited for (its time from start is
  printed), so it does not slow the next case.

The repeats interleave the cases (one of each per round), so load changes reach them alike;
each cell is the median and the min–max over the repeats; a ratio is palaestra / SB3 of the
medians. The children run with bytecode caching on (``PYTHONDONTWRITEBYTECODE`` removed, as
after ``pip install``) after one warm-up round that is not counted. The load average
(``os.getloadavg``) is printed at the start and the end: this machine has 2 cores shared with
other work, so the figures move with it.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

# The child prints the wall clock when its work is done (before interpreter shutdown).
DONE = "import time; print(time.time(), flush=True)"


@dataclass(frozen=True)
class Case:
    name: str
    argv: tuple[str, ...]  # after sys.executable; "{out}" is a fresh folder
    reference: str = ""  # the SB3 case it is compared with


def _code(statement: str) -> tuple[str, ...]:
    return ("-c", f"{statement}\n{DONE}")


BUILD = 'PPO("MlpPolicy", "CartPole-v1")'
SB3 = "from stable_baselines3 import PPO"
CASES = [
    Case("import palaestra", _code("import palaestra")),
    Case("import palaestra.algos", _code("import palaestra.algos"), "import stable_baselines3"),
    Case("import stable_baselines3", _code("import stable_baselines3")),
    Case("palaestra PPO(...)", _code(f"from palaestra.algos import PPO; {BUILD}"), "SB3 PPO(...)"),
    Case("SB3 PPO(...)", _code(f"{SB3}; {BUILD}")),
    Case(
        "palaestra train (2048 steps)",
        ("-m", "palaestra", "train", "ppo", "CartPole-v1", "--timesteps", "2048", "--out", "{out}"),
        "SB3 PPO(...).learn(2048)",
    ),
    Case(
        "SB3 PPO(...).learn(2048)",
        _code(f"import torch\ntorch.set_num_threads(1)\n{SB3}; {BUILD}.learn(2048)"),
    ),
]


def run_once(case: Case, env: dict[str, str]) -> tuple[float, float | None, float | None]:
    """(all told, ready, learning curve on disk) in seconds from the start of the process."""
    folder = Path(tempfile.mkdtemp(prefix="palaestra-startup-"))
    out = folder / "run"
    argv = [sys.executable, *(a.replace("{out}", str(out)) for a in case.argv)]
    start_clock, start = time.time(), time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, env=env, check=False)
    total = time.perf_counter() - start
    if proc.returncode != 0:
        raise RuntimeError(f"{case.name} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    ready = None
    if case.argv[0] == "-c" and "PPO" in case.argv[1]:
        ready = float(proc.stdout.split()[-1]) - start_clock
    curve = None
    if "train" in case.argv:
        png = out / "learning_curve.png"
        while not png.exists() and time.perf_counter() - start < total + 60:
            time.sleep(0.02)
        curve = time.perf_counter() - start if png.exists() else None
    shutil.rmtree(folder, ignore_errors=True)
    return total, ready, curve


def _cell(values: list[float]) -> str:
    if not values:
        return ""
    return f"{statistics.median(values):.2f} s ({min(values):.2f}–{max(values):.2f})"


def main() -> None:
    """Measure every case ``--repeats`` times, interleaved; print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    load_start = os.getloadavg()
    for case in CASES:  # warm-up round: bytecode caches, the disk cache
        run_once(case, env)
    results: dict[str, list[tuple[float, float | None, float | None]]] = {c.name: [] for c in CASES}
    for _ in range(args.repeats):
        for case in CASES:
            results[case.name].append(run_once(case, env))
    load_end = os.getloadavg()

    def median(name: str, column: int) -> float:
        return statistics.median(r[column] or 0.0 for r in results[name])

    def ratio(case: Case, column: int) -> str:
        if not case.reference or results[case.name][0][column] is None:
            return ""
        return f"{median(case.name, column) / median(case.reference, column):.2f}x"

    print(
        f"{args.repeats} repeats; load average (1 min, 5 min) at start {load_start[0]:.2f}, "
        f"{load_start[1]:.2f}; at end {load_end[0]:.2f}, {load_end[1]:.2f}"
    )
    print("| case | all told: median (min–max) | ratio | ready: median (min–max) | ratio |")
    print("|---|---:|---:|---:|---:|")
    for case in CASES:
        rows = results[case.name]
        total = _cell([r[0] for r in rows])
        ready = _cell([r[1] for r in rows if r[1] is not None])
        print(f"| {case.name} | {total} | {ratio(case, 0)} | {ready} | {ratio(case, 1)} |")
        curves = [r[2] for r in rows if r[2] is not None]
        if "train" in case.argv:
            print(f"| learning_curve.png on disk ({len(curves)}/{len(rows)}) | {_cell(curves)} |||")


if __name__ == "__main__":
    main()
