"""``palaestra bench``: env steps per second for each classic-control env, one env and the
native batch; Gymnasium's figures beside them when gymnasium is installed.

Actions are drawn before the clock starts, so the figures are the env's own cost; each figure
is the median of a few repeats. This is a quick look at this machine, not the benchmark suite
(``benchmarks/`` in the repository interleaves repeats and records its results).
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import statistics
import time
from collections.abc import Callable
from typing import Any

from palaestra.cli.common import CLIError

__all__ = ["CLASSIC_ENVS", "add_parser", "run", "single_env_speed", "vector_env_speed"]

CLASSIC_ENVS = (
    "CartPole-v1",
    "MountainCar-v0",
    "MountainCarContinuous-v0",
    "Pendulum-v1",
    "Acrobot-v1",
)


def single_env_speed(env: Any, steps: int, seed: int = 0) -> float:
    """Steps per second of ``env.step`` with random actions, resetting finished episodes."""
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(min(steps, 1000))]
    env.reset(seed=seed)
    n = len(actions)
    start = time.perf_counter()
    for i in range(steps):
        _, _, terminated, truncated, _ = env.step(actions[i % n])
        if terminated or truncated:
            env.reset()
    return steps / (time.perf_counter() - start)


def vector_env_speed(envs: Any, steps: int, seed: int = 0) -> float:
    """Env steps per second (``steps * num_envs``) of a Gymnasium-API vector env; it resets
    finished envs itself."""
    envs.action_space.seed(seed)
    actions = [envs.action_space.sample() for _ in range(min(steps, 16))]
    envs.reset(seed=seed)
    start = time.perf_counter()
    for i in range(steps):
        envs.step(actions[i % len(actions)])
    return steps * envs.num_envs / (time.perf_counter() - start)


def _median(measure: Callable[[], float], repeats: int) -> float:
    return statistics.median(measure() for _ in range(repeats))


def _measure(
    lib: Any, env_id: str, num_envs: int, steps: int, batch_steps: int, repeats: int
) -> tuple[float, float, str]:
    """``(one env steps/s, batch steps/s, how the batch was made)`` for ``lib``'s ``make``."""
    env = lib.make(env_id)
    single = _median(lambda: single_env_speed(env, steps), repeats)
    env.close()
    mode = "vector_entry_point" if lib.spec(env_id).vector_entry_point else "sync"
    envs = lib.make_vec(env_id, num_envs=num_envs, vectorization_mode=mode)
    # A sync vector env loops over its envs in Python: fewer steps keep the run short.
    n = batch_steps if mode != "sync" else max(batch_steps // 10, 2)
    batch = _median(lambda: vector_env_speed(envs, n), repeats)
    envs.close()
    return single, batch, "native" if mode != "sync" else "sync"


def _ratio(value: float) -> str:
    return f"{value:.1f}x" if value < 10 else f"{value:,.0f}x"


def add_parser(sub: Any) -> None:
    """Register ``bench`` on the subcommand parsers."""
    p = sub.add_parser(
        "bench",
        help="env speed table (steps/s) for the classic-control envs",
        description="Measure env steps per second of each classic-control env: a single env, "
        "and the native batch of --num-envs envs; with gymnasium installed, Gymnasium's "
        "figures and the ratios too.",
    )
    p.add_argument("--quick", action="store_true", help="fewer steps and one repeat (seconds)")
    p.add_argument(
        "--num-envs", type=int, default=1024, metavar="N", help="batch size (default: 1024)"
    )
    p.add_argument(
        "--steps",
        type=int,
        metavar="N",
        help="single-env steps per measurement (default: 20000, --quick: 2000); the batch "
        "makes N/100 steps of all its envs",
    )
    p.add_argument(
        "--envs",
        nargs="+",
        metavar="ID",
        default=list(CLASSIC_ENVS),
        help=f"env ids to measure (default: {' '.join(CLASSIC_ENVS)})",
    )
    p.add_argument(
        "--no-gymnasium", action="store_true", help="skip Gymnasium even when it is installed"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The ``bench`` command."""
    import palaestra

    steps = args.steps if args.steps is not None else (2000 if args.quick else 20000)
    if steps < 1 or args.num_envs < 1:
        raise CLIError("--steps and --num-envs must be positive", "e.g. --steps 2000")
    for env_id in args.envs:
        palaestra.spec(env_id)  # an unknown id fails before anything is measured
    repeats = 1 if args.quick else 3
    batch_steps = max(steps // 100, 2)
    gym = None
    if not args.no_gymnasium and importlib.util.find_spec("gymnasium") is not None:
        gym = importlib.import_module("gymnasium")  # the reference, measured the same way
    n = args.num_envs
    header = ["env", "palaestra 1 env", f"palaestra {n} envs"]
    if gym is not None:
        header[2:2] = ["gymnasium 1 env", "ratio"]
        header += [f"gymnasium {n} envs", "ratio"]
    rows = []
    for env_id in args.envs:
        ours = _measure(palaestra, env_id, n, steps, batch_steps, repeats)
        row = [env_id, f"{ours[0]:,.0f}", f"{ours[1]:,.0f}"]
        if gym is not None:
            theirs = _measure(gym, env_id, n, steps, batch_steps, repeats)
            row[2:2] = [f"{theirs[0]:,.0f}", _ratio(ours[0] / theirs[0])]
            row += [f"{theirs[1]:,.0f} ({theirs[2]})", _ratio(ours[1] / theirs[1])]
        rows.append(row)
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
    print(
        "  ".join(h.rjust(w) if i else h.ljust(w) for i, (h, w) in enumerate(zip(header, widths)))
    )
    for r in rows:
        print("  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))))
    print(
        f"env steps per second, median of {repeats} repeat(s); random actions; "
        f"batch: {n} envs stepped together{' (Gymnasium: sync = a Python loop)' if gym else ''}"
    )
    return 0
