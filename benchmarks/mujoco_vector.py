"""MuJoCo batch speed: palaestra's native batch against Gymnasium's SyncVectorEnv and
AsyncVectorEnv and EnvPool's MuJoCo envs, random actions.

Each case runs in a fresh process: warm-up steps, then steps for ``--seconds`` of wall time;
it reports env-steps per wall second and per CPU second, the CPU time being the process's (all
its threads) plus its live children's (AsyncVectorEnv's workers), read with psutil before
closing. EnvPool's tasks are its v4-era ones on its own MuJoCo build (a speed reference only).

    heavy python benchmarks/mujoco_vector.py --envs HalfCheetah-v5 Ant-v5 Hopper-v5 \
        --num-envs 1 8 64 256

Needs ``pip install -r requirements/bench.txt`` for Gymnasium and EnvPool. ``--profile`` prints
the share of a native step (N=64) spent inside MuJoCo's ``mj_step`` (and
``mj_rnePostConstraint`` where the batch calls it). ``--single`` compares one env's
``step`` (``make(id)``, time limit and checks included) with Gymnasium's, both in this run.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

IMPLS = ["palaestra", "palaestra-2t", "gym-sync", "gym-async", "envpool", "envpool-2t"]


def _make(impl: str, env_id: str, n: int):

    if impl.startswith("palaestra"):
        import palaestra

        threads = 2 if impl.endswith("2t") else 1
        env = palaestra.make_vec(env_id, n, num_threads=threads)
        env.reset(seed=0)
        shape = (n, *env.single_action_space.shape)
        return env, shape, lambda a: env.step(a)
    if impl.startswith("gym"):
        import gymnasium

        mode = "sync" if impl == "gym-sync" else "async"
        env = gymnasium.make_vec(env_id, n, vectorization_mode=mode)
        env.reset(seed=0)
        shape = (n, *env.single_action_space.shape)
        return env, shape, lambda a: env.step(a)
    import envpool

    threads = 2 if impl.endswith("2t") else 1
    env = envpool.make_gymnasium(env_id.replace("-v5", "-v4"), num_envs=n, num_threads=threads)
    env.reset()
    shape = (n, *env.action_space.shape)
    return env, shape, lambda a: env.step(a)


def run_case(impl: str, env_id: str, n: int, seconds: float) -> dict:
    """Steps per wall and per CPU second of one implementation (in this process)."""
    import numpy as np
    import psutil

    env, shape, step = _make(impl, env_id, n)
    rng = np.random.default_rng(0)
    actions = [rng.uniform(-1, 1, shape).astype(np.float32) for _ in range(64)]
    for k in range(20):
        step(actions[k % 64])
    me = psutil.Process()

    def cpu() -> float:
        total = sum(me.cpu_times()[:2])
        for child in me.children(recursive=True):
            try:
                total += sum(child.cpu_times()[:2])
            except psutil.NoSuchProcess:
                pass
        return total

    c0, t0, steps = cpu(), time.perf_counter(), 0
    while time.perf_counter() - t0 < seconds:
        for k in range(8):
            step(actions[(steps + k) % 64])
        steps += 8
    wall, cpu_s = time.perf_counter() - t0, cpu() - c0
    env.close()
    return {
        "impl": impl,
        "env": env_id,
        "n": n,
        "sps_wall": steps * n / wall,
        "sps_cpu": steps * n / cpu_s,
    }


def profile(env_id: str, n: int, steps: int = 300) -> dict:
    """Share of a native step's CPU time spent in MuJoCo's calls (the same calls timed bare)."""
    import numpy as np

    import palaestra

    env = palaestra.make_vec(env_id, n)
    env.reset(seed=0)
    batch = env.batch
    rng = np.random.default_rng(0)
    acts = rng.uniform(-1, 1, (steps, n, *env.single_action_space.shape)).astype(np.float32)
    t0 = time.process_time()
    for a in acts:
        env.step(a)
    total = time.process_time() - t0
    import mujoco

    t0 = time.process_time()
    for a in acts:
        for i, d in enumerate(batch._datas):
            d.ctrl[:] = a[i]
            mujoco.mj_step(batch._models[i], d, nstep=batch.frame_skip)
            if batch._post:
                mujoco.mj_rnePostConstraint(batch._models[i], d)
    bare = time.process_time() - t0
    return {
        "env": env_id,
        "n": n,
        "step_cpu_s": total,
        "mujoco_cpu_s": bare,
        "mujoco_share": bare / total,
    }


def single(env_id: str, lib: str, steps: int) -> dict:
    """CPU microseconds per ``step`` of one env made by ``lib.make`` (random float32 actions,
    resets included); the best of 5 blocks."""
    import numpy as np

    if lib == "gymnasium":
        import gymnasium as module
    else:
        import palaestra as module  # type: ignore[no-redef]
    env = module.make(env_id)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    acts = rng.uniform(-1, 1, (256, *env.action_space.shape)).astype(np.float32)
    blocks = []
    for _ in range(6):
        t0 = time.process_time()
        for k in range(steps):
            _, _, terminated, truncated, _ = env.step(acts[k % 256])
            if terminated or truncated:
                env.reset()
        blocks.append((time.process_time() - t0) / steps * 1e6)
    return {"env": env_id, "lib": lib, "us_per_step": min(blocks[1:])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", nargs="+", default=["HalfCheetah-v5", "Ant-v5"])
    parser.add_argument("--num-envs", nargs="+", type=int, default=[1, 8, 64, 256])
    parser.add_argument("--impls", nargs="+", default=IMPLS)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--max-async", type=int, default=64, help="largest N for gym-async")
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--single", action="store_true", help="one env's step vs Gymnasium's")
    parser.add_argument("--case", help=argparse.SUPPRESS)
    parser.add_argument("--single-case", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.single_case:
        env_id, lib = args.single_case.split(",")
        print(json.dumps(single(env_id, lib, 2000)))
        return
    if args.case:
        impl, env_id, n = args.case.split(",")
        print(json.dumps(run_case(impl, env_id, int(n), args.seconds)))
        return
    if args.profile:
        for env_id in args.envs:
            print(json.dumps(profile(env_id, 64)))
        return
    if args.single:
        print(f"load average at start: {os.getloadavg()}")
        for env_id in args.envs:
            out = {}
            for lib in ("palaestra", "gymnasium", "palaestra", "gymnasium"):  # interleaved
                case = [sys.executable, __file__, "--single-case", f"{env_id},{lib}"]
                run = subprocess.run(case, capture_output=True, text=True, check=True)
                us = json.loads(run.stdout.strip().splitlines()[-1])["us_per_step"]
                out[lib] = min(us, out.get(lib, us))
            ours, theirs = out["palaestra"], out["gymnasium"]
            print(
                f"{env_id:15s} palaestra {ours:7.1f} us/step  gymnasium {theirs:7.1f} us/step  "
                f"palaestra's speed {theirs / ours:.2f}x Gymnasium's",
                flush=True,
            )
        print(f"load average at end: {os.getloadavg()}")
        return
    print(f"load average at start: {os.getloadavg()}")
    for env_id in args.envs:
        for n in args.num_envs:
            rows = {}
            for impl in args.impls:
                if impl == "gym-async" and n > args.max_async:
                    continue
                results = []
                for _ in range(args.repeats):
                    out = subprocess.run(
                        [
                            sys.executable,
                            __file__,
                            "--case",
                            f"{impl},{env_id},{n}",
                            "--seconds",
                            str(args.seconds),
                        ],
                        capture_output=True,
                        text=True,
                        check=False,
                    )
                    if out.returncode:
                        print(f"{impl} {env_id} {n}: failed: {out.stderr.strip()[-300:]}")
                        break
                    results.append(json.loads(out.stdout.strip().splitlines()[-1]))
                if results:
                    rows[impl] = (
                        statistics.median(r["sps_wall"] for r in results),
                        statistics.median(r["sps_cpu"] for r in results),
                    )
            base = rows.get("gym-sync")
            for impl, (wall, cpu) in rows.items():
                ratio = (
                    ""
                    if base is None
                    else f"  x{wall / base[0]:.2f} wall  x{cpu / base[1]:.2f} cpu vs gym-sync"
                )
                print(
                    f"{env_id:15s} N={n:<4d} {impl:13s} {wall:10.0f} steps/s wall "
                    f"{cpu:10.0f} steps/cpu-s{ratio}",
                    flush=True,
                )
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
