"""``palaestra bench``: env steps per second for each classic-control env, one env and the
native batch; Gymnasium's figures beside them when gymnasium is installed.

Each figure is :mod:`palaestra.utils.performance`'s (Gymnasium's benchmarks: random actions
sampled as the env steps, for about ``--seconds`` seconds), the median of a few repeats; both
libraries are measured the same way. This is a quick look at this machine, not the benchmark
suite (``benchmarks/`` in the repository interleaves repeats and records its results).
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import math
import statistics
from collections.abc import Callable
from typing import Any

import palaestra
from palaestra.cli.common import CLIError
from palaestra.utils.performance import benchmark_step, benchmark_vector_step

__all__ = ["CLASSIC_ENVS", "add_parser", "run"]

CLASSIC_ENVS = (
    "CartPole-v1",
    "MountainCar-v0",
    "MountainCarContinuous-v0",
    "Pendulum-v1",
    "Acrobot-v1",
)


def _median(measure: Callable[[], float], repeats: int) -> float:
    return statistics.median(measure() for _ in range(repeats))


def _measure(
    lib: Any, env_id: str, num_envs: int, seconds: float, repeats: int
) -> tuple[float, float, str]:
    """``(one env steps/s, batch steps/s, how the batch was made)`` for ``lib``'s ``make``."""
    env = lib.make(env_id)
    single = _median(lambda: benchmark_step(env, seconds, seed=0), repeats)
    env.close()
    mode = "vector_entry_point" if lib.spec(env_id).vector_entry_point else "sync"
    envs = lib.make_vec(env_id, num_envs=num_envs, vectorization_mode=mode)
    batch = _median(lambda: benchmark_vector_step(envs, seconds, seed=0), repeats)
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
    p.add_argument(
        "--quick", action="store_true", help="shorter measurements and one repeat (seconds)"
    )
    p.add_argument(
        "--num-envs", type=int, default=1024, metavar="N", help="batch size (default: 1024)"
    )
    p.add_argument(
        "--seconds",
        type=float,
        metavar="S",
        help="length of each measurement in seconds (default: 0.5, --quick: 0.1)",
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
    seconds = args.seconds if args.seconds is not None else (0.1 if args.quick else 0.5)
    if not 0 < seconds < math.inf:
        raise CLIError(f"--seconds must be a positive number, got {seconds!r}", "e.g. 0.5")
    if args.num_envs < 1:
        raise CLIError(f"--num-envs must be at least 1, got {args.num_envs!r}", "e.g. 1024")
    for env_id in args.envs:
        palaestra.spec(env_id)  # an unknown id fails before anything is measured
    repeats = 1 if args.quick else 3
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
        ours = _measure(palaestra, env_id, n, seconds, repeats)
        row = [env_id, f"{ours[0]:,.0f}", f"{ours[1]:,.0f}"]
        if gym is not None:
            theirs = _measure(gym, env_id, n, seconds, repeats)
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
        f"env steps per second, median of {repeats} repeat(s) of {seconds:g} s; random actions; "
        f"batch: {n} envs stepped together{' (Gymnasium: sync = a Python loop)' if gym else ''}"
    )
    return 0
