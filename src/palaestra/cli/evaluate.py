"""``palaestra eval``: play a saved model and report returns, success and episode lengths.

Also the pieces ``record`` and ``train`` reuse: loading a model file of either algorithm,
finding the env it was trained on, and the episode loop.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from palaestra.cli import run_folder
from palaestra.cli.common import (
    NORMALIZE_FILE,
    CLIError,
    find_run_config,
    is_goal_env,
    model_file,
)

__all__ = ["Played", "add_parser", "ascii_histogram", "load_model", "play", "play_saved", "run"]


class Played(NamedTuple):
    """What ``play`` saw: one entry per episode, and the frames when asked for."""

    returns: list[float]
    lengths: list[int]
    terminated: list[bool]
    frames: list[np.ndarray]


def load_model(path: Path, device: str = "auto") -> Any:
    """A model of any algorithm in ``settings.ALGOS``; which comes from the file's metadata."""
    from palaestra.algos.model_io import read_manifest
    from palaestra.cli.settings import ALGO_CLASSES, algo_class

    meta = read_manifest(path, "model").meta
    by_class = {cls: name for name, cls in ALGO_CLASSES.items()}
    algo = meta.get("algo")
    if algo not in by_class:
        raise CLIError(
            f"{str(path)!r} holds a {algo!r} model",
            f"palaestra trains {', '.join(sorted(by_class))}",
        )
    return algo_class(by_class[algo]).load(path, device=device)


def model_env_id(
    path: Path, env: str | None, config: dict[str, Any] | None
) -> tuple[str, dict[str, Any]]:
    """``(env id, env kwargs)``: ``--env`` if given, else the run's ``config``."""
    kwargs = dict(config.get("env_kwargs") or {}) if config else {}
    if env is not None:
        if config and config.get("env_id") != env:
            kwargs = {}  # another env: the run's env kwargs need not apply
        return env, kwargs
    if config is None or not isinstance(config.get("env_id"), str):
        raise CLIError(
            f"cannot tell which env {str(path)!r} was trained on (no config.json beside it)",
            "pass --env ID",
        )
    return config["env_id"], kwargs


def make_env(env_id: str, kwargs: dict[str, Any], render: bool = False) -> Any:
    """``palaestra.make`` with the run's kwargs (``render_mode="rgb_array"`` to record)."""
    import palaestra

    if render:
        kwargs = {**kwargs, "render_mode": "rgb_array"}
    return palaestra.make(env_id, **kwargs)


def check_spaces(model: Any, env: Any, env_id: str) -> None:
    """``CLIError`` when the model was trained on other spaces than ``env`` has."""
    for what, ours, theirs in (
        ("observations", model.observation_space, env.observation_space),
        ("actions", model.action_space, env.action_space),
    ):
        if ours != theirs:
            raise CLIError(
                f"the model expects {what} {ours} but {env_id} has {theirs}",
                "pass --env with the env the model was trained on",
            )


def obs_normalizer(path: Path, env_id: str, venv: Any = None) -> Any:
    """The run's saved observation normalisation (``normalize`` presets), or None. ``venv``
    gives the observation space when the run's pipeline changes it (default: ``env_id``'s)."""
    stats = path.parent / NORMALIZE_FILE
    if not stats.is_file():
        return None
    from palaestra.vec_env import VecNormalize, make_vec_env

    normalizer = VecNormalize.load(str(stats), venv or make_vec_env(env_id, n_envs=1))
    normalizer.training = False
    return normalizer.normalize_obs


def play(
    model: Any,
    env: Any,
    episodes: int,
    deterministic: bool = True,
    seed: int | None = 0,
    record: bool = False,
    normalize: Any = None,
) -> Played:
    """Run ``episodes`` episodes; the first reset gets ``seed``, later ones continue its
    generator (as ``evaluate_policy`` after ``env.reset(seed=seed)``)."""
    out = Played([], [], [], [])
    obs, _ = env.reset(seed=seed)
    for episode in range(episodes):
        if episode:
            obs, _ = env.reset()
        if record:
            out.frames.append(env.render())
        total, length, terminated, truncated = 0.0, 0, False, False
        while not (terminated or truncated):
            action, _ = model.predict(
                obs if normalize is None else normalize(obs), deterministic=deterministic
            )
            obs, reward, terminated, truncated, _ = env.step(action)
            total += float(reward)
            length += 1
            if record:
                out.frames.append(env.render())
        out.returns.append(total)
        out.lengths.append(length)
        out.terminated.append(bool(terminated))
    return out


def play_saved(
    model: Any,
    path: Path,
    env: str | None,
    episodes: int,
    deterministic: bool = True,
    seed: int | None = 0,
    record: bool = False,
    run_config: dict[str, Any] | None = None,
) -> tuple[str, Played, float, bool]:
    """Play the model at ``path`` on the env its run trained on (or ``--env``), built as the
    run built it: ``(env id, what was played, render fps, whether episodes are whole games)``.
    ``run_config``: the run's ``config.json`` as the command read and checked it
    (:func:`palaestra.cli.run_folder.find_run_config`); None reads it from beside ``path``.
    """
    from palaestra.cli import pipeline

    config = find_run_config(path) if run_config is None else run_config
    env_id, env_kwargs = model_env_id(path, env, config)
    if config is not None and pipeline.uses_vec_pipeline(config):
        # The run's recipe (Atari wrappers, frame stack), on --env's id when one is given.
        atari = pipeline.atari_kwargs(config) is not None
        if atari and not pipeline.is_atari_id(env_id):
            raise CLIError(
                f"the model was trained on SB3's Atari recipe; {env_id} is not an Atari game",
                "pass --env with an Atari id",
            )
        config = {**config, "env_id": env_id}
        venv = pipeline.make_vec(config, 1, seed, render=record)
        try:
            check_spaces(model, venv, env_id)
            normalize = obs_normalizer(path, env_id, venv)
            played = pipeline.play_vec(
                model, venv, episodes, deterministic, seed, record, normalize
            )
            fps = pipeline.render_fps(venv, config)
        finally:
            venv.close()
        return env_id, played, fps, atari
    single = make_env(env_id, env_kwargs, render=record)
    try:
        check_spaces(model, single, env_id)
        played = play(
            model, single, episodes, deterministic, seed, record, obs_normalizer(path, env_id)
        )
        fps = float(single.metadata.get("render_fps") or 30)
    finally:
        single.close()
    return env_id, played, fps, False


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


def summary_lines(played: Played, env_id: str) -> list[str]:
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
    run_folder.add_allow_import(p, "eval")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The ``eval`` command."""
    if args.episodes < 1:
        raise CLIError(f"--episodes must be at least 1, got {args.episodes}", "e.g. --episodes 10")
    path = model_file(args.model)
    config = run_folder.find_run_config(path, args.allow_import, args.env)
    model = load_model(path, args.device)
    env_id, played, _, games = play_saved(
        model, path, args.env, args.episodes, args.deterministic, args.seed, run_config=config
    )
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
