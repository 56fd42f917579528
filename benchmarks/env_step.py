"""Steps per second of the built-in envs (classic control, toy text, Box2D): palaestra vs
Gymnasium, single and batched.

Run from the repository root::

    .venv/bin/python benchmarks/env_step.py              # full run (~2 minutes)
    .venv/bin/python benchmarks/env_step.py --quick      # smoke run
    .venv/bin/python benchmarks/env_step.py --toy-text   # only the toy-text envs and batches
    .venv/bin/python benchmarks/env_step.py --ids LunarLander-v3   # some single envs only

The Box2D ids (LunarLander, BipedalWalker) are measured when the ``box2d`` package is
installed (Gymnasium's own need it too); they step 5x fewer actions, a Box2D step being
20-100x slower. CarRacing (a drawn frame per step) runs only when named:
``--ids CarRacing-v3 --repeats 5``; it steps 60 actions untimed (the first second zooms in
from far away, a different picture) and times the next 200.

Single envs go through ``make(id)`` in both libraries (so TimeLimit, OrderEnforcing and the
passive checker are included), step pre-sampled ``action_space.sample()`` actions (numpy
scalars/arrays, as the tutorial passes them) and reset when an episode ends. Each figure is the
median of ``--repeats`` runs, both libraries interleaved in one process. Time is the process's
CPU time (``time.process_time``): the shared 2-core machine is busy with other jobs, and wall
time there measured their load as much as ours. The batched engines step ``[N]`` action arrays;
"with resets" also re-samples the rows that terminated (a per-row loop, on reset only).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import time
import warnings
from typing import Any

import numpy as np

import palaestra
from palaestra.envs.classic_control import CartPoleBatch, MountainCarBatch
from palaestra.envs.toy_text import BlackjackBatch, CliffWalkingBatch, FrozenLakeBatch, TaxiBatch

IDS = [
    "CartPole-v0",
    "CartPole-v1",
    "MountainCar-v0",
    "MountainCarContinuous-v0",
    "Pendulum-v1",
    "Acrobot-v1",
]
BOX2D_IDS = [
    "LunarLander-v3",
    "LunarLanderContinuous-v3",
    "BipedalWalker-v3",
    "BipedalWalkerHardcore-v3",
]
FRAME_IDS = ["CarRacing-v3"]  # observations are rendered frames: only with --ids
FRAME_SKIP, FRAME_STEPS = 60, 200  # past the opening zoom, then timed
TOY_TEXT_IDS = [
    "FrozenLake-v1",
    "FrozenLake8x8-v1",
    "CliffWalking-v1",
    "CliffWalkingSlippery-v1",
    "Taxi-v4",
    "Blackjack-v1",
]
CLASSIC_BATCHES = [MountainCarBatch, CartPoleBatch]
TOY_TEXT_BATCHES = [FrozenLakeBatch, CliffWalkingBatch, TaxiBatch, BlackjackBatch]
BATCH_SIZES = [1, 64, 1024, 16384]


def single_rate(lib: Any, env_id: str, actions: list[Any], skip: int = 0) -> float:
    """Steps/s of one env made by ``lib`` over ``actions``, resetting at episode ends; the
    first ``skip`` actions are stepped before the clock starts."""
    env = lib.make(env_id)
    env.reset(seed=0)
    step, reset = env.step, env.reset
    for action in actions[:skip]:
        _, _, terminated, truncated, _ = step(action)
        if terminated or truncated:
            reset()
    actions = actions[skip:]
    start = time.process_time()
    for action in actions:
        _, _, terminated, truncated, _ = step(action)
        if terminated or truncated:
            reset()
    return len(actions) / (time.process_time() - start)


def batch_rate(cls: type, num_envs: int, steps: int, with_resets: bool) -> float:
    """Env-steps/s of a batched engine over pre-sampled actions."""
    engine = cls(num_envs)
    engine.reset(seed=0)
    rng = np.random.default_rng(0)
    n = int(engine.single_action_space.n)
    actions = [rng.integers(0, n, num_envs) for _ in range(min(steps, 64))]
    start = time.process_time()
    for t in range(steps):
        _, _, terminated = engine.step(actions[t % len(actions)])
        if with_resets and terminated.any():
            engine.reset(mask=terminated)
        elif not with_resets and t % 100 == 99:
            engine.reset()  # keep the state in its normal range, outside the timed ratio
    return steps * num_envs / (time.process_time() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--quick", action="store_true", help="few steps, for a smoke test")
    parser.add_argument("--ids", nargs="+", help="only these single-env ids (no batched part)")
    parser.add_argument("--toy-text", action="store_true", help="only the toy-text envs")
    args = parser.parse_args()
    ids = TOY_TEXT_IDS if args.toy_text else IDS + TOY_TEXT_IDS
    batches = TOY_TEXT_BATCHES if args.toy_text else CLASSIC_BATCHES + TOY_TEXT_BATCHES
    if args.quick:
        args.repeats, args.steps = 1, 500
    import gymnasium

    warnings.filterwarnings("ignore", message=".*is out of date")  # CartPole-v0, both libraries

    print(f"numpy {np.__version__}, gymnasium {gymnasium.__version__}, repeats {args.repeats}, "
          f"load average {os.getloadavg()[0]:.2f}")  # fmt: skip
    print(f"{'env id':<26}{'palaestra':>12}{'gymnasium':>12}{'ratio':>8}   (steps/s)")
    ids = ids + (BOX2D_IDS if importlib.util.find_spec("Box2D") and not args.toy_text else [])
    for env_id in args.ids or ids:
        space = gymnasium.make(env_id).action_space
        space.seed(0)
        steps = args.steps // 4 if env_id == "Acrobot-v1" else args.steps
        steps = steps // 5 if env_id in BOX2D_IDS else steps
        skip = FRAME_SKIP if env_id in FRAME_IDS else 0
        steps = skip + FRAME_STEPS if env_id in FRAME_IDS else steps
        actions = [space.sample() for _ in range(steps)]
        ours, ref = [], []
        for _ in range(args.repeats):
            ours.append(single_rate(palaestra, env_id, actions, skip))
            ref.append(single_rate(gymnasium, env_id, actions, skip))
        p, g = statistics.median(ours), statistics.median(ref)
        print(f"{env_id:<26}{p:>12,.0f}{g:>12,.0f}{p / g:>7.2f}x")
    if args.ids:
        print(f"load average at the end {os.getloadavg()[0]:.2f}")
        return

    print(f"\n{'batched engine':<22}{'N':>7}{'step only':>16}{'with resets':>16}   (env-steps/s)")
    for cls in batches:
        for num_envs in BATCH_SIZES:
            steps = max(20, min(2000, 400_000 // num_envs)) if not args.quick else 10
            rates = {}
            for with_resets in (False, True):
                runs = [batch_rate(cls, num_envs, steps, with_resets) for _ in range(args.repeats)]
                rates[with_resets] = statistics.median(runs)
            print(f"{cls.__name__:<22}{num_envs:>7}{rates[False]:>16,.0f}{rates[True]:>16,.0f}")


if __name__ == "__main__":
    main()
