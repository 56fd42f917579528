"""Batched Pendulum-v1 and Acrobot-v1: palaestra's native batch vs gymnax's jitted vmap step.

Run from the repository root (jax and gymnax: ``pip install -r requirements/bench.txt`` then
``pip install --no-deps -r requirements/bench-no-deps.txt``)::

    .venv/bin/python benchmarks/vs_gymnax.py                            # this tree vs gymnax
    .venv/bin/python benchmarks/vs_gymnax.py --before /tmp/before       # plus an older tree
    .venv/bin/python benchmarks/vs_gymnax.py --profile Acrobot-v1 --sizes 16384
    .venv/bin/python benchmarks/vs_gymnax.py --profile Acrobot-v1 --replay  # per operation

Each contender runs in its own fresh interpreter, in turn, ``--rounds`` times (the figure is
the median): palaestra's ``make_vec(id, n)`` (the native batch with autoreset, Gymnasium API)
from this tree's ``src`` and, with ``--before``, from an older tree's; gymnax's
``jax.jit(jax.vmap(env.step))`` (step plus gymnax's own autoreset) on jax's CPU backend, one
thread (``XLA_FLAGS``, below), compiled before the clock starts and each timed call waited
for (``block_until_ready``). Every contender steps 16 pre-drawn random action batches
(Pendulum: uniform float32 torques in [-2, 2]; Acrobot: ints in {0, 1, 2}; gymnax also gets
pre-split keys), cycled for at least ``--seconds``. Rates are env-steps per CPU second of the
process (``time.process_time``: all its threads), so the load of the shared machine counts
less; the load average is printed beside each table.

``--profile ID`` instead prints cProfile's top functions of this tree's batch step.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path
from typing import Any

from child import last_json_line  # benchmarks/ is on sys.path when run as a script

IDS = ["Pendulum-v1", "Acrobot-v1"]
SIZES = [1024, 16384]
# One host device, no Eigen thread pool: jax's CPU backend on one thread (jax 0.10 honours
# these; an unknown flag would abort the child).
XLA_FLAGS = "--xla_force_host_platform_device_count=1 --xla_cpu_multi_thread_eigen=false"

_PALAESTRA = """
import json, sys, time
import numpy as np
import palaestra
env_id, n, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
env = palaestra.make_vec(env_id, n)
env.reset(seed=0)
rng = np.random.default_rng(0)
if env_id == "Pendulum-v1":
    actions = [rng.uniform(-2, 2, (n, 1)).astype(np.float32) for _ in range(16)]
else:
    actions = [rng.integers(0, 3, n) for _ in range(16)]
for a in actions:
    env.step(a)  # warm-up
steps, start = 0, time.process_time()
while time.process_time() - start < seconds:
    for a in actions:
        env.step(a)
    steps += len(actions)
print(json.dumps(steps * n / (time.process_time() - start)))
"""

_GYMNAX = """
import json, sys, time
import jax, gymnax
env_id, n, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
env, params = gymnax.make(env_id)
reset = jax.vmap(env.reset, in_axes=(0, None))
obs, state = reset(jax.random.split(jax.random.PRNGKey(0), n), params)
step = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
keys = [jax.random.split(jax.random.PRNGKey(100 + i), n) for i in range(16)]
if env_id == "Pendulum-v1":
    draw = [jax.random.PRNGKey(i) for i in range(16)]
    actions = [jax.random.uniform(k, (n,), minval=-2, maxval=2) for k in draw]
else:
    actions = [jax.random.randint(jax.random.PRNGKey(i), (n,), 0, 3) for i in range(16)]
for k, a in zip(keys, actions):  # compile and warm up
    obs, state, reward, terminated, truncated, info = step(k, state, a, params)
jax.block_until_ready(state)
steps, start = 0, time.process_time()
while time.process_time() - start < seconds:
    for k, a in zip(keys, actions):
        obs, state, reward, terminated, truncated, info = step(k, state, a, params)
        jax.block_until_ready(state)
    steps += len(actions)
print(json.dumps(steps * n / (time.process_time() - start)))
"""


def measure(kind: str, tree: Path, env_id: str, n: int, seconds: float) -> float:
    """Env-steps per CPU second of one contender in a fresh interpreter."""
    env = dict(os.environ, PYTHONPATH=str(tree / "src"), XLA_FLAGS=XLA_FLAGS)
    code = _GYMNAX if kind == "gymnax" else _PALAESTRA
    argv = [sys.executable, "-c", code, env_id, str(n), str(seconds)]
    return float(last_json_line(argv, env, tree))


def _env_and_actions(env_id: str, n: int) -> tuple[Any, list[Any]]:
    """This tree's ``make_vec(env_id, n)``, reset, and the 16 action batches the runs cycle."""
    import numpy as np

    import palaestra

    env = palaestra.make_vec(env_id, n)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    if env_id == "Pendulum-v1":
        return env, [rng.uniform(-2, 2, (n, 1)).astype(np.float32) for _ in range(16)]
    return env, [rng.integers(0, 3, n) for _ in range(16)]


def profile(env_id: str, n: int, steps: int) -> None:
    """cProfile's top functions (by own time) of ``steps`` batch steps of this tree."""
    import cProfile
    import pstats

    env, actions = _env_and_actions(env_id, n)
    prof = cProfile.Profile()
    prof.enable()
    for t in range(steps):
        env.step(actions[t % 16])
    prof.disable()
    pstats.Stats(prof).sort_stats("tottime").print_stats(18)


def replay_profile(env_id: str, n: int, steps: int) -> None:
    """Time each replayed operation of the batch step (``_trace.Program``), grouped by kind.

    Each call is timed with ``perf_counter`` (which adds ~0.3 us a call: small calls read
    high), after ``steps`` warm-up steps; the rest of ``_step`` (copies in and out, the trig
    cache's check) is the batch step minus the replay.
    """
    import collections
    import time

    env, actions = _env_and_actions(env_id, n)
    for t in range(steps):
        env.step(actions[t % 16])
    batch = env
    while not hasattr(batch, "_replays"):  # wrappers, then the engine, then the batch
        batch = getattr(batch, "env", None) or getattr(batch, "batch", None) or batch.engine
    chunks = batch._replays()
    spent: collections.Counter[str] = collections.Counter()
    calls: collections.Counter[str] = collections.Counter()
    clock = time.perf_counter
    start = time.process_time()
    for t in range(steps):
        env.step(actions[t % 16])
    whole = (time.process_time() - start) / steps
    for _ in range(steps):
        for _rows, _prog, replay in chunks:
            for fn, fn_args in replay:
                name = getattr(fn, "__name__", type(fn).__name__.strip("_"))
                t0 = clock()
                fn(*fn_args)
                spent[name] += clock() - t0
                calls[name] += 1
    total = sum(spent.values()) / steps
    print(f"whole vector step {whole * 1e3:.3f} ms; replay {total * 1e3:.3f} ms (timed calls)")
    print("| operation | calls/step | ms/step | share of the step |")
    print("|---|---:|---:|---:|")
    for name, sec in spent.most_common():
        ms = sec / steps * 1e3
        print(f"| {name} | {calls[name] // steps} | {ms:.3f} | {ms / (whole * 1e3):.0%} |")


def _fmt(rate: float) -> str:
    return f"{rate / 1e6:.2f}M"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, help="an older tree's root, measured alongside")
    parser.add_argument("--env", action="append", choices=IDS, help="only this id (repeatable)")
    parser.add_argument("--sizes", help="comma-separated numbers of envs (default 1024,16384)")
    parser.add_argument("--seconds", type=float, default=1.5, help="CPU seconds per run")
    parser.add_argument("--rounds", type=int, default=3, help="runs per contender (median)")
    parser.add_argument("--profile", choices=IDS, help="profile this id's batch step instead")
    parser.add_argument("--steps", type=int, default=300, help="steps profiled")
    parser.add_argument(
        "--replay", action="store_true", help="with --profile: time each replayed operation"
    )
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")] if args.sizes else SIZES
    if args.profile:
        for n in sizes:
            print(f"## {args.profile}, {n} envs, {args.steps} steps")
            (replay_profile if args.replay else profile)(args.profile, n, args.steps)
        return
    here = Path(__file__).resolve().parents[1]
    kinds = [("after", here)] + ([("before", args.before.resolve())] if args.before else [])
    kinds.append(("gymnax", here))
    print(f"load average at start: {os.getloadavg()}")
    head = "| env | envs | " + " | ".join(
        f"{'palaestra ' + k if k != 'gymnax' else 'gymnax'} (M steps/cpu-s)" for k, _ in kinds
    )
    ratios = ["after / gymnax"] + (["before / gymnax", "after / before"] if args.before else [])
    print(head + " | " + " | ".join(ratios) + " |")
    print("|---|---:|" + "---:|" * (len(kinds) + len(ratios)))
    for env_id in args.env or IDS:
        for n in sizes:
            runs: dict[str, list[float]] = {k: [] for k, _ in kinds}
            for r in range(args.rounds):
                order = kinds if r % 2 == 0 else kinds[::-1]  # alternate who goes first
                for kind, tree in order:
                    runs[kind].append(measure(kind, tree, env_id, n, args.seconds))
            med = {k: statistics.median(v) for k, v in runs.items()}
            cells = [_fmt(med[k]) for k, _ in kinds]
            cells.append(f"{med['after'] / med['gymnax']:.2f}x")
            if args.before:
                cells.append(f"{med['before'] / med['gymnax']:.2f}x")
                cells.append(f"{med['after'] / med['before']:.2f}x")
            print(f"| {env_id} | {n} | " + " | ".join(cells) + " |", flush=True)
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
