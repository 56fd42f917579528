"""What ``train`` prints when a run finishes: the summary, the evaluation and the files."""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra.cli.common import eprint, format_duration
from palaestra.cli.evaluate import GAMES_NOTE, summary_lines
from palaestra.error import DependencyNotInstalled
from palaestra.runs import evaluate_run
from palaestra.runs.curves import (
    LEARNING_CURVE_FILE,
    draw_learning_curve,
    read_episodes,
    read_evaluations,
)
from palaestra.runs.files import (
    BEST_MODEL_FILE,
    BEST_NORMALIZE_FILE,
    CONFIG_FILE,
    EPISODES_FILE,
    EVALUATIONS_FILE,
    MODEL_FILE,
    NORMALIZE_FILE,
    REPLAY_ALGOS,
    REPLAY_FILE,
    is_goal_env,
)

__all__ = ["print_summary"]


def print_summary(eval_episodes: int, result: Any) -> None:
    """Steps, wall time, fps, the recent training return, a deterministic evaluation, the
    learning curve, and the list of files written (``result``: a ``TrainResult``)."""
    model, run_dir, algo = result.model, result.run_dir, result.spec.algo
    steps, seconds, env_id = result.session_steps, result.session_seconds, result.spec.env_id
    written = [CONFIG_FILE, "progress.csv", EPISODES_FILE, MODEL_FILE]
    print(
        f"trained {algo} on {env_id}: {model.num_timesteps:,} steps, "
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
    try:
        drawing = draw_learning_curve(run_dir, f"{algo.upper()} on {env_id}")
        curve = LEARNING_CURVE_FILE + " (drawing)" * (drawing is not None)
    except DependencyNotInstalled:
        eprint(f"note: matplotlib is not installed, so no {LEARNING_CURVE_FILE}")
        curve = ""
    evaluations = read_evaluations(run_dir)
    if evaluations is not None and len(evaluations.mean):
        best = int(np.argmax(evaluations.mean))
        print(
            f"evaluations during training: {len(evaluations.mean)}, the last "
            f"{evaluations.mean[-1]:.2f} at {evaluations.steps[-1]:,} steps, the best "
            f"{evaluations.mean[best]:.2f} at {evaluations.steps[best]:,} steps ({BEST_MODEL_FILE})"
        )
        written += [EVALUATIONS_FILE, BEST_MODEL_FILE]
        if (run_dir / BEST_NORMALIZE_FILE).is_file():
            written.append(BEST_NORMALIZE_FILE)
    if eval_episodes > 0:
        played = evaluate_run(run_dir, eval_episodes, model=model, spec=result.spec)
        unit = ("game" if played.games else "episode") + "s" * (eval_episodes != 1)
        print(f"evaluation ({eval_episodes} {unit}, deterministic, seed 0):")
        if played.games:
            print(f"  {GAMES_NOTE}")
        for text in summary_lines(played, env_id):
            print(f"  {text}")
    if curve:
        written.append(curve)
    if algo in REPLAY_ALGOS:
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
