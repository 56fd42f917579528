"""Measure an Atari preset as a user runs it, against a uniformly random policy; ``--update``
writes the preset's ``measured`` block in ``src/palaestra/presets/presets.json``.

Run from the repository root, one training at a time (each takes 10-15 minutes on 2 cores)::

    .venv/bin/python benchmarks/atari_presets.py --algo ppo --update
    .venv/bin/python benchmarks/atari_presets.py --algo dqn --update
    .venv/bin/python benchmarks/atari_presets.py --algo ppo --out /tmp/r --reuse   # eval only
    .venv/bin/python benchmarks/atari_presets.py --algo ppo --games 2 --set n_timesteps=2048

Steps, all through the CLI except the random policy:

1. ``palaestra train ALGO ENV --seed S --out DIR --progress line`` (a subprocess; the 1-minute
   load average is sampled every 15 s into ``DIR/load_samples.txt``, since other work on a
   shared machine inflates wall times). ``wall_s`` is the run's own ``status.json`` wall time
   (``learn`` only). ``--reuse`` skips training when ``DIR`` already holds a finished run.
2. ``palaestra eval DIR --episodes GAMES`` (greedy, seed 0) and the same with ``--stochastic``
   (sampled actions, how RL-Zoo evaluates Atari). Episodes are whole games: all lives, the
   unclipped score, as the Monitor under SB3's AtariWrapper reports them.
3. A uniformly random policy for the same number of whole games on the same pipeline
   (``palaestra.runs.recipe``: ``make_atari_env`` + ``VecFrameStack``, one env, seed 0).

One seed per preset: a training costs a quarter of an hour of a shared 2-core CPU.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import re
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from palaestra import presets
from palaestra.runs.recipe import atari_kwargs
from presets import machine, write_measured

PALAESTRA = str(Path(sys.executable).with_name("palaestra"))
ENV_ID = "ALE/Breakout-v5"


class LoadSampler(threading.Thread):
    """Append ``<unix time> <1-minute load average>`` to a file every ``every`` seconds."""

    def __init__(self, path: Path, every: float = 15.0) -> None:
        super().__init__(daemon=True)
        self.path, self.every, self.done = path, every, threading.Event()

    def run(self) -> None:
        while not self.done.is_set():
            with self.path.open("a") as f:
                f.write(f"{time.time():.0f} {os.getloadavg()[0]:.2f}\n")
            self.done.wait(self.every)


class RandomPolicy:
    """Uniform actions through ``predict``."""

    def __init__(self, n_actions: int, seed: int) -> None:
        self.n, self.rng = n_actions, np.random.default_rng(seed)

    def predict(self, obs: np.ndarray, **_: Any) -> tuple[np.ndarray, None]:
        """One random action per env."""
        return self.rng.integers(0, self.n, len(obs)), None


def train(algo: str, env_id: str, seed: int, out: Path, assignments: list[str]) -> None:
    """Run ``palaestra train`` with a load sampler."""
    cmd = [PALAESTRA, "train", algo, env_id, "--seed", str(seed), "--out", str(out)]
    cmd += ["--progress", "line", *(arg for a in assignments for arg in ("--set", a))]
    out.mkdir(parents=True, exist_ok=True)
    sampler = LoadSampler(out / "load_samples.txt")
    sampler.start()
    try:
        subprocess.run(cmd, check=True)
    finally:
        sampler.done.set()
        sampler.join()


def cli_eval(out: Path, games: int, stochastic: bool) -> tuple[float, float, str]:
    """``palaestra eval``: (mean, std) of whole-game scores, and its stdout."""
    cmd = [PALAESTRA, "eval", str(out), "--episodes", str(games)]
    if stochastic:
        cmd.append("--stochastic")
    text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    found = re.search(r"mean return: (-?[\d.]+) ± ([\d.]+)", text)
    if found is None:
        raise SystemExit(f"cannot read the mean return from:\n{text}")
    return float(found[1]), float(found[2]), text


def random_games(config: dict[str, Any], games: int) -> list[float]:
    """Whole-game scores of a uniformly random policy on the run's pipeline."""
    from palaestra.runs.evaluation import play_episodes
    from palaestra.runs.recipe import make_vec

    venv = make_vec(config, 1, seed=0)
    venv.seed(0)
    returns, _, _ = play_episodes(RandomPolicy(int(venv.action_space.n), 0), venv, games)
    venv.close()
    return returns


def load_summary(path: Path) -> dict[str, Any]:
    """Mean, min and max of the sampled 1-minute load averages."""
    values = [float(line.split()[1]) for line in path.read_text().splitlines() if line.strip()]
    return {
        "load_average_1m": round(float(np.mean(values)), 2),
        "load_average_1m_range": [min(values), max(values)],
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--algo", choices=["dqn", "ppo"], required=True)
    parser.add_argument("--env", default=ENV_ID, metavar="ID")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--games", type=int, default=20, help="evaluation games (default 20)")
    parser.add_argument("--out", type=Path, help="run folder (default /tmp/palaestra-ALGO-ENV)")
    parser.add_argument("--reuse", action="store_true", help="evaluate a finished run in --out")
    parser.add_argument("--set", dest="assignments", action="append", default=[])
    parser.add_argument("--update", action="store_true", help="write 'measured' to presets.json")
    args = parser.parse_args(argv)
    if args.update and args.assignments:
        parser.error("--update records the presets as shipped; drop --set")
    presets.get_preset(args.algo, args.env)  # fails early when there is no such preset
    out = args.out or Path(f"/tmp/palaestra-{args.algo}-{args.env.replace('/', '_')}")
    status_file = out / "status.json"
    finished = status_file.is_file() and json.loads(status_file.read_text())["status"] == "finished"
    if not (args.reuse and finished):
        train(args.algo, args.env, args.seed, out, args.assignments)
    status = json.loads(status_file.read_text())
    config = json.loads((out / "config.json").read_text())
    greedy = cli_eval(out, args.games, stochastic=False)
    print(greedy[2])
    sampled = cli_eval(out, args.games, stochastic=True)
    print(sampled[2])
    randoms = random_games(config, args.games)
    frame_skip = (atari_kwargs(config) or {}).get("frame_skip", 4)
    record = {
        "seeds": [args.seed],
        "games": args.games,
        "mean_return": [greedy[0]],
        "std_return": [greedy[1]],
        "mean_return_stochastic": [sampled[0]],
        "std_return_stochastic": [sampled[1]],
        "random_mean_return": round(float(np.mean(randoms)), 2),
        "random_std_return": round(float(np.std(randoms)), 2),
        "agent_steps": status["num_timesteps"],
        "frames": status["num_timesteps"] * frame_skip,
        "wall_s": [round(status["wall_time_s"], 1)],
        "date": datetime.date.today().isoformat(),
        "machine": machine() + ", shared with other benchmarks",
        **load_summary(out / "load_samples.txt"),
        "command": f"palaestra train {args.algo} {args.env} --seed {args.seed} --out RUN"
        f" && palaestra eval RUN --episodes {args.games} [--stochastic]; script: "
        f".venv/bin/python benchmarks/atari_presets.py --algo {args.algo} --update",
        "note": "one seed; returns are whole-game scores (5 lives, unclipped) over the games "
        "listed, greedy (the eval default) and sampled; random: uniform actions, same games",
    }
    print(json.dumps(record, indent=2))
    if args.update:
        write_measured({(args.algo, args.env, "default"): record})
        print("wrote the measured record to presets.json")


if __name__ == "__main__":
    main()
