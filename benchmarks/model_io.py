"""Model files: save and load seconds and peak memory, palaestra against Stable-Baselines3.

The model is SB3's large-model test's, ``TD3("MlpPolicy", "Pendulum-v1",
policy_kwargs=dict(net_arch=[w, w, w]), device="cpu")``, at several widths ``w`` (an untrained
TD3 file holds its actor, twin critics and their targets: about 12 w**2 float32 weights), or
with ``--algo ppo`` the same with PPO (its actor and critic: about 4 w**2 weights). Each
measurement runs in a fresh interpreter, so one library's memory never counts against the
other's: one process builds the model and times ``save``; another times ``load`` of that file
(the model is rebuilt from the file, so loading includes building the networks, on both sides).
Peak memory is the highest resident size sampled every 2 ms during the call, less the size just
before it: for ``save`` what the call adds over the model, for ``load`` the model plus what the
call adds. Repeats alternate the two libraries; each figure is a median.

    python benchmarks/model_io.py                      # widths 64 1024 2048 4096, 3 repeats
    python benchmarks/model_io.py --widths 8192 --repeats 3
    python benchmarks/model_io.py --algo ppo --widths 7072 --repeats 3

Needs stable-baselines3 (a dev dependency).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
from pathlib import Path

from child import last_json_line  # benchmarks/ is on sys.path when run as a script

CHILD = r"""
import json, os, sys, threading, time

def rss():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")

def measured(fn):
    base, peak, done = rss(), [0], [False]
    def sample():
        while not done[0]:
            peak[0] = max(peak[0], rss())
            time.sleep(0.002)
    thread = threading.Thread(target=sample, daemon=True)
    thread.start()
    start = time.perf_counter()
    result = fn()
    seconds = time.perf_counter() - start
    done[0] = True
    thread.join()
    peak[0] = max(peak[0], rss())
    return result, seconds, peak[0] - base

lib, op, width, path, algo = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5]
import torch
torch.set_num_threads(1)
if lib == "sb3":
    import gymnasium as gym
    import stable_baselines3 as algos
    env = gym.make("Pendulum-v1")
else:
    import palaestra.algos as algos
    env = "Pendulum-v1"
Algo = getattr(algos, algo.upper())
kwargs = dict(policy_kwargs=dict(net_arch=[width] * 3), device="cpu")
if op == "save":
    model = Algo("MlpPolicy", env, **kwargs)
    _, seconds, peak = measured(lambda: model.save(path))
else:
    model, seconds, peak = measured(lambda: Algo.load(path, env=env, **kwargs))
weights = sum(p.numel() for p in model.policy.parameters())
print(json.dumps({"seconds": seconds, "peak": peak, "weights": weights}))
"""


def run(lib: str, op: str, width: int, path: Path, algo: str) -> dict[str, float]:
    """One measurement in a fresh interpreter."""
    argv = [sys.executable, "-c", CHILD, lib, op, str(width), str(path), algo]
    return last_json_line(argv, {**os.environ, "OMP_NUM_THREADS": "1"})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--widths", type=int, nargs="+", default=[64, 1024, 2048, 4096])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--algo", choices=["td3", "ppo"], default="td3")
    args = parser.parse_args()
    mib = 1 << 20
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    header = (
        f"| {args.algo} net_arch | file | lib | save s | load s | save peak extra | load peak | "
        "save ratio | load ratio |"
    )
    print(header)
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for width in args.widths:
            results: dict[str, dict[str, list[float]]] = {}
            sizes = {}
            for _ in range(args.repeats):
                for lib in ("palaestra", "sb3"):
                    path = Path(tmp) / f"{lib}_{width}.zip"
                    saved = run(lib, "save", width, path, args.algo)
                    loaded = run(lib, "load", width, path, args.algo)
                    sizes[lib] = path.stat().st_size
                    path.unlink()
                    r = results.setdefault(lib, {"save": [], "load": [], "sp": [], "lp": []})
                    r["save"].append(saved["seconds"])
                    r["load"].append(loaded["seconds"])
                    r["sp"].append(saved["peak"])
                    r["lp"].append(loaded["peak"])
            med = {
                lib: {k: statistics.median(v) for k, v in r.items()} for lib, r in results.items()
            }
            for lib in ("palaestra", "sb3"):
                m = med[lib]
                ratio = (
                    f"{m['save'] / med['sb3']['save']:.2f}x | {m['load'] / med['sb3']['load']:.2f}x"
                    if lib == "palaestra"
                    else " | "
                )
                print(
                    f"| [{width}]*3 | {sizes[lib] / mib:.1f} MiB | {lib} | {m['save']:.3f} | "
                    f"{m['load']:.3f} | {m['sp'] / mib:.0f} MiB | {m['lp'] / mib:.0f} MiB | "
                    f"{ratio} |",
                    flush=True,
                )
            for lib in ("palaestra", "sb3"):
                runs = ", ".join(
                    f"{a:.3f}/{b:.3f}" for a, b in zip(results[lib]["save"], results[lib]["load"])
                )
                print(f"<!-- [{width}]*3 {lib} save/load s, each run: {runs} -->", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
