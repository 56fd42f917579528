"""Vectorized environments: palaestra's native batch against a loop over single envs.

``make_vec_env("CartPole-v1", n_envs=N)`` returns palaestra's *native batch* for built-in ids:
the physics of all N envs advances in one set of numpy operations. ``vec_env_cls=DummyVecEnv``
gives the classic SB3 layout instead: N separate envs stepped one after another in a Python
loop. Both speak the same SB3 ``VecEnv`` API and, seeded alike, produce the same episodes, so
an algorithm cannot tell them apart; only the speed differs. This example shows

1. raw env-steps per second of both at 1, 8, 64 and 256 envs (random actions): palaestra's
   single envs are fast, so a loop keeps up at a few envs; the batch pulls ahead with more;
2. PPO trained on CartPole-v1 with the tuned preset (8 envs) on each: env-steps per second of
   the whole training loop, and the evaluation return of both agents (learning works, and
   with the same seed on both it is the same agent). At 8 envs the network's updates take
   most of the time, so both train at about the same speed; the batch pays off when many
   envs feed the learner (step 1 shows where).

Run::

    .venv/bin/python examples/vectorized_training.py          # ~20 s
    .venv/bin/python examples/vectorized_training.py --quick  # seconds, for the tests
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

import palaestra as gym
from palaestra import presets
from palaestra.vec_env import DummyVecEnv, make_vec_env

ENV_ID = "CartPole-v1"


def make(n_envs: int, native: bool, seed: int) -> Any:
    """The native batch, or a DummyVecEnv loop over ``n_envs`` single envs."""
    if native:
        return make_vec_env(ENV_ID, n_envs=n_envs, seed=seed)
    return make_vec_env(ENV_ID, n_envs=n_envs, seed=seed, vec_env_cls=DummyVecEnv)


def stepping_rate(n_envs: int, native: bool, steps: int) -> float:
    """Env steps per second with random actions (every env counts; autoreset included)."""
    venv = make(n_envs, native, seed=0)
    venv.reset()
    actions = np.random.default_rng(0).integers(0, 2, size=(steps // n_envs, n_envs))
    start = time.perf_counter()
    for row in actions:
        venv.step(row)
    rate = len(actions) * n_envs / (time.perf_counter() - start)
    venv.close()
    return rate


def train(native: bool, timesteps: int, seed: int) -> tuple[float, float, Any]:
    """PPO with the CartPole-v1 preset: (training seconds, mean eval return, model)."""
    from palaestra.algos import PPO, evaluate_policy

    preset = presets.get_preset("ppo", ENV_ID)
    venv = make(preset["n_envs"], native, seed)
    model = PPO(preset["policy"], venv, seed=seed, **presets.resolve(preset["hyperparams"]))
    start = time.perf_counter()
    model.learn(timesteps)
    seconds = time.perf_counter() - start
    env = gym.make(ENV_ID)
    env.reset(seed=10_000 + seed)
    mean, _ = evaluate_policy(model, env, n_eval_episodes=20, deterministic=True)
    return seconds, float(mean), model


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="tiny runs (for the tests)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    import torch

    torch.set_num_threads(1)
    step_budget = 4_096 if args.quick else 200_000
    timesteps = 2_048 if args.quick else presets.get_preset("ppo", ENV_ID)["n_timesteps"]

    print(f"1. stepping {ENV_ID} with random actions ({step_budget} env steps per row)")
    print(f"{'envs':>5s} {'DummyVecEnv steps/s':>20s} {'native steps/s':>15s} {'speed-up':>9s}")
    for n_envs in (1, 8, 64, 256):
        loop = stepping_rate(n_envs, native=False, steps=step_budget)
        batch = stepping_rate(n_envs, native=True, steps=step_budget)
        print(f"{n_envs:5d} {loop:20,.0f} {batch:15,.0f} {batch / loop:8.1f}x")

    print(f"\n2. PPO on {ENV_ID}, preset 'default', {timesteps} steps, seed {args.seed}")
    print(f"{'vec env':12s} {'train s':>8s} {'steps/s':>9s} {'eval return':>12s}")
    params = []
    for native in (False, True):
        seconds, mean, model = train(native, timesteps, args.seed)
        name = "native" if native else "DummyVecEnv"
        print(f"{name:12s} {seconds:8.1f} {timesteps / seconds:9,.0f} {mean:12.1f}")
        params.append(torch.cat([p.detach().flatten() for p in model.policy.parameters()]))
    same = bool(torch.equal(params[0], params[1]))
    print(f"same trained weights from both vec envs: {same}")


if __name__ == "__main__":
    main()
