"""Replay memory for Atari DQN: bytes per transition of ``DQN(optimize_memory_usage=True)``.

Run from the repository root (``benchmarks/atari.py --cases memory`` runs the same)::

    .venv/bin/python benchmarks/atari_memory.py            # 100k transitions (~2-4 minutes)
    .venv/bin/python benchmarks/atari_memory.py --quick    # 2k transitions

Fills palaestra's frame buffer with real ``BreakoutNoFrameskip-v4`` transitions
(``make_atari_env`` with SB3's AtariWrapper, life loss ends episodes, ``VecFrameStack(4)``,
8 envs, random actions), the way DQN's loop adds them, and reports the bytes of every array
the buffer holds (``nbytes``; numpy allocates lazily, so this is what a full buffer costs)
against the target: 1.2x the bytes of as many unique 84x84 frames as transitions. Stable-
Baselines3's buffers of the same capacity are built (not filled) for comparison; their
``optimize_memory_usage`` needs ``handle_timeout_termination=False``. Also prints the CPU
time per ``add`` (8 envs) and per ``sample(32)``.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

ENV_ID, N_ENVS, FRAME = "BreakoutNoFrameskip-v4", 8, 84 * 84


def sb3_nbytes(n: int, optimize: bool) -> int:
    """Bytes of the arrays of SB3's ReplayBuffer for ``n`` stacked Breakout transitions."""
    from gymnasium import spaces
    from stable_baselines3.common.buffers import ReplayBuffer

    obs = spaces.Box(0, 255, (84, 84, 4), np.uint8)
    buf = ReplayBuffer(
        n,
        obs,
        spaces.Discrete(4),
        n_envs=N_ENVS,
        optimize_memory_usage=optimize,
        handle_timeout_termination=False,
    )
    arrays = [buf.observations, buf.actions, buf.rewards, buf.dones, buf.timeouts]
    if not optimize:
        arrays.append(buf.next_observations)
    return int(sum(a.nbytes for a in arrays))


def fill(n: int) -> tuple[Any, float, float]:
    """A frame buffer of ``n`` transitions filled from Breakout; (buffer, add us, sample us)."""
    from palaestra.algos.common.frame_replay_buffer import FrameReplayBuffer, frame_layout
    from palaestra.vec_env import VecFrameStack, make_atari_env

    venv = VecFrameStack(make_atari_env(ENV_ID, n_envs=N_ENVS, seed=0), 4)
    space = venv.observation_space
    buf = FrameReplayBuffer(n, space, venv.action_space, N_ENVS, layout=frame_layout(space, venv))
    rng = np.random.default_rng(0)
    obs, add_time = venv.reset(), 0.0
    for _ in range(n // N_ENVS):
        actions = rng.integers(0, 4, N_ENVS)
        new_obs, rewards, dones, infos = venv.step(actions)
        next_obs = new_obs.copy()
        for i in np.flatnonzero(dones):
            next_obs[i] = infos[i]["terminal_observation"]
        timeouts = np.array([bool(info.get("TimeLimit.truncated", False)) for info in infos])
        start = time.process_time()
        buf.add(obs, next_obs, actions, rewards, dones, timeouts)
        add_time += time.process_time() - start
        obs = new_obs
    venv.close()
    buf.sample(32, rng)  # torch's first call initialises itself
    start = time.process_time()
    for _ in range(200):
        buf.sample(32, rng)
    sample_time = (time.process_time() - start) / 200
    return buf, add_time / (n // N_ENVS) * 1e6, sample_time * 1e6


def bench_memory(args: argparse.Namespace) -> None:
    """Bytes of a full buffer vs the 1.2x-unique-frames target and SB3's buffers."""
    n = 2_000 if args.quick else 100_000
    target = 1.2 * n * FRAME
    buf, add_us, sample_us = fill(n)
    ours = buf.nbytes()
    mb = 1e6
    print(f"memory: {n:,} Breakout transitions (84x84x4 uint8 stacks), {N_ENVS} envs")
    print(f"{'':<34}unique frames {n * FRAME / mb:,.1f} MB, target <= {target / mb:,.1f} MB")
    ratio = ours / (n * FRAME)
    verdict = "met" if ours <= target else "MISSED"
    name = "palaestra optimize_memory_usage"
    print(f"{name:<34}{ours / mb:>10,.1f} MB  {ratio:.3f}x frames  ({verdict})")
    print(f"{'':<34}frames stored {buf.stored_frames():,} for {buf.size() * N_ENVS:,} transitions")
    for name, optimize in (("SB3 optimize_memory_usage", True), ("SB3 plain", False)):
        theirs = sb3_nbytes(n, optimize)
        print(f"{name:<34}{theirs / mb:>10,.1f} MB  {theirs / ours:.1f}x palaestra's")
    print(f"{'':<34}add (8 envs) {add_us:.0f} us CPU, sample(32) {sample_us:.0f} us CPU")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2k transitions, for a smoke test")
    bench_memory(parser.parse_args())


if __name__ == "__main__":
    main()
