"""The tutorial's vectorized-environment blocks, with only their import lines changed.

SB3 imports become ``palaestra.vec_env``; ``gymnasium`` becomes ``palaestra``. The DQN training
block belongs to the algorithms and is tested there; the timing block runs with fewer steps.
"""

from __future__ import annotations

import pytest

BLOCK_SPACES = """
from palaestra.vec_env import DummyVecEnv, SubprocVecEnv
from palaestra.vec_env import make_vec_env
import palaestra as gym
# Create 4 parallel environments
num_envs = 4
vec_env = make_vec_env('MountainCar-v0', n_envs=num_envs)
print(f"Created {num_envs} parallel environments")
print(f"Observation space: {vec_env.observation_space}")
print(f"Action space: {vec_env.action_space}")
"""

BLOCK_STEP = """
from palaestra.vec_env import make_vec_env
import numpy as np
vec_env = make_vec_env('MountainCar-v0', n_envs=4)
# Reset returns observations for all 4 environments
obs = vec_env.reset()
print("Observations shape:", obs.shape)
# Actions for all 4 environments
actions = np.array([0, 1, 2, 1])
obs, rewards, dones, infos = vec_env.step(actions)
print("Rewards:", rewards)
print("Dones:", dones)
"""

BLOCK_CLASSES = """
from palaestra.vec_env import DummyVecEnv
from palaestra.vec_env import SubprocVecEnv
import palaestra as gym
def make_env():
    return gym.make('MountainCar-v0')
# Create 4 environments in same process
envs = [make_env for _ in range(4)]
vec_env = DummyVecEnv(envs)
# Create 4 environments in separate processes
envs = [make_env for _ in range(4)]
vec_env = SubprocVecEnv(envs)
"""

BLOCK_TIMING = """
from palaestra.vec_env import DummyVecEnv, SubprocVecEnv
import palaestra as gym
import time
def make_env():
    return gym.make('MountainCar-v0')
# Test DummyVecEnv
start = time.time()
vec_env_dummy = DummyVecEnv([make_env for _ in range(8)])
vec_env_dummy.reset() # Must reset before stepping
for _ in range(STEPS):
    vec_env_dummy.step([vec_env_dummy.action_space.sample() for _ in range(8)])
dummy_time = time.time() - start
vec_env_dummy.close()
# Test SubprocVecEnv
start = time.time()
vec_env_subproc = SubprocVecEnv([make_env for _ in range(8)])
vec_env_subproc.reset() # Must reset before stepping
for _ in range(STEPS):
    vec_env_subproc.step([vec_env_subproc.action_space.sample() for _ in range(8)])
subproc_time = time.time() - start
vec_env_subproc.close()
print(f"DummyVecEnv time: {dummy_time:.2f}s")
print(f"SubprocVecEnv time: {subproc_time:.2f}s")
print(f"Speedup: {dummy_time/subproc_time:.2f}x")
"""

BLOCK_MAKE = """
from palaestra.vec_env import make_vec_env
from palaestra.vec_env import SubprocVecEnv
# Automatically uses DummyVecEnv by default
vec_env = make_vec_env('MountainCar-v0', n_envs=8)
# Or explicitly choose SubprocVecEnv for computationally intensive environments
vec_env = make_vec_env('MountainCar-v0', n_envs=8, vec_env_cls=SubprocVecEnv)
"""


def _run(block: str, **env: object) -> None:
    exec(compile(block, "<tutorial>", "exec"), {"__name__": "tutorial", **env})


def test_spaces_block(capsys):
    _run(BLOCK_SPACES)
    assert capsys.readouterr().out == (
        "Created 4 parallel environments\n"
        "Observation space: Box([-1.2  -0.07], [0.6  0.07], (2,), float32)\n"
        "Action space: Discrete(3)\n"
    )


def test_step_block_prints_the_tutorials_shapes(capsys):
    _run(BLOCK_STEP)
    assert capsys.readouterr().out == (
        "Observations shape: (4, 2)\nRewards: [-1. -1. -1. -1.]\nDones: [False False False False]\n"
    )


@pytest.mark.timeout(120)
def test_class_and_make_blocks_run():
    import gc

    import psutil

    before = {p.pid for p in psutil.Process().children(recursive=True)}
    _run(BLOCK_CLASSES)
    _run(BLOCK_MAKE)
    gc.collect()  # the blocks never close their SubprocVecEnvs: collection must reap them
    helpers = ("forkserver", "resource_tracker")  # multiprocessing's own long-lived helpers
    workers = [
        p
        for p in psutil.Process().children(recursive=True)
        if p.pid not in before and not any(h in " ".join(p.cmdline()) for h in helpers)
    ]
    psutil.wait_procs(workers, timeout=10)
    assert not [p for p in workers if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]


@pytest.mark.timeout(120)
def test_timing_block_runs(capsys):
    _run(BLOCK_TIMING, STEPS=100)
    out = capsys.readouterr().out
    assert "DummyVecEnv time:" in out and "Speedup:" in out
