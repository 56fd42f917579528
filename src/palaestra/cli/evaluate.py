"""``palaestra eval``: play a saved model and report returns, success and episode lengths
(:func:`palaestra.runs.evaluate_run` plays them)."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from palaestra.cli.common import CLIError, add_allow_import
from palaestra.runs import evaluate_run
from palaestra.runs.files import is_goal_env
from palaestra.runs.recipe import import_env_module

__all__ = ["GAMES_NOTE", "add_parser", "ascii_histogram", "run", "summary_lines"]


GAMES_NOTE = (
    "episodes are whole games (all lives; the unclipped score, as the Monitor under SB3's "
    "AtariWrapper reports it)"
)


def ascii_histogram(values: list[int], bins: int = 10, width: int = 40) -> list[str]:
    """Rows ``"lo-hi | ####  count"`` over at most ``bins`` bins of whole numbers.

    >>> print("\\n".join(ascii_histogram([10, 10, 11, 14], bins=3, width=4)))
      10-11 | ####  3
      12-13 |       0
      14-15 | #     1
    """
    data = np.asarray(values, dtype=np.int64)
    lo, hi = int(data.min()), int(data.max())
    step = max(1, -(-(hi - lo + 1) // bins))  # ceil: every value lands in one of <= bins bins
    counts = np.bincount((data - lo) // step)
    labels = [
        str(lo + i * step) if step == 1 else f"{lo + i * step}-{lo + (i + 1) * step - 1}"
        for i in range(len(counts))
    ]
    label_width = max(len(label) for label in labels)
    peak = int(counts.max())
    return [
        f"  {label:>{label_width}} | {'#' * round(width * count / peak):<{width}}  {count}"
        for label, count in zip(labels, counts)
    ]


def summary_lines(played: Any, env_id: str) -> list[str]:
    """Mean ± std return and, for goal envs, the success rate."""
    returns = np.asarray(played.returns)
    lines = [f"mean return: {returns.mean():.2f} ± {returns.std():.2f}"]
    if is_goal_env(env_id):
        wins = sum(played.terminated)
        rate = 100.0 * wins / len(returns)
        lines.append(f"success rate: {rate:.1f}% ({wins}/{len(returns)} episodes reached the goal)")
    return lines


def add_parser(sub: Any) -> None:
    """Register ``eval`` on the subcommand parsers."""
    p = sub.add_parser(
        "eval",
        help="evaluate a saved model",
        description="Play a saved model and print its mean ± std return, its success rate "
        "(goal envs such as MountainCar: an episode that terminates before the time limit "
        "succeeded) and a histogram of episode lengths. A run trained on SB3's Atari recipe "
        "is played on that recipe again, and its episodes are whole games (all lives, the "
        "unclipped score).",
    )
    p.add_argument("model", metavar="MODEL", help="a model.zip, or a run folder holding one")
    p.add_argument(
        "--episodes", type=int, default=10, metavar="N", help="episodes to play (default: 10)"
    )
    p.add_argument(
        "--env",
        metavar="ID",
        help="env id to play on (default: the env in the run's config.json)",
    )
    mode = p.add_mutually_exclusive_group()
    mode.add_argument(
        "--deterministic",
        dest="deterministic",
        action="store_true",
        default=True,
        help="greedy actions (the default)",
    )
    mode.add_argument(
        "--stochastic",
        dest="deterministic",
        action="store_false",
        help="sample actions from the policy (DQN: epsilon-greedy at its final epsilon)",
    )
    p.add_argument(
        "--seed", type=int, default=0, metavar="S", help="seed of the first reset (default: 0)"
    )
    p.add_argument(
        "--device", default="auto", metavar="DEV", help="torch device: auto (default), cpu, cuda"
    )
    add_allow_import(p, "eval")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The ``eval`` command."""
    if args.episodes < 1:
        raise CLIError(f"--episodes must be at least 1, got {args.episodes}", "e.g. --episodes 10")
    if args.env:  # --env mygrid:Grid-v0: the user's own module
        import_env_module(args.env, f"--env {args.env!r}")
    played = evaluate_run(
        args.model,
        args.episodes,
        args.deterministic,
        args.seed,
        args.env,
        args.allow_import,
        device=args.device,
    )
    model, env_id, games = played.model, played.env_id, played.games
    path = played.path
    kind = "deterministic" if args.deterministic else "stochastic"
    unit = ("game" if games else "episode") + "s" * (args.episodes != 1)
    header = f"{type(model).__name__} {path} on {env_id}: {args.episodes} {unit}, {kind}"
    print(f"{header}, seed {args.seed}")
    if games:
        print(GAMES_NOTE)
    for line in summary_lines(played, env_id):
        print(line)
    lengths = played.lengths
    unit = "game lengths in agent steps" if games else "episode lengths"
    print(f"{unit} (min {min(lengths)}, mean {np.mean(lengths):.1f}, max {max(lengths)}):")
    for row in ascii_histogram(lengths):
        print(row)
    return 0
