"""The torch learner on a GPU: ``device="cuda"`` for MlpPolicy and CnnPolicy, timed.

Run on a machine with CUDA (from the repository root, palaestra on ``PYTHONPATH``)::

    python benchmarks/device_check.py            # CartPole MLPs, then Breakout CNNs if ale-py
    python benchmarks/device_check.py --only presets   # SAC/TD3/DDPG/A2C presets on cuda

Checks, each printed with its wall time: PPO and DQN ``MlpPolicy`` on CartPole-v1 with
``device="cuda"`` (the learner must be the torch learner with its parameters on the GPU; the
agent is evaluated over 20 deterministic episodes), a save/load round trip onto the CPU with
equal predictions, and PPO ``CnnPolicy`` on Breakout (8 envs, SB3's Atari recipe) on cuda and
on the CPU for the same number of frames. ``--only presets``: the SAC, TD3 and DDPG Pendulum-v1
presets and the A2C CartPole-v1 preset trained on cuda (parameters checked on the GPU, 20
deterministic episodes), each saved on cuda and loaded on the CPU (largest action difference
over 64 observations), and two SAC runs with one seed compared bit for bit.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

import palaestra as gym
from palaestra import presets
from palaestra.algos import A2C, DDPG, DQN, PPO, SAC, TD3, evaluate_policy
from palaestra.algos.learners import TorchLearner
from palaestra.vec_env import VecFrameStack, make_atari_env, make_vec_env

DEVICE = "cuda"
TORCH = {"backend": "torch"}  # what cuda picks anyway; a --device cpu dry run too


def _check_on_cuda(model: object) -> None:
    assert isinstance(model.learner, TorchLearner), model.learner  # type: ignore[attr-defined]
    devices = {p.device.type for p in model.policy.parameters()}  # type: ignore[attr-defined]
    assert devices == {DEVICE}, devices


def cartpole(steps_ppo: int, steps_dqn: int) -> None:
    env = make_vec_env("CartPole-v1", n_envs=8, seed=0)
    start = time.perf_counter()
    ppo = PPO(
        "MlpPolicy",
        env,
        n_steps=32,
        batch_size=256,
        gae_lambda=0.8,
        gamma=0.98,
        n_epochs=20,
        ent_coef=0.0,
        learning_rate=1e-3,
        seed=0,
        device=DEVICE,
        policy_kwargs=TORCH,
    )
    _check_on_cuda(ppo)
    ppo.learn(steps_ppo)
    wall = time.perf_counter() - start
    mean, std = evaluate_policy(ppo, gym.make("CartPole-v1"), n_eval_episodes=20)
    print(
        f"PPO MlpPolicy CartPole-v1 {DEVICE}: {steps_ppo} steps in {wall:.1f} s, "
        f"return {mean:.1f} +- {std:.1f}",
        flush=True,
    )
    with tempfile.TemporaryDirectory() as tmp:
        ppo.save(Path(tmp) / "ppo")
        cpu = PPO.load(Path(tmp) / "ppo", device="cpu")
        obs = np.random.default_rng(0).normal(size=(64, 4)).astype(np.float32) * 0.1
        same = np.array_equal(
            ppo.predict(obs, deterministic=True)[0], cpu.predict(obs, deterministic=True)[0]
        )
        print(
            f"  saved on the device, loaded on the cpu ({cpu.learner.backend} learner): "
            f"same greedy actions on 64 observations: {same}",
            flush=True,
        )
    start = time.perf_counter()
    dqn = DQN(
        "MlpPolicy",
        gym.make("CartPole-v1"),
        learning_starts=1000,
        seed=0,
        device=DEVICE,
        policy_kwargs=TORCH,
    )
    _check_on_cuda(dqn)
    dqn.learn(steps_dqn)
    wall = time.perf_counter() - start
    print(
        f"DQN MlpPolicy CartPole-v1 {DEVICE}: {steps_dqn} steps in {wall:.1f} s "
        f"({dqn._n_updates} updates)",
        flush=True,
    )


PRESET_ALGOS = {"sac": SAC, "td3": TD3, "ddpg": DDPG, "a2c": A2C}


def preset_runs(fraction: float = 1.0) -> None:
    """Each new algorithm's shipped preset, trained with ``device="cuda"``."""
    for algo, env_id in [
        ("sac", "Pendulum-v1"),
        ("td3", "Pendulum-v1"),
        ("ddpg", "Pendulum-v1"),
        ("a2c", "CartPole-v1"),
    ]:
        preset = presets.get_preset(algo, env_id)
        hyper = presets.resolve(preset["hyperparams"])
        hyper["policy_kwargs"] = {**hyper.get("policy_kwargs", {}), **TORCH}
        steps = int(preset["n_timesteps"] * fraction)
        env = make_vec_env(env_id, n_envs=preset["n_envs"], seed=0)
        cls = PRESET_ALGOS[algo]
        start = time.perf_counter()
        model = cls(preset["policy"], env, seed=0, device=DEVICE, **hyper)
        _check_on_cuda(model)
        model.learn(steps)
        wall = time.perf_counter() - start
        mean, std = evaluate_policy(model, gym.make(env_id), n_eval_episodes=20)
        print(
            f"{algo.upper()} {env_id} preset {DEVICE}: {steps} steps in "
            f"{wall:.1f} s, return {mean:.1f} +- {std:.1f}",
            flush=True,
        )
        with tempfile.TemporaryDirectory() as tmp:
            model.save(Path(tmp) / algo)
            cpu = cls.load(Path(tmp) / algo, device="cpu")
            space = model.observation_space
            obs = np.random.default_rng(0).uniform(-1, 1, size=(64, *space.shape))
            here = model.predict(obs.astype(np.float32), deterministic=True)[0]
            there = cpu.predict(obs.astype(np.float32), deterministic=True)[0]
            gap = float(np.max(np.abs(np.asarray(here, float) - np.asarray(there, float))))
            print(
                f"  saved on the device, loaded on the cpu ({cpu.learner.backend} learner): "
                f"largest action difference over 64 observations {gap:.2e}",
                flush=True,
            )
    hashes = []
    for _ in range(2):
        model = SAC(
            "MlpPolicy",
            "Pendulum-v1",
            learning_starts=500,
            seed=3,
            device=DEVICE,
            policy_kwargs=TORCH,
        )
        model.learn(1500)
        params = torch.cat([p.detach().flatten().cpu() for p in model.policy.parameters()])
        hashes.append(params.numpy().tobytes())
    print(f"SAC Pendulum-v1 {DEVICE}, one seed twice: same parameter bits {hashes[0] == hashes[1]}")


def breakout(frames: int) -> None:
    for device in (DEVICE, "cpu"):
        env = VecFrameStack(make_atari_env("BreakoutNoFrameskip-v4", n_envs=8, seed=0), 4)
        model = PPO(
            "CnnPolicy",
            env,
            n_steps=128,
            batch_size=256,
            n_epochs=4,
            learning_rate=2.5e-4,
            clip_range=0.1,
            ent_coef=0.01,
            vf_coef=0.5,
            seed=0,
            device=device,
        )
        if device == DEVICE:
            _check_on_cuda(model)
        model.learn(1024)  # warm-up: cuDNN autotuning, first allocations
        start, before = time.perf_counter(), model.num_timesteps
        model.learn(frames, reset_num_timesteps=False)
        wall = time.perf_counter() - start
        frames = model.num_timesteps - before  # whole rollouts
        print(
            f"PPO CnnPolicy Breakout 8 envs {device}: {frames} steps in {wall:.1f} s "
            f"= {frames / wall:,.0f} steps/s (torch threads {torch.get_num_threads()})",
            flush=True,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ppo-steps", type=int, default=50_000)
    parser.add_argument("--dqn-steps", type=int, default=10_000)
    parser.add_argument("--atari-frames", type=int, default=8_192)
    parser.add_argument("--device", default="cuda", help="cpu: a dry run of the script")
    parser.add_argument("--only", choices=["presets"], help="run only this part")
    parser.add_argument(
        "--fraction", type=float, default=1.0, help="of each preset's steps (a quick dry run)"
    )
    args = parser.parse_args()
    global DEVICE
    DEVICE = args.device
    if DEVICE == "cuda":
        assert torch.cuda.is_available(), "no CUDA device"
        print(f"torch {torch.__version__} on {torch.cuda.get_device_name(0)}", flush=True)
    if args.only == "presets":
        preset_runs(args.fraction)
        return
    cartpole(args.ppo_steps, args.dqn_steps)
    try:
        import ale_py  # noqa: F401
    except ImportError:
        print("ale-py missing: Breakout skipped")
        return
    breakout(args.atari_frames)


if __name__ == "__main__":
    main()
