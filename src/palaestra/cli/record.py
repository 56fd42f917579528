"""``palaestra record``: play a saved model with ``render_mode="rgb_array"`` into a GIF or MP4."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from palaestra.cli.common import CLIError, add_allow_import
from palaestra.error import dependency_not_installed
from palaestra.runs import evaluate_run
from palaestra.runs.recipe import import_env_module
from palaestra.utils import video

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Register ``record`` on the subcommand parsers."""
    p = sub.add_parser(
        "record",
        help="write a GIF or MP4 of a saved model playing",
        description="Play a saved model and write every rendered frame to a video: .gif needs "
        'Pillow, .mp4 needs imageio-ffmpeg (both: pip install "palaestra[video]").',
    )
    p.add_argument("model", metavar="MODEL", help="a model.zip, or a run folder holding one")
    p.add_argument(
        "--out", required=True, metavar="FILE", help="the video to write: FILE.gif or FILE.mp4"
    )
    p.add_argument(
        "--episodes", type=int, default=1, metavar="N", help="episodes to record (default: 1)"
    )
    p.add_argument(
        "--env", metavar="ID", help="env id to play on (default: the env in the run's config.json)"
    )
    p.add_argument(
        "--seed", type=int, default=0, metavar="S", help="seed of the first reset (default: 0)"
    )
    p.add_argument(
        "--fps",
        type=float,
        metavar="FPS",
        help="frames per second (default: the env's render_fps, else 30)",
    )
    p.add_argument(
        "--stochastic",
        action="store_true",
        help="sample actions from the policy instead of acting greedily",
    )
    p.add_argument(
        "--device", default="auto", metavar="DEV", help="torch device: auto (default), cpu, cuda"
    )
    add_allow_import(p, "record")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The ``record`` command."""
    out = Path(args.out)
    if out.suffix.lower() not in (".gif", ".mp4"):
        raise CLIError(
            f"cannot write {args.out!r}: unknown video format", "end --out in .gif or .mp4"
        )
    if args.episodes < 1:
        raise CLIError(f"--episodes must be at least 1, got {args.episodes}", "e.g. --episodes 1")
    if args.fps is not None and not args.fps > 0:
        raise CLIError(f"--fps must be positive, got {args.fps}", "e.g. --fps 30")
    if out.suffix.lower() == ".mp4":
        if not video.mp4_available():  # before playing, not after
            raise dependency_not_installed("imageio-ffmpeg", "video", "writing MP4 files")

    if args.env:  # --env mygrid:Grid-v0: the user's own module
        import_env_module(args.env, f"--env {args.env!r}")

    played = evaluate_run(
        args.model,
        args.episodes,
        not args.stochastic,
        args.seed,
        args.env,
        args.allow_import,
        record=True,
        device=args.device,
    )
    env_fps, games = played.fps, played.games
    fps = args.fps or env_fps
    video.save_video(played.frames, out, fps=fps)
    returns = ", ".join(f"{r:.1f}" for r in played.returns)
    print(
        f"wrote {out}: {len(played.frames)} frames at {fps:g} fps, "
        f"{args.episodes} {'game' if games else 'episode'}(s), return {returns}"
    )
    return 0
