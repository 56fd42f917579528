"""Does training learn? palaestra against Stable-Baselines3, seed by seed: DQN, PPO, A2C, SAC, TD3.

Run from the repository root::

    .venv/bin/python benchmarks/learning.py                          # everything (long)
    .venv/bin/python benchmarks/learning.py --algo ppo --lib palaestra
    .venv/bin/python benchmarks/learning.py --algo dqn --lib sb3 --seeds 0 1 --jobs 2
    .venv/bin/python benchmarks/learning.py --algo a2c
    .venv/bin/python benchmarks/learning.py --algo continuous         # sac and td3
    .venv/bin/python benchmarks/learning.py --algo gsde               # ppo_sde and sac_sde
    .venv/bin/python benchmarks/learning.py --algo sac_mujoco         # SAC on HalfCheetah-v5

* ``dqn``: MountainCar-v0, the tutorial settings (``learning_rate=1e-3, buffer_size=50000,
  learning_starts=1000, batch_size=128, tau=1.0, gamma=0.99, train_freq=4,
  gradient_steps=1, target_update_interval=250, exploration_fraction=0.2,
  exploration_final_eps=0.05``), ``--steps`` env steps (default 200k). Reported: success rate
  (episodes that reach the flag, i.e. terminate before the 200-step limit) and mean episode
  length over 100 deterministic episodes.
* ``ppo``: CartPole-v1, 8 envs, ``n_steps=32, batch_size=256, gae_lambda=0.8, gamma=0.98,
  n_epochs=20, ent_coef=0.0``, learning rate and clip range decayed linearly from 1e-3 / 0.2 to
  0, ``--ppo-steps`` env steps (default 100k). Reported: mean return over 100 deterministic
  episodes.
* ``a2c``: CartPole-v1, 8 envs, SB3's A2C defaults (``n_steps=5``, RMSprop with
  ``learning_rate=7e-4``, ``gae_lambda=1``, ``ent_coef=0``; RL-Zoo's CartPole setting but for
  its budget), ``--a2c-steps`` env steps (default 200k). Reported: mean return over 100
  deterministic episodes.
* ``sac`` / ``td3``: Pendulum-v1, one env, SB3's defaults but ``learning_rate=1e-3`` (the
  issue's speed and learning setting: 256x256 nets for SAC, 400x300 for TD3, batch 256,
  ``learning_starts=100``, one gradient step per env step, no action noise for TD3),
  ``--continuous-steps`` env steps (default 10k). Reported: mean return over 100 deterministic
  episodes, and per library the mean over seeds with a 95% t-interval.

* ``ppo_sde`` / ``sac_sde``: gSDE with the RL Zoo 2.9.2 hyperparameters, as
  ``rl_zoo3/hyperparams/ppo.yml`` (Pendulum-v1: 4 envs, ``n_steps=1024, gae_lambda=0.95,
  gamma=0.9, n_epochs=10, learning_rate=1e-3, clip_range=0.2, use_sde=True,
  sde_sample_freq=4``, ``--ppo-sde-steps``, default the Zoo's 100k) and ``sac.yml``
  (MountainCarContinuous-v0: ``learning_rate=3e-4, buffer_size=50000, batch_size=512,
  ent_coef=0.1, train_freq=32, gradient_steps=32, gamma=0.9999, tau=0.01,
  learning_starts=0, use_sde=True, log_std_init=-3.67, net_arch=[64, 64], use_expln=True``,
  ``--sac-sde-steps``, default the Zoo's 50k) give them. Reported: mean return over 100
  (Pendulum) / 20 (MountainCarContinuous, 999-step episodes) deterministic episodes, per
  library the interquartile mean over seeds (25% trimmed from each end), whether
  palaestra's is at least SB3's minus 10% of its magnitude, and the ratio of training env
  steps per second (median over seeds).

* ``sac_mujoco``: SAC on HalfCheetah-v5 (MuJoCo), the RL Zoo 2.9.2 ``sac.yml`` settings for
  HalfCheetah-v4 (SB3's SAC defaults) with ``learning_starts=5000`` for a budget of
  ``--sac-mujoco-steps`` (default 15k; the Zoo's is 1M with ``learning_starts=10000``), as
  palaestra's SAC HalfCheetah-v5 preset. Reported like the gSDE cases, over 10 deterministic
  1000-step episodes.

Both libraries run with ``torch.set_num_threads(1)`` and the same env construction: SB3 gets
``gymnasium.make`` / SB3's ``make_vec_env``, palaestra gets ``palaestra.make`` /
``palaestra.vec_env.make_vec_env``. The evaluation env is made the same way, reset with seed
``10_000 + seed`` once and then unseeded. One line per (algo, lib, seed), then a summary.
``--jobs 2`` runs seeds in two processes (wall times then share the machine).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

from tutorial_settings import DQN_KWARGS  # benchmarks/ is on sys.path when run as a script

PPO_N_ENVS = 8
A2C_N_ENVS = 8
EVAL_EPISODES = 100
CONTINUOUS = ("sac", "td3")
GSDE = ("ppo_sde", "sac_sde")
# Compared by interquartile mean like the gSDE cases (the criterion).
IQM_CASES = (*GSDE, "sac_mujoco")
# SAC on HalfCheetah-v5: the RL Zoo 2.9.2 sac.yml HalfCheetah-v4 settings (SB3's SAC defaults:
# 256x256, lr 3e-4, batch 256, buffer 1M, one gradient step per env step, automatic entropy)
# at a budget this shared 2-core machine fits: the Zoo's learning_starts of 10,000 (1% of its
# 1M steps) is cut to 5,000 of 15,000. The same settings as palaestra's SAC HalfCheetah-v5
# preset. 1000-step episodes: 10 deterministic ones are evaluated.
SAC_MUJOCO_KWARGS = {"learning_starts": 5000}
SAC_MUJOCO_EVAL_EPISODES = 10
# Two-sided 95% Student t quantiles by degrees of freedom (n - 1 seeds).
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262}


@dataclass
class Result:
    algo: str
    lib: str
    seed: int
    steps: int
    success: float  # DQN: fraction of episodes reaching the goal; PPO/A2C: nan
    mean_length: float
    mean_return: float
    train_wall_s: float
    train_cpu_s: float

    def line(self) -> str:
        head = f"{self.algo} {self.lib:9s} seed={self.seed} steps={self.steps}"
        if self.algo == "dqn":
            score = f"success={self.success:6.1%} mean_len={self.mean_length:6.1f}"
        else:
            score = f"mean_return={self.mean_return:6.1f} mean_len={self.mean_length:6.1f}"
        timing = f"train wall={self.train_wall_s:6.1f}s cpu={self.train_cpu_s:6.1f}s"
        return f"{head} {score} {timing}"


def linear(start: float) -> Any:
    """``progress_remaining * start``: 0 at the end of training (the zoo's ``lin_`` schedule)."""

    def schedule(progress_remaining: float) -> float:
        return progress_remaining * start

    return schedule


def make_env(lib: str, env_id: str) -> Any:
    if lib == "sb3":
        import gymnasium

        return gymnasium.make(env_id)
    import palaestra

    return palaestra.make(env_id)


def make_vec(lib: str, env_id: str, n_envs: int, seed: int) -> Any:
    if lib == "sb3":
        from stable_baselines3.common.env_util import make_vec_env
    else:
        from palaestra.vec_env import make_vec_env
    return make_vec_env(env_id, n_envs=n_envs, seed=seed)


def algo_class(lib: str, algo: str) -> Any:
    if lib == "sb3":
        import stable_baselines3 as algos
    else:
        import palaestra.algos as algos  # type: ignore[no-redef]
    return getattr(algos, algo.split("_")[0].upper())


def evaluate(model: Any, env: Any, seed: int, episodes: int) -> tuple[float, float, float]:
    """(success rate, mean length, mean return) over deterministic episodes."""
    successes, lengths, returns = 0, [], []
    obs, _ = env.reset(seed=10_000 + seed)
    for _ in range(episodes):
        length, total, done = 0, 0.0, False
        while not done:
            action, _ = model.predict(obs, deterministic=True)
            # Discrete envs take a Python int; Box envs the predicted float32 array as is.
            obs, reward, terminated, truncated, _ = env.step(
                action if action.shape else int(action)
            )
            length += 1
            total += float(reward)
            done = terminated or truncated
        successes += int(terminated)
        lengths.append(length)
        returns.append(total)
        obs, _ = env.reset()
    return successes / episodes, statistics.fmean(lengths), statistics.fmean(returns)


def build(algo: str, lib: str, seed: int) -> tuple[Any, str]:
    cls = algo_class(lib, algo)
    if algo == "ppo_sde":  # rl_zoo3 2.9.2 ppo.yml, Pendulum-v1
        env_id = "Pendulum-v1"
        model = cls(
            "MlpPolicy",
            make_vec(lib, env_id, 4, seed),
            n_steps=1024,
            gae_lambda=0.95,
            gamma=0.9,
            n_epochs=10,
            ent_coef=0.0,
            learning_rate=1e-3,
            clip_range=0.2,
            use_sde=True,
            sde_sample_freq=4,
            seed=seed,
        )
        return model, env_id
    if algo == "sac_sde":  # rl_zoo3 2.9.2 sac.yml, MountainCarContinuous-v0
        env_id = "MountainCarContinuous-v0"
        model = cls(
            "MlpPolicy",
            make_env(lib, env_id),
            learning_rate=3e-4,
            buffer_size=50000,
            batch_size=512,
            ent_coef=0.1,
            train_freq=32,
            gradient_steps=32,
            gamma=0.9999,
            tau=0.01,
            learning_starts=0,
            use_sde=True,
            policy_kwargs=dict(log_std_init=-3.67, net_arch=[64, 64], use_expln=True),
            seed=seed,
        )
        return model, env_id
    if algo == "sac_mujoco":
        env_id = "HalfCheetah-v5"
        model = cls("MlpPolicy", make_env(lib, env_id), seed=seed, **SAC_MUJOCO_KWARGS)
        return model, env_id
    if algo == "dqn":
        env_id = "MountainCar-v0"
        model = cls("MlpPolicy", make_env(lib, env_id), seed=seed, **DQN_KWARGS)
        return model, env_id
    if algo in CONTINUOUS:
        env_id = "Pendulum-v1"
        return cls("MlpPolicy", make_env(lib, env_id), learning_rate=1e-3, seed=seed), env_id
    env_id = "CartPole-v1"
    if algo == "a2c":
        return cls("MlpPolicy", make_vec(lib, env_id, A2C_N_ENVS, seed), seed=seed), env_id
    model = cls(
        "MlpPolicy",
        make_vec(lib, env_id, PPO_N_ENVS, seed),
        n_steps=32,
        batch_size=256,
        gae_lambda=0.8,
        gamma=0.98,
        n_epochs=20,
        ent_coef=0.0,
        learning_rate=linear(1e-3),
        clip_range=linear(0.2),
        seed=seed,
    )
    return model, env_id


def run_one(algo: str, lib: str, seed: int, steps: int) -> Result:
    import torch

    torch.set_num_threads(1)
    model, env_id = build(algo, lib, seed)
    wall, cpu = time.perf_counter(), time.process_time()
    model.learn(total_timesteps=steps)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    episodes = {"sac_sde": 20, "sac_mujoco": SAC_MUJOCO_EVAL_EPISODES}.get(algo, EVAL_EPISODES)
    success, length, ret = evaluate(model, make_env(lib, env_id), seed, episodes)
    return Result(algo, lib, seed, steps, success, length, ret, wall, cpu)


def _run_task(task: tuple[str, str, int, int]) -> Result:
    return run_one(*task)


def mean_ci95(values: list[float]) -> tuple[float, float]:
    """Mean and half-width of its two-sided 95% Student-t confidence interval."""
    mean = statistics.fmean(values)
    if len(values) < 2:
        return mean, math.nan
    half = T95.get(len(values) - 1, 1.96) * statistics.stdev(values) / math.sqrt(len(values))
    return mean, half


def compare_continuous(results: list[Result]) -> None:
    """Per SAC/TD3: each library's mean and 95% CI, and whether palaestra is not worse."""
    for algo in CONTINUOUS:
        ours = [r.mean_return for r in results if r.algo == algo and r.lib == "palaestra"]
        theirs = [r.mean_return for r in results if r.algo == algo and r.lib == "sb3"]
        if not ours or not theirs:
            continue
        our_mean, our_half = mean_ci95(ours)
        sb3_mean, sb3_half = mean_ci95(theirs)
        # "Not worse": our mean at or above the lower end of SB3's interval.
        verdict = "not worse" if our_mean >= sb3_mean - sb3_half else "WORSE"
        print(
            f"{algo}: palaestra {our_mean:.1f} +- {our_half:.1f}, "
            f"sb3 {sb3_mean:.1f} +- {sb3_half:.1f} (95% CI): palaestra {verdict}"
        )


def iqm(values: list[float]) -> float:
    """Interquartile mean: the mean after dropping ``int(n / 4)`` values from each end."""
    ordered = sorted(values)
    cut = len(ordered) // 4
    return statistics.fmean(ordered[cut : len(ordered) - cut])


def compare_iqm(results: list[Result]) -> None:
    """Per gSDE / MuJoCo case: each library's IQM, the issue's criterion and the speed ratio."""
    for algo in IQM_CASES:
        rows = {
            lib: [r for r in results if r.algo == algo and r.lib == lib]
            for lib in ("palaestra", "sb3")
        }
        if not rows["palaestra"] or not rows["sb3"]:
            continue
        ours, theirs = (iqm([r.mean_return for r in rows[lib]]) for lib in ("palaestra", "sb3"))
        ok = ours >= theirs - 0.1 * abs(theirs)
        speed = {
            lib: statistics.median(r.steps / r.train_wall_s for r in rows[lib]) for lib in rows
        }
        # CPU seconds too: on a shared machine the wall clock also counts other processes
        cpu = {lib: statistics.median(r.steps / r.train_cpu_s for r in rows[lib]) for lib in rows}
        print(
            f"{algo}: IQM palaestra {ours:.1f}, sb3 {theirs:.1f} "
            f"({'>=' if ok else 'BELOW'} sb3 - 10%|sb3| = {theirs - 0.1 * abs(theirs):.1f}); "
            f"env-steps/s palaestra {speed['palaestra']:.0f}, sb3 {speed['sb3']:.0f}, "
            f"ratio {speed['palaestra'] / speed['sb3']:.2f}x (per CPU second "
            f"{cpu['palaestra'] / cpu['sb3']:.2f}x)"
        )


def summarise(results: list[Result]) -> None:
    print("\nsummary (median over seeds)")
    for algo in ("dqn", "ppo", "a2c", *CONTINUOUS, *IQM_CASES):
        for lib in ("palaestra", "sb3"):
            rows = [r for r in results if r.algo == algo and r.lib == lib]
            if not rows:
                continue
            seeds = ",".join(str(r.seed) for r in rows)
            wall = statistics.median(r.train_wall_s for r in rows)
            if algo == "dqn":
                rates = [r.success for r in rows]
                per_seed = "/".join(f"{x:.0%}" for x in rates)
                score = f"median success {statistics.median(rates):.0%} ({per_seed})"
            elif algo in CONTINUOUS or algo in IQM_CASES:
                rets = [r.mean_return for r in rows]
                per_seed = "/".join(f"{x:.1f}" for x in rets)
                score = f"median return {statistics.median(rets):.1f} ({per_seed})"
            else:
                rets = [r.mean_return for r in rows]
                good = sum(x >= 475 for x in rets)
                per_seed = "/".join(f"{x:.1f}" for x in rets)
                score = f"{good}/{len(rets)} seeds >= 475 ({per_seed})"
            print(f"{algo} {lib:9s} seeds {seeds}: {score}; median train wall {wall:.1f}s")
    compare_continuous(results)
    compare_iqm(results)


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--steps", type=int, default=200_000, help="DQN env steps")
    parser.add_argument("--ppo-steps", type=int, default=100_000, help="PPO env steps")
    parser.add_argument("--a2c-steps", type=int, default=200_000, help="A2C env steps")
    parser.add_argument(
        "--continuous-steps", type=int, default=10_000, help="SAC and TD3 env steps"
    )
    parser.add_argument("--ppo-sde-steps", type=int, default=100_000, help="PPO gSDE steps")
    parser.add_argument("--sac-sde-steps", type=int, default=50_000, help="SAC gSDE steps")
    parser.add_argument(
        "--sac-mujoco-steps", type=int, default=15_000, help="SAC HalfCheetah-v5 steps"
    )
    parser.add_argument(
        "--algo",
        choices=[
            *("dqn", "ppo", "a2c", "sac", "td3", *IQM_CASES),
            *("gsde", "both", "continuous", "all"),
        ],
        default="both",
        help="both: dqn and ppo; continuous: sac and td3; all: every algorithm",
    )
    parser.add_argument("--lib", choices=["palaestra", "sb3", "both"], default="both")
    parser.add_argument("--jobs", type=int, default=1, help="processes (seeds in parallel)")
    return parser.parse_args()


def main() -> None:
    args = parse_args()
    algos = {
        "both": ["dqn", "ppo"],
        "continuous": list(CONTINUOUS),
        "gsde": list(GSDE),
        "all": ["dqn", "ppo", "a2c", *CONTINUOUS],
    }.get(args.algo, [args.algo])
    libs = ["palaestra", "sb3"] if args.lib == "both" else [args.lib]
    budget = {
        "dqn": args.steps,
        "ppo": args.ppo_steps,
        "a2c": args.a2c_steps,
        "sac": args.continuous_steps,
        "td3": args.continuous_steps,
        "ppo_sde": args.ppo_sde_steps,
        "sac_sde": args.sac_sde_steps,
        "sac_mujoco": args.sac_mujoco_steps,
    }
    tasks = [
        (algo, lib, seed, budget[algo]) for algo in algos for seed in args.seeds for lib in libs
    ]
    results: list[Result] = []
    if args.jobs > 1:
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            for result in pool.map(_run_task, tasks):
                print(result.line(), flush=True)
                results.append(result)
    else:
        for task in tasks:
            result = _run_task(task)
            print(result.line(), flush=True)
            results.append(result)
    summarise(results)


if __name__ == "__main__":
    main()
