"""Env-steps per second of vector envs: palaestra's engines vs Gymnasium's and SB3's.

Run from the repository root::

    .venv/bin/python benchmarks/vector_step.py           # full run (a few minutes)
    .venv/bin/python benchmarks/vector_step.py --quick   # smoke run
    .venv/bin/python benchmarks/vector_step.py --env CartPole-v1 --sizes 1024 --no-processes --us
    .venv/bin/python benchmarks/vector_step.py --toy-text --sizes 1024 --no-processes --us

For MountainCar-v0 and CartPole-v1 at 8, 64, 1024 and 16384 envs (the toy-text ids with
``--toy-text``: FrozenLake-v1, CliffWalking-v1, Taxi-v4, Blackjack-v1), in one process:

* palaestra native: ``palaestra.make_vec(id, n)`` (the native batch, Gymnasium API, copy=True);
* palaestra native, SB3 API: ``palaestra.vec_env.make_vec_env(id, n)`` (the batch under a
  VecMonitor: list-of-dict infos, as SB3 returns them);
* gymnasium ``SyncVectorEnv`` of ``gymnasium.make(id)`` envs;
* SB3 ``DummyVecEnv`` of ``gymnasium.make(id)`` envs;

and at 8 envs the process-based ones: palaestra ``SubprocVecEnv`` vs SB3's (both with their
default start method, forkserver) and palaestra ``AsyncVectorEnv`` vs gymnasium's (fork).

Every contender steps the same pre-sampled random actions (arrays of ints) with autoreset.
In-process contenders are timed in process CPU time (``time.process_time``; the shared machine
is noisy), process-based ones in wall time (their work happens in the workers). Each figure is
the median of ``--repeats`` timed runs of at least ``--seconds`` each.
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

SIZES = [8, 64, 1024, 16384]
IDS = ["MountainCar-v0", "CartPole-v1"]
TOY_TEXT_IDS = ["FrozenLake-v1", "CliffWalking-v1", "Taxi-v4", "Blackjack-v1"]


def _rate(
    step: Callable[[Any], Any],
    actions: list[np.ndarray],
    n: int,
    seconds: float,
    clock: Callable[[], float],
) -> float:
    """Env-steps/s of ``step`` over cycled ``actions``, run for at least ``seconds``."""
    for a in actions[:2]:
        step(a)  # warm-up
    steps, start = 0, clock()
    while True:
        for a in actions:
            step(a)
        steps += len(actions)
        elapsed = clock() - start
        if elapsed >= seconds:
            return steps * n / elapsed


def _median_rate(
    make: Callable[[], Any],
    reset: str,
    n: int,
    args: argparse.Namespace,
    clock: Callable[[], float] = time.process_time,
) -> float:
    env = make()
    getattr(env, reset)() if reset != "reset_seed" else env.reset(seed=0)
    n_actions = int(
        env.single_action_space.n if hasattr(env, "single_action_space") else env.action_space.n
    )
    rng = np.random.default_rng(0)
    actions = [rng.integers(0, n_actions, n) for _ in range(16)]
    rates = [_rate(env.step, actions, n, args.seconds, clock) for _ in range(args.repeats)]
    env.close()
    return statistics.median(rates)


def in_process(env_id: str, n: int, args: argparse.Namespace) -> dict[str, float]:
    """Rates of the in-process contenders for ``n`` envs."""
    import gymnasium
    from stable_baselines3.common.vec_env import DummyVecEnv as SB3Dummy

    import palaestra
    from palaestra.vec_env import make_vec_env

    def gym_fn() -> Any:
        return gymnasium.make(env_id)

    return {
        "palaestra native": _median_rate(
            lambda: palaestra.make_vec(env_id, n), "reset_seed", n, args
        ),
        "palaestra native (SB3 API)": _median_rate(
            lambda: make_vec_env(env_id, n_envs=n, seed=0), "reset", n, args
        ),
        "gymnasium SyncVectorEnv": _median_rate(
            lambda: gymnasium.vector.SyncVectorEnv([gym_fn] * n), "reset_seed", n, args
        ),
        "SB3 DummyVecEnv": _median_rate(lambda: SB3Dummy([gym_fn] * n), "reset", n, args),
    }


def _pal_env() -> Any:
    import palaestra

    return palaestra.make(_ENV_ID[0])


def _gym_env() -> Any:
    import gymnasium

    return gymnasium.make(_ENV_ID[0])


_ENV_ID = ["MountainCar-v0"]


def processes(env_id: str, n: int, args: argparse.Namespace) -> dict[str, float]:
    """Rates of the process-based contenders (wall time)."""
    import gymnasium
    from stable_baselines3.common.vec_env import SubprocVecEnv as SB3Subproc

    from palaestra.vec_env import SubprocVecEnv
    from palaestra.vector import AsyncVectorEnv

    _ENV_ID[0] = env_id
    wall = time.perf_counter
    return {
        "palaestra SubprocVecEnv": _median_rate(
            lambda: SubprocVecEnv([_pal_env] * n), "reset", n, args, wall
        ),
        "SB3 SubprocVecEnv": _median_rate(
            lambda: SB3Subproc([_gym_env] * n), "reset", n, args, wall
        ),
        "palaestra AsyncVectorEnv": _median_rate(
            lambda: AsyncVectorEnv([_pal_env] * n, context="fork"), "reset_seed", n, args, wall
        ),
        "gymnasium AsyncVectorEnv": _median_rate(
            lambda: gymnasium.vector.AsyncVectorEnv([_gym_env] * n, context="fork"),
            "reset_seed",
            n,
            args,
            wall,
        ),
    }


def _fmt(rate: float) -> str:
    return f"{rate / 1e6:.2f}M" if rate >= 1e6 else f"{rate / 1e3:.1f}k"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="short runs, sizes 8 and 1024")
    parser.add_argument("--seconds", type=float, default=0.4)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--env", action="append", choices=IDS + TOY_TEXT_IDS, help="only this id (repeatable)"
    )
    parser.add_argument("--toy-text", action="store_true", help="the toy-text ids instead")
    parser.add_argument("--sizes", help="comma-separated numbers of envs, e.g. 1024")
    parser.add_argument(
        "--no-processes", action="store_true", help="skip the process-based table (8 envs)"
    )
    parser.add_argument(
        "--us", action="store_true", help="add µs per vector step of native and gymnasium"
    )
    args = parser.parse_args()
    sizes = SIZES
    if args.quick:
        args.seconds, args.repeats, sizes = 0.05, 1, [8, 1024]
    if args.sizes:
        sizes = [int(n) for n in args.sizes.split(",")]
    ids = args.env or (TOY_TEXT_IDS if args.toy_text else IDS)
    warnings.filterwarnings("ignore")

    extra = " native µs/step | gymnasium µs/step |" if args.us else ""
    print(
        "| env | envs | palaestra native | native, SB3 API | gymnasium SyncVectorEnv "
        f"| SB3 DummyVecEnv | native / gymnasium |{extra}"
    )
    print("|---|---:|---:|---:|---:|---:|---:|" + "---:|" * (2 if args.us else 0))
    for env_id in ids:
        for n in sizes:
            r = in_process(env_id, n, args)
            native, gym = r["palaestra native"], r["gymnasium SyncVectorEnv"]
            us = f" {n / native * 1e6:.1f} | {n / gym * 1e6:.0f} |" if args.us else ""
            print(
                f"| {env_id} | {n} | {_fmt(native)} "
                f"| {_fmt(r['palaestra native (SB3 API)'])} "
                f"| {_fmt(gym)} | {_fmt(r['SB3 DummyVecEnv'])} "
                f"| {native / gym:.0f}x |{us}",
                flush=True,
            )
    if args.no_processes:
        return
    print()
    print(
        "| env | envs | palaestra SubprocVecEnv | SB3 SubprocVecEnv | ratio "
        "| palaestra AsyncVectorEnv | gymnasium AsyncVectorEnv | ratio |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for env_id in ids:
        r = processes(env_id, 8, args)
        print(
            f"| {env_id} | 8 | {_fmt(r['palaestra SubprocVecEnv'])} "
            f"| {_fmt(r['SB3 SubprocVecEnv'])} "
            f"| {r['palaestra SubprocVecEnv'] / r['SB3 SubprocVecEnv']:.1f}x "
            f"| {_fmt(r['palaestra AsyncVectorEnv'])} | {_fmt(r['gymnasium AsyncVectorEnv'])} "
            f"| {r['palaestra AsyncVectorEnv'] / r['gymnasium AsyncVectorEnv']:.1f}x |",
            flush=True,
        )


if __name__ == "__main__":
    main()
