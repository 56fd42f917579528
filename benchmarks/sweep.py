"""Wall time of a grid of runs: local, one after another, against a local Ray on this
machine's cores; and Ray's overhead per task.

Run from the repository root::

    .venv/bin/python benchmarks/sweep.py               # 2 variants x 8 seeds, PPO CartPole
    .venv/bin/python benchmarks/sweep.py --quick       # 2 x 2 seeds, short runs

The grid is PPO's CartPole-v1 preset (8 envs, 50k steps) and the same with ``gamma=0.95``, on
seeds 0-7: 16 runs, trained by :func:`palaestra.runs.grid.run_grid` with ``backend="local"``
(in this process, one after another) and ``backend="ray"`` (a local Ray, one task per run,
``num_cpus`` = this machine's cores), each into its own folder. Reported: both wall times and
their ratio, the time ``ray.init`` took (paid once per command, not per task), whether the two
backends trained the same bits (every run's weights compared), and the overhead per task: the
cores' seconds of the Ray grid not spent inside ``learn`` (wall x cores - sum of the tasks'
training seconds) over the number of tasks; a second Ray grid of 16 runs of 64 steps each
measures it on tasks that do almost nothing. The load average is printed with the figures.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from palaestra.runs import RunSpec, load_model
from palaestra.runs.grid import GridRun, Outcome, connect_ray, run_grid


def grid(root: Path, seeds: int, steps: int | None) -> list[GridRun]:
    runs = []
    for label, overrides in (("preset", {}), ("gamma0.95", {"hyperparams": {"gamma": 0.95}})):
        for seed in range(seeds):
            spec = RunSpec.from_preset(
                "ppo", "CartPole-v1", seed=seed, n_timesteps=steps, overrides=overrides
            )
            runs.append(GridRun(label, spec, root / label / f"seed{seed}"))
    return runs


def timed(runs: list[GridRun], backend: str) -> tuple[float, list[Outcome]]:
    start = time.perf_counter()
    outcomes = run_grid(runs, backend)
    wall = time.perf_counter() - start
    failed = [o.error for o in outcomes if o.status != "trained"]
    if failed:
        raise SystemExit(f"runs failed: {failed}")
    return wall, outcomes


def same_bits(a: list[GridRun], b: list[GridRun]) -> bool:
    for x, y in zip(a, b):
        ours = load_model(x.run_dir / "model.zip").policy.state_dict()
        theirs = load_model(y.run_dir / "model.zip").policy.state_dict()
        if any(not np.array_equal(v.numpy(), theirs[k].numpy()) for k, v in ours.items()):
            return False
    return True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 x 2 seeds of 5k steps")
    args = parser.parse_args()
    seeds, steps = (2, 5_000) if args.quick else (8, None)
    cores = os.cpu_count() or 1
    root = Path(tempfile.mkdtemp(prefix="palaestra-sweep-bench-"))
    try:
        load_before = os.getloadavg()[0]
        local_runs = grid(root / "local", seeds, steps)
        local_wall, local = timed(local_runs, "local")
        start = time.perf_counter()
        connect_ray(None, num_cpus=cores)
        init_s = time.perf_counter() - start
        ray_runs = grid(root / "ray", seeds, steps)
        ray_wall, remote = timed(ray_runs, "ray")
        train_s = sum(o.seconds for o in remote)
        overhead = (ray_wall * cores - train_s) / len(remote)
        tiny_wall, tiny = timed(grid(root / "tiny", seeds, 64), "ray")
        tiny_overhead = (tiny_wall * cores - sum(o.seconds for o in tiny)) / len(tiny)
        load_after = os.getloadavg()[0]
        n = len(local_runs)
        print(f"grid: PPO CartPole-v1 preset x 2 variants x {seeds} seeds = {n} runs, "
              f"{local_runs[0].spec.n_timesteps:,} steps each; {cores} cores")  # fmt: skip
        print(
            f"local, one after another: {local_wall:7.1f} s "
            f"(median run {statistics.median(o.seconds for o in local):.2f} s of training)"
        )
        print(
            f"ray, {cores} CPUs:              {ray_wall:7.1f} s  -> {local_wall / ray_wall:.2f}x "
            f"(ray.init {init_s:.1f} s, paid once, not included)"
        )
        print(
            f"overhead per task: {overhead:.2f} core-seconds on these runs, "
            f"{tiny_overhead:.2f} on {len(tiny)} runs of 64 steps"
        )
        print(f"same bits on both backends: {same_bits(local_runs, ray_runs)}")
        print(f"load average (1 min): {load_before:.2f} before, {load_after:.2f} after")
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
