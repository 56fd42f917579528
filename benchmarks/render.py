"""Milliseconds per ``render()`` frame (``rgb_array``): palaestra's numpy rasterizer vs
Gymnasium's pygame renderer, plus save_video's GIF encoding.

Run from the repository root::

    .venv/bin/python benchmarks/render.py            # full run (~1 minute)
    .venv/bin/python benchmarks/render.py --quick    # smoke run

Both libraries ``make(id, render_mode="rgb_array")``, step the same pre-sampled actions from
the same seed (their dynamics are equal, so they draw the same states) and time only the
``render()`` calls. Each figure is the median over ``--repeats`` rounds, the libraries
interleaved round by round in one process so that machine noise hits both alike.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from typing import Any

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import palaestra

IDS = ["CartPole-v1", "MountainCar-v0", "MountainCarContinuous-v0", "Pendulum-v1", "Acrobot-v1"]


def render_ms(lib: Any, env_id: str, frames: int, seed: int = 0) -> float:
    """Mean milliseconds per render() over ``frames`` steps of random actions."""
    env = lib.make(env_id, render_mode="rgb_array")
    env.reset(seed=seed)
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(frames)]
    env.render()  # first frame builds caches / surfaces in both libraries
    total = 0.0
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
        start = time.perf_counter()
        env.render()
        total += time.perf_counter() - start
    env.close()
    return total / frames * 1e3


def gif_ms(frames: int) -> float:
    """Milliseconds per frame for save_video(..., '.gif') of MountainCar frames."""
    from palaestra.utils.video import save_video

    env = palaestra.make("MountainCar-v0", render_mode="rgb_array_list")
    env.reset(seed=0)
    for _ in range(frames - 1):
        env.step(env.action_space.sample())
    shots = env.render()
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        save_video(shots, os.path.join(tmp, "car.gif"), fps=30)
        return (time.perf_counter() - start) / len(shots) * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="few frames, one repeat")
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    frames, repeats = (30, 1) if args.quick else (args.frames, args.repeats)

    import gymnasium

    print(f"frames per round: {frames}, rounds: {repeats} (median shown)\n")
    print("| env | Gymnasium 1.x (pygame) ms/frame | palaestra ms/frame | speed-up |")
    print("|---|---:|---:|---:|")
    for env_id in IDS:
        ours, theirs = [], []
        for r in range(repeats):
            theirs.append(render_ms(gymnasium, env_id, frames, seed=r))
            ours.append(render_ms(palaestra, env_id, frames, seed=r))
        g, p = statistics.median(theirs), statistics.median(ours)
        print(f"| {env_id} | {g:.3f} | {p:.3f} | {g / p:.1f}x |")
    print(f"\nsave_video GIF (Pillow, adaptive palette): {gif_ms(frames // 3 or 10):.2f} ms/frame")


if __name__ == "__main__":
    main()
