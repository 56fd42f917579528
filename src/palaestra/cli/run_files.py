"""What ``train`` leaves in a run folder when it stops: the resumable checkpoint, and the
end-of-run summary with the learning curve."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from palaestra.cli.common import (
    CONFIG_FILE,
    EPISODES_FILE,
    MODEL_FILE,
    NORMALIZE_FILE,
    REPLAY_ALGOS,
    REPLAY_FILE,
    STATUS_FILE,
    eprint,
    is_goal_env,
    write_json,
)

__all__ = ["print_summary", "write_status"]


def write_status(
    run_dir: Path,
    state: str,
    steps: int,
    total: int,
    wall: float,
    checkpoint: str | None,
) -> None:
    """``status.json``: where the run stands and which checkpoint ``--resume`` continues."""
    write_json(
        run_dir / STATUS_FILE,
        {
            "status": state,
            "num_timesteps": int(steps),
            "total_timesteps": int(total),
            "wall_time_s": round(wall, 3),
            "checkpoint": checkpoint,
        },
    )


def print_summary(
    eval_episodes: int,
    config: dict[str, Any],
    model: Any,
    run_dir: Path,
    steps: int,
    seconds: float,
) -> None:
    """Steps, wall time, fps, the recent training return, a deterministic evaluation, the
    learning curve, and the list of files written."""
    from palaestra.cli.curves import read_episodes
    from palaestra.cli.evaluate import GAMES_NOTE, play_saved, summary_lines
    from palaestra.cli.progress import format_duration

    env_id = config["env_id"]
    written = [CONFIG_FILE, "progress.csv", EPISODES_FILE, MODEL_FILE]
    print(
        f"trained {config['algo']} on {env_id}: {model.num_timesteps:,} steps, "
        f"wall time {format_duration(seconds)} ({seconds:.1f} s), {steps / seconds:,.0f} fps"
    )
    history = read_episodes(run_dir)
    last = history.returns[-100:]
    if len(last):
        line = f"mean return over the last {len(last)} training episodes: {np.mean(last):.2f}"
        if is_goal_env(env_id) and history.terminated is not None:
            line += f", success {100 * np.mean(history.terminated[-100:]):.1f}%"
        print(line)
    else:
        print("no training episode finished yet")
    # The learning curve is drawn off the training path (see ``curves``), started before the
    # evaluation so that a drawing in the background overlaps it.
    from palaestra.cli.curves import LEARNING_CURVE_FILE, draw_learning_curve
    from palaestra.error import DependencyNotInstalled

    try:
        drawing = draw_learning_curve(run_dir, f"{config['algo'].upper()} on {env_id}")
        curve = LEARNING_CURVE_FILE + " (drawing)" * (drawing is not None)
    except DependencyNotInstalled:
        eprint(f"note: matplotlib is not installed, so no {LEARNING_CURVE_FILE}")
        curve = ""
    if eval_episodes > 0:
        _, played, _, games = play_saved(model, run_dir / MODEL_FILE, None, eval_episodes)
        unit = ("game" if games else "episode") + "s" * (eval_episodes != 1)
        print(f"evaluation ({eval_episodes} {unit}, deterministic, seed 0):")
        if games:
            print(f"  {GAMES_NOTE}")
        for text in summary_lines(played, env_id):
            print(f"  {text}")
    if curve:
        written.append(curve)
    if config["algo"] in REPLAY_ALGOS:
        written.append(REPLAY_FILE)
    if (run_dir / NORMALIZE_FILE).is_file():
        written.append(NORMALIZE_FILE)
    if (run_dir / "checkpoints").is_dir():
        written.append("checkpoints/")
    if (run_dir / "resume").is_dir():
        written.append("resume/")
    if (run_dir / "tb").is_dir():
        written.append("tb/")
    print(f"wrote {run_dir}/: {', '.join(written)}")
