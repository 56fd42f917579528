"""Does reward shaping help DQN on MountainCar? The tutorial's experiment, with statistics.

The getting-started tutorial trains one DQN per variant and compares 10 evaluation episodes
of each. One seed per variant cannot tell a real effect from luck: DQN on MountainCar varies a
lot from seed to seed. This example runs the same three variants properly:

* ``baseline``: MountainCar-v0's own reward (-1 per step);
* ``naive``: + ``0.5 * (position + 1.2)`` per step, a bonus for height on *either* hill (the
  tutorial's ``NaiveRewardShaping``, which invites reward hacking);
* ``progress``: + ``10 * (new rightmost position - old)``, a bonus only for new rightward
  progress (the tutorial's ``BetterRewardShaping``).

Every variant trains DQN with the same hyperparameters (palaestra's tuned ``MountainCar-v0``
preset) on several seeds. The shaping wrappers sit *outside* the ``Monitor`` that
``make_vec_env`` adds, so the learning curves show the true return (-episode length) for all
variants. Each trained agent plays 100 deterministic episodes on the unshaped env. Printed:
per variant the mean final return with its 95% confidence interval over seeds (Student t),
the success rate (episodes that reach the flag) and the training time; plotted: the learning
curves of all variants, mean over seeds with a 95% band, in ``learning_curves.png``.

Run::

    .venv/bin/python examples/reward_shaping.py                 # 3 variants x 5 seeds, minutes
    .venv/bin/python examples/reward_shaping.py --seeds 0 1 2 --variants baseline progress
    .venv/bin/python examples/reward_shaping.py --quick         # seconds, for the tests
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any, NamedTuple, SupportsFloat

import numpy as np

import palaestra as gym
from palaestra import presets
from palaestra.algos.callbacks import BaseCallback
from palaestra.runs.curves import Episodes, plot_compare, variant_band
from palaestra.runs.stats import confidence_interval

ENV_ID = "MountainCar-v0"


class NaiveRewardShaping(gym.RewardWrapper):
    """Bonus for height on either hill: the agent can collect it without reaching the flag."""

    def reward(self, reward: SupportsFloat) -> float:
        position = self.env.unwrapped.state[0]
        return float(reward) + (position + 1.2) * 0.5


class ProgressRewardShaping(gym.RewardWrapper):
    """Bonus only for reaching a new rightmost position in the episode."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.best_position = -1.2

    def reset(self, **kwargs: Any) -> Any:
        self.best_position = -1.2
        return self.env.reset(**kwargs)

    def reward(self, reward: SupportsFloat) -> float:
        position = self.env.unwrapped.state[0]
        if position > self.best_position:
            bonus = (position - self.best_position) * 10
            self.best_position = position
            return float(reward) + bonus
        return float(reward)


VARIANTS: dict[str, Any] = {
    "baseline": None,
    "naive": NaiveRewardShaping,
    "progress": ProgressRewardShaping,
}


class EpisodeRecorder(BaseCallback):
    """Every finished training episode: env steps so far, true return, length, success."""

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[tuple[int, float, int, bool]] = []

    def _on_step(self) -> bool:
        for done, info in zip(self.locals["dones"], self.locals["infos"]):
            if done and "episode" in info:
                success = not info.get("TimeLimit.truncated", False)
                self.rows.append(
                    (self.num_timesteps, info["episode"]["r"], info["episode"]["l"], success)
                )
        return True

    def episodes(self) -> Episodes:
        rows = np.array(self.rows, dtype=float).reshape(-1, 4)
        return Episodes(rows[:, 0], rows[:, 1], rows[:, 2].astype(int), rows[:, 3] > 0)


class Result(NamedTuple):
    variant: str
    seed: int
    mean_return: float  # over the evaluation episodes, on the unshaped env
    success: float  # fraction of evaluation episodes that reach the flag
    train_s: float
    curve: Episodes


def train_and_evaluate(variant: str, seed: int, preset: dict[str, Any], episodes: int) -> Result:
    """Train DQN on ``variant``'s env with ``seed``; evaluate on plain MountainCar-v0."""
    from palaestra.algos import DQN, evaluate_policy
    from palaestra.vec_env import make_vec_env

    venv = make_vec_env(ENV_ID, n_envs=preset["n_envs"], seed=seed, wrapper_class=VARIANTS[variant])
    model = DQN(preset["policy"], venv, seed=seed, **presets.resolve(preset["hyperparams"]))
    recorder = EpisodeRecorder()
    start = time.perf_counter()
    model.learn(preset["n_timesteps"], callback=recorder)
    train_s = time.perf_counter() - start
    env = gym.make(ENV_ID)
    env.reset(seed=10_000 + seed)
    returns, lengths = evaluate_policy(
        model, env, n_eval_episodes=episodes, deterministic=True, return_episode_rewards=True
    )
    limit = env.spec.max_episode_steps if env.spec else 200
    success = float(np.mean([n < limit for n in lengths]))
    return Result(variant, seed, float(np.mean(returns)), success, train_s, recorder.episodes())


def print_table(results: list[Result], variants: list[str]) -> None:
    """Per variant: per-seed returns, mean with 95% CI, success rate, training time."""
    head = f"{'variant':9s} {'mean return [95% CI]':>26s} {'success':>8s} {'train s':>8s}"
    print(f"\n{head}  per-seed returns ({len(results) // len(variants)} seeds)")
    for variant in variants:
        rows = [r for r in results if r.variant == variant]
        mean, low, high = confidence_interval([r.mean_return for r in rows])
        ci = f"{mean:7.1f} [{low:7.1f}, {high:7.1f}]"
        success = np.mean([r.success for r in rows])
        train_s = np.mean([r.train_s for r in rows])
        per_seed = " ".join(f"{r.mean_return:.0f}" for r in rows)
        print(f"{variant:9s} {ci:>26s} {success:8.0%} {train_s:8.1f}  {per_seed}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--variants", nargs="+", choices=list(VARIANTS), default=list(VARIANTS))
    parser.add_argument("--timesteps", type=int, help="training steps (default: the preset's)")
    parser.add_argument("--quick", action="store_true", help="tiny runs (for the tests)")
    parser.add_argument("--out", type=Path, default=Path("runs/reward_shaping"))
    args = parser.parse_args(argv)

    import torch

    torch.set_num_threads(1)
    preset = presets.get_preset("dqn", ENV_ID)
    episodes = 100
    if args.timesteps:
        preset["n_timesteps"] = args.timesteps
    if args.quick:
        args.seeds, episodes = args.seeds[:2], 5
        # Two episodes per env (so there are learning curves), few gradient steps.
        preset["n_timesteps"] = 400 * preset["n_envs"]
        preset["hyperparams"].update(learning_starts=200 * preset["n_envs"], gradient_steps=1)
    steps, n_envs = preset["n_timesteps"], preset["n_envs"]
    print(f"DQN on {ENV_ID}, preset 'default' ({steps} steps, {n_envs} envs), seeds {args.seeds}")

    results = []
    for variant in args.variants:
        for seed in args.seeds:
            result = train_and_evaluate(variant, seed, preset, episodes)
            results.append(result)
            score = f"return {result.mean_return:7.1f}, success {result.success:4.0%}"
            print(f"  {variant:9s} seed {seed}: {score}, {result.train_s:.1f} s", flush=True)
    print_table(results, args.variants)

    bands = [variant_band(v, [r.curve for r in results if r.variant == v]) for v in args.variants]
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / "learning_curves.png"
    title = f"DQN on {ENV_ID}: true return while training (mean, 95% band over seeds)"
    plot_compare([b for b in bands if b is not None], png, title)
    print(f"\nwrote {png}")


if __name__ == "__main__":
    main()
