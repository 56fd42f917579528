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
preset) on 10 seeds: 30 runs, described as :class:`palaestra.runs.RunSpec` and trained by
:func:`palaestra.runs.grid.run_grid`, one after another or as Ray tasks on this machine's cores
(``--backend ray``) or a cluster (``--address``), with the same results either way. The shaping
wrappers sit *outside* the ``Monitor`` that ``make_vec_env`` adds, so the learning curves show
the true return (-episode length) for all variants. Each trained agent plays 100 deterministic
episodes (Monitor returns: the true reward). Printed: per variant the interquartile mean (IQM)
over seeds of each seed's mean evaluation return, with its 95% percentile-bootstrap confidence
interval (:mod:`palaestra.runs.stats`, as ``palaestra compare``: Agarwal et al. 2021), the
success rate (episodes that reach the flag) and the training time; plotted: the learning
curves of all variants, the same IQM and interval over seeds at every point, in
``learning_curves.png``.

Run::

    .venv/bin/python examples/reward_shaping.py --backend ray   # 3 variants x 10 seeds on Ray
    .venv/bin/python examples/reward_shaping.py --seeds 0 1 2 --variants baseline progress
    .venv/bin/python examples/reward_shaping.py --quick         # seconds, for the tests
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any, SupportsFloat

import numpy as np

import palaestra as gym
from palaestra.runs import RunSpec, evaluate_run
from palaestra.runs.compare import group_runs, summarize
from palaestra.runs.curves import plot_compare, variant_band
from palaestra.runs.grid import GridRun, run_grid
from palaestra.runs.stats import CONFIDENCE_LEVEL, iqm_interval, method_note

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


# The wrappers by name ("module:Class"), so that a run folder records them and a Ray worker,
# which imports this file as the module ``reward_shaping``, builds the same env.
VARIANTS: dict[str, str | None] = {
    "baseline": None,
    "naive": "reward_shaping:NaiveRewardShaping",
    "progress": "reward_shaping:ProgressRewardShaping",
}


def grid(variants: list[str], seeds: list[int], out: Path, quick: bool) -> list[GridRun]:
    """One run per variant and seed: the DQN preset with the variant's wrapper."""
    runs = []
    for variant in variants:
        for seed in seeds:
            overrides: dict[str, Any] = {"env_wrapper": VARIANTS[variant]}
            if quick:  # two episodes per env (so there are learning curves), few gradient steps
                overrides.update(
                    n_timesteps=1600, hyperparams={"learning_starts": 800, "gradient_steps": 1}
                )
            spec = RunSpec.from_preset("dqn", ENV_ID, seed=seed, overrides=overrides)
            runs.append(GridRun(variant, spec, out / variant / f"seed{seed}"))
    return runs


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    parser.add_argument("--variants", nargs="+", choices=list(VARIANTS), default=list(VARIANTS))
    parser.add_argument("--backend", choices=("local", "ray"), default="local")
    parser.add_argument("--address", help="Ray cluster (auto, ray://HOST:10001); default local")
    parser.add_argument("--quick", action="store_true", help="tiny runs (for the tests)")
    parser.add_argument("--out", type=Path, default=Path("runs/reward_shaping"))
    args = parser.parse_args(argv)
    episodes = 5 if args.quick else 100
    if args.quick:
        args.seeds = args.seeds[:2]
    # Ray's workers import the wrappers from this folder.
    here = str(Path(__file__).resolve().parent)
    os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [here, os.environ.get("PYTHONPATH")]))

    runs = grid(args.variants, args.seeds, args.out, args.quick)
    spec = runs[0].spec
    print(f"DQN on {ENV_ID}, preset 'default' ({spec.n_timesteps} steps, {spec.n_envs} envs), "
          f"seeds {args.seeds}, backend {args.backend}")  # fmt: skip
    outcomes = run_grid(runs, args.backend, args.address)
    failed = [o for o in outcomes if o.status == "failed"]
    for outcome in failed:
        print(f"  {outcome.run.label} seed {outcome.run.spec.seed} failed: {outcome.error}")

    finished = [o for o in outcomes if o.status != "failed"]
    played: dict[str, list[Any]] = {variant: [] for variant in args.variants}
    for outcome in finished:
        run = outcome.run
        result = evaluate_run(
            run.run_dir,
            episodes,
            seed=10_000 + (run.spec.seed or 0),
            allow_import=["reward_shaping"],
        )
        played[run.label].append((result, outcome.seconds))
        score = f"return {result.mean_return:7.1f}, success {result.success_rate:4.0%}"
        print(f"  {run.label:9s} seed {run.spec.seed}: {score}, {outcome.seconds:.1f} s")

    ci_head = f"IQM return [{CONFIDENCE_LEVEL:.0%} CI]"
    head = f"{'variant':9s} {'seeds':>5s} {ci_head:>26s} {'success':>8s} {'train s':>8s}"
    print(f"\n{head}  per-seed returns ({episodes} episodes each)")
    for variant, results in played.items():
        if not results:  # every seed failed
            print(f"{variant:9s} {0:5d} {'n/a':>26s}")
            continue
        means = [r.mean_return for r, _ in results]
        value, low, high = iqm_interval(means)
        success = np.mean([r.success_rate for r, _ in results])
        seconds = np.mean([t for _, t in results])
        per_seed = " ".join(f"{m:.1f}" for m in means)
        interval = "n/a (one seed)" if low is None else f"[{low:7.1f}, {high:7.1f}]"
        ci = f"{value:7.1f} {interval}"
        print(f"{variant:9s} {len(means):5d} {ci:>26s} {success:8.0%} {seconds:8.1f}  {per_seed}")
    print(f"(return: each seed's mean over its {episodes} evaluation episodes; {method_note()})")

    rows = summarize(group_runs([o.run.run_dir for o in finished]), args.variants)
    bands = [band for row in rows if (band := variant_band(row.label, row.episodes))]
    png = args.out / "learning_curves.png"
    # plot_compare adds what the line and band are, the seeds per variant and the window.
    plot_compare(bands, png, f"DQN on {ENV_ID}: true return while training")
    print(f"\nwrote {png}")


if __name__ == "__main__":
    main()
