"""Train every shipped preset on several seeds, evaluate it, and (``--update``) record the
results in ``src/palaestra/presets/presets.json``.

Run from the repository root::

    .venv/bin/python benchmarks/presets.py                          # every preset, seeds 0-4
    .venv/bin/python benchmarks/presets.py --algo dqn --env MountainCar-v0
    .venv/bin/python benchmarks/presets.py --update                 # write each preset's "measured"
    .venv/bin/python benchmarks/presets.py --algo dqn --env CartPole-v1 --seeds 0 1 \\
        --set n_timesteps=30000 --set hyperparams.learning_rate=0.001   # try a change

Each run is built exactly as ``palaestra train ALGO ENV --preset NAME --seed S`` builds it:
``make_vec_env(env_id, n_envs, seed=S, env_kwargs)`` (under ``VecNormalize`` when the preset
says ``normalize``), ``ALGO(policy, env, seed=S, **resolve(hyperparams))``, then
``learn(n_timesteps)`` with ``torch.set_num_threads(1)``. Only ``learn`` is timed, in wall-clock
and in process CPU seconds (the second is what other jobs on a shared machine do not inflate).
The trained model then plays 100 deterministic episodes (10 on MuJoCo's 1000-step robots) with
``evaluate_policy`` on a fresh ``palaestra.make(env_id)`` reset once with seed ``10_000 + S``
(later resets continue its generator). Goal envs also report the success rate: the env's
``info["is_success"]`` at each episode's end where it reports one (BitFlipping), else episodes
that end before the time limit (MountainCar, Acrobot). One row per (preset, seed) as it
finishes, then per preset the medians, the interquartile mean and range over seeds and how many
seeds reach the env's target (the env spec's ``reward_threshold``; -200 for Pendulum-v1, which
has none). Run one training at a time on a quiet machine: wall times are
the point; where the machine is shared, the CPU seconds say what an idle core would take.
Atari presets (``"atari"`` in the preset) are left to ``benchmarks/atari_presets.py``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import statistics
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import palaestra
from palaestra import presets
from palaestra.runs.files import is_goal_env
from palaestra.runs.settings import ALGOS, parse_value
from palaestra.runs.stats import iqm
from palaestra.utils.atomic_write import atomic_write

PRESETS_JSON = Path(__file__).resolve().parents[1] / "src/palaestra/presets/presets.json"
EVAL_EPISODES = 100
# MuJoCo's robots run 1000-step episodes on a deterministic policy from a small reset noise:
# 10 episodes cost a tenth of the CPU of 100 (100,000 policy steps on HalfCheetah) and vary
# little between episodes.
LONG_EVAL_EPISODES = 10
EVAL_SEED = 10_000
# Targets where the env spec has no reward_threshold ("solved" as the RL Zoo reports it).
# BitFlipping15-v0: a policy that flips each zero bit once returns -(zeros - 1), about -6.5 from
# a uniform start, and a failed episode -15: -7.5 is about 90% success; the success rate itself
# (the env's info["is_success"]) is recorded and held to SUCCESS_TARGETS.
EXTRA_TARGETS = {"Pendulum-v1": -200.0, "BitFlipping15-v0": -7.5}
SUCCESS_TARGETS = {"BitFlipping15-v0": 0.9}


@dataclass
class Run:
    """One trained and evaluated (preset, seed)."""

    algo: str
    env_id: str
    name: str
    seed: int
    mean_return: float
    std_return: float
    success: float | None  # goal envs only: fraction of episodes ending before the time limit
    wall_s: float
    steps: int
    cpu_s: float = float("nan")  # process CPU time of training: what load does not inflate


def target(env_id: str) -> float:
    """The mean return that counts as solving ``env_id``."""
    threshold = palaestra.spec(env_id).reward_threshold
    if threshold is not None:
        return float(threshold)
    if env_id in EXTRA_TARGETS:
        return EXTRA_TARGETS[env_id]
    raise KeyError(f"no target return known for {env_id!r}; add it to EXTRA_TARGETS")


def eval_episodes(env_id: str) -> int:
    """How many deterministic episodes evaluate a preset on ``env_id``."""
    entry = palaestra.spec(env_id).entry_point
    mujoco = isinstance(entry, str) and entry.startswith("palaestra.envs.mujoco")
    return LONG_EVAL_EPISODES if mujoco else EVAL_EPISODES


def make_training_env(env_id: str, preset: dict[str, Any], seed: int) -> Any:
    """The CLI's training env: the native batch, under VecNormalize when asked."""
    from palaestra.vec_env import VecNormalize, make_vec_env

    venv = make_vec_env(
        env_id, n_envs=preset["n_envs"], seed=seed, env_kwargs=preset.get("env_kwargs")
    )
    normalize = preset.get("normalize") or False
    if normalize is False:
        return venv
    kwargs = dict(normalize) if isinstance(normalize, dict) else {}
    kwargs.setdefault("gamma", preset["hyperparams"].get("gamma", 0.99))
    return VecNormalize(venv, **kwargs)


class NormalizedPolicy:
    """``model.predict`` on observations normalised by the training VecNormalize's statistics."""

    def __init__(self, model: Any, venv: Any) -> None:
        self.model, self.venv = model, venv
        venv.training = False

    def predict(self, obs: Any, **kwargs: Any) -> Any:
        return self.model.predict(self.venv.normalize_obs(obs), **kwargs)


def evaluate(
    model: Any,
    venv: Any,
    algo: str,
    env_id: str,
    name: str,
    preset: dict[str, Any],
    seed: int,
    wall: float,
    cpu: float,
) -> Run:
    """:func:`eval_episodes` deterministic episodes on a fresh env reset once with
    ``EVAL_SEED + seed``."""
    from palaestra.algos import evaluate_policy

    policy = NormalizedPolicy(model, venv) if preset.get("normalize") else model
    env = palaestra.make(env_id, **(preset.get("env_kwargs") or {}))
    env.reset(seed=EVAL_SEED + seed)
    reported: list[bool] = []  # info["is_success"] at each episode's end, where the env says
    episodes = eval_episodes(env_id)

    def on_step(locals_: dict[str, Any], globals_: dict[str, Any]) -> None:
        if locals_["done"] and "is_success" in locals_["info"]:
            reported.append(bool(locals_["info"]["is_success"]))

    returns, lengths = evaluate_policy(
        policy,
        env,
        n_eval_episodes=episodes,
        deterministic=True,
        return_episode_rewards=True,
        callback=on_step,
    )
    if preset.get("normalize"):
        venv.training = True  # evaluation paused training; it goes on normalising as before
    success = None
    if len(reported) == episodes:  # every episode's end said whether it succeeded
        success = float(np.mean(reported))
    elif is_goal_env(env_id):
        limit = env.spec.max_episode_steps if env.spec is not None else None
        counts = np.asarray(lengths)  # a list here (return_episode_rewards=True)
        success = float(np.mean(counts < limit)) if limit else None
    env.close()
    return Run(
        algo,
        env_id,
        name,
        seed,
        float(np.mean(returns)),
        float(np.std(returns)),
        success,
        wall,
        int(model.num_timesteps),
        cpu,
    )


def run_one(
    algo: str,
    env_id: str,
    name: str,
    preset: dict[str, Any],
    seed: int,
    eval_at: list[int] | None = None,
) -> Run:
    """Train ``preset`` with ``seed`` the way the CLI does, then evaluate it.

    ``eval_at``: also evaluate (and print a row) when training passes each of these step
    counts. Evaluating plays a separate env with the deterministic policy, which touches
    neither the model's nor the training env's state, so the row at N is what a preset with
    ``n_timesteps=N`` gives when nothing is scheduled on the total (constant learning rate,
    no exploration schedule), and its wall time is the training time up to N alone.
    """
    import torch

    from palaestra.algos.callbacks import BaseCallback
    from palaestra.runs.settings import algo_class

    torch.set_num_threads(1)
    venv = make_training_env(env_id, preset, seed)
    cls = algo_class(algo)
    model = cls(
        preset["policy"], venv, seed=seed, verbose=0, **presets.resolve(preset["hyperparams"])
    )
    marks = sorted(m for m in (eval_at or []) if m < preset["n_timesteps"])
    paused = [0.0, 0.0]  # wall, CPU seconds spent evaluating

    class EvalAt(BaseCallback):
        def _on_step(self) -> bool:
            # Past the mark, not at it: an off-policy learner trains after the steps it has
            # collected, so the policy that learn(N) returns exists from step N + 1 on.
            if marks and self.num_timesteps > marks[0]:
                mark = marks.pop(0)
                begin, begin_cpu = time.perf_counter(), time.process_time()
                wall, cpu = begin - start - paused[0], begin_cpu - start_cpu - paused[1]
                done = evaluate(model, venv, algo, env_id, name, preset, seed, wall, cpu)
                done.steps = mark
                print(row(done), flush=True)
                paused[0] += time.perf_counter() - begin
                paused[1] += time.process_time() - begin_cpu
            return True

    start, start_cpu = time.perf_counter(), time.process_time()
    model.learn(preset["n_timesteps"], callback=EvalAt() if marks else None)
    wall = time.perf_counter() - start - paused[0]
    cpu = time.process_time() - start_cpu - paused[1]
    return evaluate(model, venv, algo, env_id, name, preset, seed, wall, cpu)


# -- output ------------------------------------------------------------------------------------
HEADER = f"{'algo':4s} {'env':15s} {'preset':8s} {'seed':>4s} {'return':>14s} {'success':>7s}"
HEADER += f" {'wall s':>7s} {'cpu s':>7s} {'steps':>8s}"


def row(run: Run) -> str:
    """One table line."""
    success = "" if run.success is None else f"{run.success:.0%}"
    score = f"{run.mean_return:7.1f} ±{run.std_return:5.1f}"
    return (
        f"{run.algo:4s} {run.env_id:15s} {run.name:8s} {run.seed:4d} {score:>14s} {success:>7s}"
        f" {run.wall_s:7.1f} {run.cpu_s:7.1f} {run.steps:8d}"
    )


def summary(runs: list[Run]) -> dict[str, Any]:
    """Per-seed results, medians and the interquartile mean and range of one preset (the
    ``measured`` record)."""
    goal = target(runs[0].env_id)
    returns = [r.mean_return for r in runs]
    out: dict[str, Any] = {
        "seeds": [r.seed for r in runs],
        "mean_return": [round(x, 1) for x in returns],
        "median_return": round(statistics.median(returns), 1),
        # The IQM over seeds (palaestra compare's statistic) and the 25th-75th percentiles.
        "iqm_return": round(iqm(returns), 1),
        "interquartile_range": [round(float(q), 1) for q in np.percentile(returns, [25, 75])],
        "target": goal,
        "seeds_meeting_target": sum(r.mean_return >= goal for r in runs),
        "wall_s": [round(r.wall_s, 1) for r in runs],
        "wall_s_median": round(statistics.median(r.wall_s for r in runs), 1),
        "cpu_s": [round(r.cpu_s, 1) for r in runs],
        "cpu_s_median": round(statistics.median(r.cpu_s for r in runs), 1),
    }
    if eval_episodes(runs[0].env_id) != EVAL_EPISODES:
        out["eval_episodes"] = eval_episodes(runs[0].env_id)
    if runs[0].success is not None:
        out["success_rate"] = [r.success for r in runs]
    if runs[0].env_id in SUCCESS_TARGETS:
        out["success_target"] = SUCCESS_TARGETS[runs[0].env_id]
        out["seeds_meeting_success_target"] = sum(
            (r.success or 0.0) >= out["success_target"] for r in runs
        )
    return out


def summary_line(runs: list[Run]) -> str:
    s = summary(runs)
    head = f"{runs[0].algo} {runs[0].env_id} {runs[0].name}:"
    return (
        f"{head} median return {s['median_return']:.1f}, IQM {s['iqm_return']:.1f} "
        f"(IQR {s['interquartile_range'][0]:.1f} to {s['interquartile_range'][1]:.1f}), "
        f"{s['seeds_meeting_target']}/{len(runs)} seeds >= {s['target']:g}, "
        f"median train wall {s['wall_s_median']:.1f}s, CPU {s['cpu_s_median']:.1f}s"
    )


# -- presets.json --------------------------------------------------------------------------------
def compact_json(value: Any, indent: int = 0, width: int = 100) -> str:
    """JSON with anything that fits on one line kept on one line (the file stays readable)."""
    flat = json.dumps(value)
    if len(flat) + indent <= width or not isinstance(value, (dict, list)) or not value:
        return flat
    pad = " " * (indent + 2)
    if isinstance(value, dict):
        items = [
            f"{pad}{json.dumps(k)}: {compact_json(v, indent + 2, width)}" for k, v in value.items()
        ]
        return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"
    items = [f"{pad}{compact_json(v, indent + 2, width)}" for v in value]
    return "[\n" + ",\n".join(items) + "\n" + " " * indent + "]"


def write_measured(measured: dict[tuple[str, str, str], dict[str, Any]]) -> None:
    """Set the ``measured`` field of each given preset in presets.json."""
    table = json.loads(PRESETS_JSON.read_text(encoding="utf-8"))
    for (algo, env_id, name), record in measured.items():
        table[algo][env_id][name]["measured"] = record
    with atomic_write(PRESETS_JSON, "w", encoding="utf-8") as fh:
        fh.write(compact_json(table) + "\n")


def machine() -> str:
    """Cores and CPU model: the same code ran ~4x slower on 2026-11-27's machine (AMD EPYC
    family 25, AVX2) than on 2026-11-23's, so a wall time means little without the CPU."""
    return f"{os.cpu_count()}-core {cpu_model()}, 1 torch thread"


def cpu_model() -> str:
    """``/proc/cpuinfo``'s model name, family, model and widest AVX ("CPU" where unreadable)."""
    try:
        text = Path("/proc/cpuinfo").read_text(encoding="utf-8")
    except OSError:
        return "CPU"
    fields: dict[str, str] = {}
    for line in text.splitlines():
        key, sep, value = line.partition(":")
        if not sep:
            break  # the first processor's block ends at the first blank line
        fields.setdefault(key.strip(), value.strip())
    flags = fields.get("flags", "").split()
    avx = next((f for f in ("avx512f", "avx2", "avx") if f in flags), "no AVX")
    name, family, model = (fields.get(k, "?") for k in ("model name", "cpu family", "model"))
    return f"{name} (family {family}, model {model}, {avx})"


# -- main ----------------------------------------------------------------------------------------
def selected(algo: str | None, env_id: str | None, name: str | None) -> list[tuple[str, str, str]]:
    out = []
    for a, envs in presets.available().items():
        for e, names in envs.items():
            for n in names:
                if presets.get_preset(a, e, n).get("atari"):
                    continue  # Atari presets: benchmarks/atari_presets.py (whole games, 1 seed)
                if (algo in (None, a)) and (env_id in (None, e)) and (name in (None, n)):
                    out.append((a, e, n))
    if not out:
        raise SystemExit(f"no preset matches algo={algo!r} env={env_id!r} preset={name!r}")
    return out


def overridden(preset: dict[str, Any], assignments: list[str]) -> dict[str, Any]:
    """``preset`` with ``--set key.sub=value`` overrides (JSON or Python-literal values)."""
    for item in assignments:
        key, sep, text = item.partition("=")
        if not sep:
            raise SystemExit(f"--set {item!r} is not key=value")
        override: dict[str, Any] = {}
        node = override
        parts = key.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = parse_value(text)
        preset = presets.merge(preset, override)
    return preset


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--algo", choices=list(ALGOS))
    parser.add_argument("--env", metavar="ID")
    parser.add_argument("--preset", metavar="NAME", help="preset name (default: all)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument(
        "--set",
        dest="assignments",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="try a change, e.g. n_envs=4 or hyperparams.learning_rate=0.002 (not with --update)",
    )
    parser.add_argument("--update", action="store_true", help="write 'measured' into presets.json")
    parser.add_argument(
        "--eval-at",
        type=int,
        nargs="+",
        default=[],
        metavar="STEPS",
        help="also evaluate at these step counts during training (to choose n_timesteps)",
    )
    args = parser.parse_args(argv)
    if args.update and args.assignments:
        parser.error("--update records the presets as shipped; drop --set")
    return args


def command(algo: str, env_id: str, name: str, seeds: list[int]) -> str:
    preset = "" if name == "default" else f" --preset {name}"
    seed_list = " ".join(map(str, seeds))
    return (
        f".venv/bin/python benchmarks/presets.py --algo {algo} --env {env_id}{preset}"
        f" --seeds {seed_list}"
    )


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    print(f"load average at start: {os.getloadavg()[0]:.2f} ({machine()})", flush=True)
    print(HEADER, flush=True)
    measured: dict[tuple[str, str, str], dict[str, Any]] = {}
    lines = []
    for algo, env_id, name in selected(args.algo, args.env, args.preset):
        preset = overridden(presets.get_preset(algo, env_id, name), args.assignments)
        runs = []
        for seed in args.seeds:
            runs.append(run_one(algo, env_id, name, preset, seed, args.eval_at))
            print(row(runs[-1]), flush=True)
        lines.append(summary_line(runs))
        measured[(algo, env_id, name)] = {
            **summary(runs),
            "date": datetime.date.today().isoformat(),
            "machine": machine(),
            "load_average_1m": round(os.getloadavg()[0], 2),
            "command": command(algo, env_id, name, args.seeds),
        }
    print("\nsummary")
    print("\n".join(lines))
    print(f"load average at end: {os.getloadavg()[0]:.2f}")
    if args.update:
        write_measured(measured)
        print(f"wrote {len(measured)} measured record(s) to {PRESETS_JSON}")


if __name__ == "__main__":
    main()
