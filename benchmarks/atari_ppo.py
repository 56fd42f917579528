"""A short PPO run on Breakout: does the CnnPolicy path learn on a CPU budget?

Run from the repository root::

    .venv/bin/python benchmarks/atari_ppo.py                      # 250k steps = 1M frames, ~15 min
    .venv/bin/python benchmarks/atari_ppo.py --threads-probe      # torch threads 1 vs 2 only
    .venv/bin/python benchmarks/atari_ppo.py --timesteps 2048 --eval-episodes 2   # smoke

Setup: ``make_atari_env("BreakoutNoFrameskip-v4", n_envs=8, seed=0)`` (SB3's AtariWrapper:
no-op starts, frame skip 4 with max-pool, life loss ends training episodes, fire on reset,
84x84 gray, rewards clipped) + ``VecFrameStack(4)``; RL-Zoo's Atari PPO settings (n_steps
128, n_epochs 4, batch 256, lr 2.5e-4 and clip 0.1 both decaying linearly to 0, ent_coef
0.01, vf_coef 0.5) on a budget of ``--timesteps`` agent steps (each 4 emulator frames).
One torch thread by default: on the shared 2-core machine ``--threads-probe`` measured 261
agent steps/s with 1 thread and 104 with 2 (load average 2.7).

Evaluation: the trained policy (sampling actions, and greedy) and a uniformly random policy,
``--eval-episodes`` full games each (``evaluate_policy`` reads the Monitor under the
AtariWrapper: whole games of 5 lives, unclipped score) on the same env setup with seed 100.
Prints frames, wall time, the machine's load average, and mean +- std of both.

Measured (default command, load average ~2.5-2.8 on 2 shared cores, 1 torch thread):
1,003,520 frames in 722 s (347 agent steps/s); 20 games each: trained, sampled 10.50 +- 7.95,
greedy 9.10 +- 7.03; random 1.50 +- 1.63. (150k steps / 600k frames gave 3.10 +- 1.87 sampled
vs random 1.40 +- 1.56 over 10 games: not yet a clear margin.)
"""

from __future__ import annotations

import argparse
import os
import time
from typing import Any

import numpy as np
import torch

from palaestra.algos import PPO, LinearSchedule, evaluate_policy
from palaestra.vec_env import VecFrameStack, make_atari_env

ENV_ID, N_ENVS = "BreakoutNoFrameskip-v4", 8
SETTINGS: dict[str, Any] = {  # RL-Zoo hyperparams/ppo.yml, atari
    "n_steps": 128,
    "n_epochs": 4,
    "batch_size": 256,
    "learning_rate": LinearSchedule(2.5e-4, 0.0, 1.0),
    "clip_range": LinearSchedule(0.1, 0.0, 1.0),
    "ent_coef": 0.01,
    "vf_coef": 0.5,
}


def make_env(n_envs: int, seed: int) -> Any:
    """Breakout, SB3's Atari recipe, 4 stacked frames."""
    return VecFrameStack(make_atari_env(ENV_ID, n_envs=n_envs, seed=seed), n_stack=4)


class RandomPolicy:
    """Uniform actions through ``predict``, for ``evaluate_policy``."""

    def __init__(self, n_actions: int, seed: int) -> None:
        self.n, self.rng = n_actions, np.random.default_rng(seed)

    def predict(self, obs: np.ndarray, state: Any = None, **_: Any) -> tuple[np.ndarray, Any]:
        """One random action per env."""
        return self.rng.integers(0, self.n, len(obs)), state


def probe_threads(steps: int = 2048) -> dict[int, float]:
    """Seconds of ``learn(steps)`` (rollouts + updates) with 1 and 2 torch threads."""
    times = {}
    for threads in (1, 2, 1, 2):
        model = PPO("CnnPolicy", make_env(N_ENVS, 0), num_threads=threads, seed=0, **SETTINGS)
        model.learn(256)  # warm-up: first allocations, env resets
        start = time.perf_counter()
        model.learn(steps, reset_num_timesteps=False)
        times[threads] = min(times.get(threads, np.inf), time.perf_counter() - start)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=250_000, help="agent steps")
    parser.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    parser.add_argument("--eval-episodes", type=int, default=20)
    parser.add_argument("--threads-probe", action="store_true")
    parser.add_argument("--save", default=None, help="where to save the trained model")
    args = parser.parse_args()
    print(f"torch {torch.__version__}, load average {os.getloadavg()}, {os.cpu_count()} CPUs")
    if args.threads_probe:
        for threads, seconds in probe_threads().items():
            print(f"torch threads {threads}: {2048 / seconds:,.0f} agent steps/s")
        return
    model = PPO(
        "CnnPolicy", make_env(N_ENVS, 0), num_threads=args.threads, seed=0, verbose=0, **SETTINGS
    )
    start = time.perf_counter()
    model.learn(args.timesteps)
    train_s = time.perf_counter() - start
    if args.save:
        model.save(args.save)
    eval_env = make_env(5, 100)
    start = time.perf_counter()
    results = {
        "trained, sampled": evaluate_policy(
            model, eval_env, args.eval_episodes, deterministic=False
        ),
        "trained, greedy": evaluate_policy(model, make_env(5, 100), args.eval_episodes),
        "random": evaluate_policy(RandomPolicy(4, 100), make_env(5, 100), args.eval_episodes),
    }
    eval_s = time.perf_counter() - start
    frames = model.num_timesteps * 4
    print(f"PPO CnnPolicy {ENV_ID}, {N_ENVS} envs, torch threads {args.threads}")
    print(f"trained on {model.num_timesteps:,} agent steps = {frames:,} frames in {train_s:,.0f} s")
    print(f"({model.num_timesteps / train_s:,.0f} steps/s); evaluation {eval_s:,.0f} s")
    print(f"load average after: {os.getloadavg()}")
    print(f"{'policy':<18}{'games':>6}{'mean score':>12}{'std':>8}")
    for name, (mean, std) in results.items():
        print(f"{name:<18}{args.eval_episodes:>6}{mean:>12.2f}{std:>8.2f}")


if __name__ == "__main__":
    main()
