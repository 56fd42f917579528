"""Row-by-row check: palaestra's Pendulum/Acrobot batch equals Gymnasium's single envs.

    .venv/bin/python benchmarks/batch_parity.py --envs 16384 --steps 1000   # the issue-28 check

Row i of the batch (seeded ``seed + i``) and a ``gymnasium.make(id)`` env reset with the same
seed step the same random actions (Pendulum: float32 torques in [-2, 2]; Acrobot: {0, 1, 2});
a row resets when its episode ends (termination or the time limit) on both sides. Every
observation and reward must be the same bits; the first mismatch is printed and exits 1.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def check(env_id: str, n: int, steps: int) -> int:
    """Number of mismatching (row, step) pairs (0: equal everywhere)."""
    import gymnasium

    from palaestra.envs.classic_control.acrobot import AcrobotBatch
    from palaestra.envs.classic_control.pendulum import PendulumBatch

    batch = (PendulumBatch if env_id == "Pendulum-v1" else AcrobotBatch)(n)
    limit = 200 if env_id == "Pendulum-v1" else 500
    rng = np.random.default_rng(0)
    if env_id == "Pendulum-v1":
        actions = rng.uniform(-2, 2, (steps, n, 1)).astype(np.float32)
    else:
        actions = rng.integers(0, 3, (steps, n))
    obs = [batch.reset(seed=0).copy()]
    rewards, elapsed = [], np.zeros(n, dtype=np.int64)
    for t in range(steps):
        o, r, term = batch.step(actions[t])
        elapsed += 1
        obs_t, rew_t = o.copy(), r.copy()
        done = term | (elapsed >= limit)
        if done.any():
            batch.reset(mask=done)
            elapsed[done] = 0
        obs.append(obs_t)
        rewards.append(rew_t)
    bad = 0
    for i in range(n):
        env = gymnasium.make(env_id)
        o, _ = env.reset(seed=i)
        assert o.tobytes() == obs[0][i].tobytes(), (env_id, i, "reset")
        for t in range(steps):
            a = actions[t, i] if env_id == "Pendulum-v1" else int(actions[t, i])
            o, r, term, trunc, _ = env.step(a)
            if o.tobytes() != obs[t + 1][i].tobytes() or r != rewards[t][i]:
                bad += 1
                print(f"{env_id} row {i} step {t}: {o} {r} != {obs[t + 1][i]} {rewards[t][i]}")
                break
            if term or trunc:
                env.reset()
    return bad


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, default=16384)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--env", action="append", choices=["Pendulum-v1", "Acrobot-v1"])
    args = parser.parse_args()
    bad = 0
    for env_id in args.env or ["Pendulum-v1", "Acrobot-v1"]:
        b = check(env_id, args.envs, args.steps)
        print(f"{env_id}: {args.envs} envs x {args.steps} steps, {b} rows differ", flush=True)
        bad += b
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
