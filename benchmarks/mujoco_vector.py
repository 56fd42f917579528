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
``mj_rnePostConstraint`` where the batch calls it), the same for Gymnasium's SyncVectorEnv,
and the bound that MuJoCo's own work puts on the batch's ratio to it. ``--releases`` times
bare ``mj_step`` in EnvPool's bundled MuJoCo 2.2.1 against the installed release on the same
files. ``--single`` compares one env's ``step`` (``make(id)``, time limit and checks
included) with Gymnasium's, both in this run.
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


def profile(env_id: str, n: int, steps: int = 300, rounds: int = 5) -> dict:
    """Where a native step's CPU time goes, and what bounds a bit-exact batch.

    Interleaved rounds of ``steps // rounds`` steps (medians): palaestra's batch step, and
    MuJoCo's calls it makes timed bare over the same ``MjData``; Gymnasium's SyncVectorEnv
    step over the same actions, and its MuJoCo calls timed bare (``mj_step`` and
    ``mj_rnePostConstraint`` on a model per row, as Gymnasium makes them). A batch that made
    only MuJoCo's calls could reach ``gym_step / palaestra_mujoco`` times Gymnasium's speed.
    """
    import mujoco
    import numpy as np

    import palaestra

    env = palaestra.make_vec(env_id, n)
    env.reset(seed=0)
    batch = env.batch
    try:
        import gymnasium

        theirs = gymnasium.make_vec(env_id, n, vectorization_mode="sync")
        theirs.reset(seed=0)
        raw = [e.unwrapped for e in theirs.envs]
    except ImportError:
        theirs = None
    rng = np.random.default_rng(0)
    per = steps // rounds
    acts = rng.uniform(-1, 1, (per, n, *env.single_action_space.shape)).astype(np.float32)

    def ours_step() -> None:
        for a in acts:
            env.step(a)

    def ours_bare() -> None:
        for a in acts:
            for i, d in enumerate(batch._datas):
                d.ctrl[:] = a[i]
                mujoco.mj_step(batch._models[i], d, nstep=batch.frame_skip)
                if batch._post:
                    mujoco.mj_rnePostConstraint(batch._models[i], d)

    def gym_step() -> None:
        for a in acts:
            theirs.step(a)

    def gym_bare() -> None:
        for a in acts:
            for i, e in enumerate(raw):
                e.data.ctrl[:] = a[i]
                mujoco.mj_step(e.model, e.data, nstep=e.frame_skip)
                mujoco.mj_rnePostConstraint(e.model, e.data)

    parts = {"step": ours_step, "mujoco": ours_bare}
    if theirs is not None:
        parts.update(gym_step=gym_step, gym_mujoco=gym_bare)
    times: dict[str, list[float]] = {name: [] for name in parts}
    for _ in range(rounds):
        for name, part in parts.items():
            t0 = time.process_time()
            part()
            times[name].append((time.process_time() - t0) / (per * n) * 1e6)
    us = {name: statistics.median(values) for name, values in times.items()}
    out = {
        "env": env_id,
        "n": n,
        "us_per_env_step": round(us["step"], 2),
        "mujoco_us": round(us["mujoco"], 2),
        "mujoco_share": round(us["mujoco"] / us["step"], 3),
    }
    if theirs is not None:
        out.update(
            gym_us=round(us["gym_step"], 2),
            gym_mujoco_us=round(us["gym_mujoco"], 2),
            gym_mujoco_share=round(us["gym_mujoco"] / us["gym_step"], 3),
            ratio=round(us["gym_step"] / us["step"], 3),
            bound=round(us["gym_step"] / us["mujoco"], 3),
        )
        theirs.close()
    return out


def releases(xml_name: str, calls: int = 20000, rounds: int = 7) -> dict:
    """CPU microseconds per bare ``mj_step`` on the same MJCF file (EnvPool's copy, else
    palaestra's) in EnvPool's bundled MuJoCo 2.2.1 (its C library through ctypes) and in the
    installed ``mujoco``, from the initial state with zero controls; medians of interleaved
    rounds."""
    import ctypes

    import envpool
    import mujoco

    root = os.path.join(os.path.dirname(envpool.__file__), "mujoco")
    xml = os.path.join(root, "assets_gym", xml_name)
    try:
        mujoco.MjModel.from_xml_path(xml)
    except ValueError:  # EnvPool's file is too old for this MuJoCo: palaestra's model for both
        from palaestra.envs.mujoco._base import ASSETS

        xml = str(ASSETS / xml_name)
    lib = ctypes.CDLL(os.path.join(root, "libmujoco.so.2.2.1"))
    lib.mj_loadXML.restype = ctypes.c_void_p
    lib.mj_loadXML.argtypes = [ctypes.c_char_p, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int]
    lib.mj_makeData.restype = ctypes.c_void_p
    lib.mj_makeData.argtypes = [ctypes.c_void_p]
    lib.mj_step.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    message = ctypes.create_string_buffer(1000)
    old_model = lib.mj_loadXML(xml.encode(), None, message, 1000)
    if not old_model:
        raise RuntimeError(f"MuJoCo 2.2.1 cannot load {xml}: {message.value!r}")
    old_data = lib.mj_makeData(old_model)
    model = mujoco.MjModel.from_xml_path(xml)
    data = mujoco.MjData(model)

    def old() -> None:
        for _ in range(calls):
            lib.mj_step(old_model, old_data)

    def new() -> None:
        for _ in range(calls):
            mujoco.mj_step(model, data)

    times: dict[str, list[float]] = {"2.2.1": [], mujoco.__version__: []}
    for _ in range(rounds):
        for name, part in (("2.2.1", old), (mujoco.__version__, new)):
            t0 = time.process_time()
            part()
            times[name].append((time.process_time() - t0) / calls * 1e6)
    us = {name: round(statistics.median(values), 2) for name, values in times.items()}
    speed = round(us[mujoco.__version__] / us["2.2.1"], 3)
    return {"xml": xml, "us_per_mj_step": us, "speed_2.2.1": speed}


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
    parser.add_argument(
        "--releases", action="store_true", help="bare mj_step: EnvPool's MuJoCo 2.2.1 vs ours"
    )
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
    if args.releases:
        print(f"load average at start: {os.getloadavg()}")
        for xml_name in ("half_cheetah.xml", "ant.xml", "hopper.xml"):
            print(json.dumps(releases(xml_name)), flush=True)
        print(f"load average at end: {os.getloadavg()}")
        return
    if args.profile:
        print(f"load average at start: {os.getloadavg()}")
        for env_id in args.envs:
            for n in args.num_envs:
                print(json.dumps(profile(env_id, n)), flush=True)
        print(f"load average at end: {os.getloadavg()}")
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
            # repeats interleave the implementations, so that a burst of load on the shared
            # cores hits them alike
            impls = [
                impl for impl in args.impls if not (impl == "gym-async" and n > args.max_async)
            ]
            results: dict[str, list[dict]] = {impl: [] for impl in impls}
            for _ in range(args.repeats):
                for impl in impls:
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
                        continue
                    results[impl].append(json.loads(out.stdout.strip().splitlines()[-1]))
            rows = {
                impl: (
                    statistics.median(r["sps_wall"] for r in runs),
                    statistics.median(r["sps_cpu"] for r in runs),
                )
                for impl, runs in results.items()
                if runs
            }
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
