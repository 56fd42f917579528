"""Atari env-steps per second: palaestra vs Gymnasium + ale-py, in one process.

Run from the repository root::

    .venv/bin/python benchmarks/atari.py                   # every case (~1 minute)
    .venv/bin/python benchmarks/atari.py --cases single    # one case
    .venv/bin/python benchmarks/atari.py --quick           # smoke run

Cases:

- ``single``: ``make("ALE/Breakout-v5")`` in both libraries (v5 defaults: frameskip 4, sticky
  actions 0.25, RGB observations, the wrappers ``make`` adds), random actions drawn once
  from a fixed seed (``np.int64``, as ``action_space.sample()`` gives them), reset at episode
  ends. Target: ratio >= 0.95 (the emulator dominates; the Python around it must not add).
- ``preprocessed``: ``FrameStackObservation(AtariPreprocessing(make("ALE/Breakout-v5",
  frameskip=1)), 4)`` in both libraries (Gymnasium's defaults: 30 no-ops, frame skip 4 with a
  max-pool, 84x84 grayscale); agent steps/s, each 4 emulator frames. Gymnasium's wrapper calls
  ``cv2.resize(INTER_AREA)``; where OpenCV is not installed its ``cv2`` is a stand-in whose
  ``resize`` is Pillow's ``Image.resize(BOX)`` (the line says which was measured, and the
  resize alone is timed too). Target: palaestra faster (ratio > 1).
- ``sb3-wrapper``: SB3's ``AtariWrapper`` (no-ops, frame skip 4 with max-pool, episodic life,
  FIRE reset, ``WarpFrame`` 84x84 grayscale, reward clipping) around
  ``make("BreakoutNoFrameskip-v4")``: palaestra's numpy ``WarpFrame`` vs SB3's with OpenCV;
  agent steps/s, the same stacks with emulation stubbed out (their own cost, which is what
  differs; steadier under load), and the warp alone. Target: ratio >= 1.
- ``vector``: ``make_vec("ALE/Breakout-v5", num_envs=n)`` for n = 2 and 4 in both libraries
  (both ale-py's ``ALEVectorInterface``); env-steps/s (``atari_vector.py``). Target: ratio
  >= 0.90.
- ``memory``: bytes of DQN's ``optimize_memory_usage`` replay buffer holding 100k real Breakout
  transitions (84x84x4 stacks) vs 1.2x the bytes of 100k unique frames, and SB3's buffers
  (``atari_memory.py``; ``--quick``: 2k transitions). Not a speed ratio.

Each figure is the median of ``--repeats`` runs, the two libraries interleaved. Time is the
process's CPU time (``time.process_time``): the shared machine is busy with other jobs, and
wall time there would measure their load as much as ours.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from atari_memory import bench_memory  # benchmarks/ is on sys.path when run as a script
from atari_vector import bench_vector

import palaestra

ENV_ID = "ALE/Breakout-v5"


def gymnasium_module() -> Any:
    """Gymnasium with ale-py's ids registered."""
    import ale_py
    import gymnasium

    gymnasium.register_envs(ale_py)
    return gymnasium


def single_rate(lib: Any, actions: np.ndarray) -> float:
    """Env-steps/s of one ``lib.make(ENV_ID)`` over ``actions``."""
    return steps_per_cpu_second(lib.make(ENV_ID), actions)


def steps_per_cpu_second(env: Any, actions: np.ndarray) -> float:
    """Steps/s of ``env`` over ``actions``, resetting at episode ends; closes ``env``."""
    env.reset(seed=0)
    step, reset = env.step, env.reset
    start = time.process_time()
    for action in actions:
        _, _, terminated, truncated, _ = step(action)
        if terminated or truncated:
            reset()
    elapsed = time.process_time() - start
    env.close()
    return len(actions) / elapsed


def bench_single(args: argparse.Namespace) -> None:
    """palaestra vs Gymnasium, one Breakout env each."""
    gymnasium = gymnasium_module()
    actions = np.random.default_rng(0).integers(0, 4, args.steps)  # Breakout: Discrete(4)
    ours, ref = [], []
    for _ in range(args.repeats):
        ours.append(single_rate(palaestra, actions))
        ref.append(single_rate(gymnasium, actions))
    p, g = statistics.median(ours), statistics.median(ref)
    print(f"{'single ' + ENV_ID:<34}{p:>12,.0f}{g:>12,.0f}{p / g:>7.2f}x   (target >= 0.95x)")
    runs = f"palaestra {[round(r) for r in ours]}, gymnasium {[round(r) for r in ref]}"
    print(f"{'':<34}runs: {runs}")


def opencv_or_pillow() -> str:
    """Import ``cv2``; without OpenCV, put a stand-in in ``sys.modules`` whose ``resize`` is
    Pillow's area-style ``BOX`` filter, so that Gymnasium's AtariPreprocessing can run.
    Returns what Gymnasium's resize is. ``drop_cv2_stand_in`` takes the stand-in out again."""
    import sys
    import types

    try:
        import cv2

        return f"OpenCV {cv2.__version__} cv2.resize(INTER_AREA)"
    except ImportError:
        from PIL import Image

    def resize(src: np.ndarray, dsize: tuple[int, int], interpolation: int) -> np.ndarray:
        return np.asarray(Image.fromarray(src).resize(dsize, Image.Resampling.BOX))

    shim = types.ModuleType("cv2")
    shim.INTER_AREA = 3  # type: ignore[attr-defined]
    shim.resize = resize  # type: ignore[attr-defined]
    shim.palaestra_stand_in = True  # type: ignore[attr-defined]
    sys.modules["cv2"] = shim
    return "no OpenCV here: Pillow Image.resize(BOX) stand-in"


def drop_cv2_stand_in() -> None:
    """Remove the ``cv2`` stand-in: SB3 (the memory case) treats any ``cv2`` as OpenCV and
    calls ``cv2.ocl``, which the stand-in does not have."""
    import sys

    if getattr(sys.modules.get("cv2"), "palaestra_stand_in", False):
        del sys.modules["cv2"]


def resize_micros(resize: Callable[[np.ndarray], Any], frame: np.ndarray, n: int = 2000) -> float:
    """CPU microseconds per call of ``resize(frame)``."""
    start = time.process_time()
    for _ in range(n):
        resize(frame)
    return (time.process_time() - start) / n * 1e6


def preprocessed_rate(lib: Any, actions: np.ndarray) -> float:
    """Agent steps/s of ``lib``'s AtariPreprocessing + FrameStackObservation(4) stack."""
    base = lib.make(ENV_ID, frameskip=1)
    env = lib.wrappers.FrameStackObservation(lib.wrappers.AtariPreprocessing(base), 4)
    return steps_per_cpu_second(env, actions)


def bench_preprocessed(args: argparse.Namespace) -> None:
    """palaestra vs Gymnasium, AtariPreprocessing + 4-frame stack on one Breakout env."""
    resize_kind = opencv_or_pillow()
    gymnasium = gymnasium_module()
    import cv2

    from palaestra.wrappers.resize import resize_area

    actions = np.random.default_rng(0).integers(0, 4, max(1, args.steps // 4))
    ours, ref = [], []
    for _ in range(args.repeats):
        ours.append(preprocessed_rate(palaestra, actions))
        ref.append(preprocessed_rate(gymnasium, actions))
    p, g = statistics.median(ours), statistics.median(ref)
    name = "preprocessed (agent steps)"
    print(f"{name:<34}{p:>12,.0f}{g:>12,.0f}{p / g:>7.2f}x   (target > 1x)")
    runs = f"palaestra {[round(r) for r in ours]}, gymnasium {[round(r) for r in ref]}"
    print(f"{'':<34}runs: {runs}")
    frame = palaestra.make(ENV_ID).unwrapped.ale.getScreenGrayscale()
    ours_us = resize_micros(lambda f: resize_area(f, (84, 84)), frame)
    ref_us = resize_micros(lambda f: cv2.resize(f, (84, 84), interpolation=cv2.INTER_AREA), frame)
    print(f"{'':<34}gymnasium resize: {resize_kind}")
    sizes = f"resize_area {ours_us:.0f} us, gymnasium's {ref_us:.0f} us"
    print(f"{'':<34}210x160 -> 84x84 gray: {sizes}")
    drop_cv2_stand_in()


SB3_ID = "BreakoutNoFrameskip-v4"


def sb3_wrapper_rate(lib: Any, wrapper: Any, actions: np.ndarray) -> float:
    """Agent steps/s of ``wrapper(lib.make(SB3_ID))``: SB3's AtariWrapper stack."""
    return steps_per_cpu_second(wrapper(lib.make(SB3_ID)), actions)


class _NoEmulation:
    """An ``ale`` whose ``act`` emulates nothing (the screen stays as it is): what is left of a
    step is the Python and numpy around the emulator, the part the libraries differ in."""

    def __init__(self, ale: Any) -> None:
        self._ale = ale

    def __getattr__(self, name: str) -> Any:  # a benchmark stand-in, not library code
        return getattr(self._ale, name)

    def act(self, *args: Any, **kwargs: Any) -> float:
        return 0.0


def stack_overhead_micros(env: Any, n: int = 1000) -> float:
    """CPU microseconds per agent step of ``env`` with emulation stubbed out; closes ``env``.
    Much steadier on a busy machine than the full rate, since emulation is ~60% of a step."""
    env.reset(seed=0)
    base = env.unwrapped
    base.ale = _NoEmulation(base.ale)
    start = time.process_time()
    for _ in range(n):
        env.step(0)
    elapsed = time.process_time() - start
    env.close()
    return elapsed / n * 1e6


def bench_sb3_wrapper(args: argparse.Namespace) -> None:
    """palaestra's ``AtariWrapper`` vs SB3's (with OpenCV) on BreakoutNoFrameskip-v4."""
    gymnasium = gymnasium_module()
    import cv2
    from stable_baselines3.common.atari_wrappers import AtariWrapper as SB3AtariWrapper

    from palaestra.wrappers import AtariWrapper
    from palaestra.wrappers.atari import WarpFrame

    actions = np.random.default_rng(0).integers(0, 4, max(1, args.steps // 4))
    ours, ref = [], []
    for _ in range(args.repeats):
        ours.append(sb3_wrapper_rate(palaestra, AtariWrapper, actions))
        ref.append(sb3_wrapper_rate(gymnasium, SB3AtariWrapper, actions))
    p, g = statistics.median(ours), statistics.median(ref)
    name = "SB3 AtariWrapper (agent steps)"
    print(f"{name:<34}{p:>12,.0f}{g:>12,.0f}{p / g:>7.2f}x   (target >= 1x, vs OpenCV)")
    runs = f"palaestra {[round(r) for r in ours]}, sb3 {[round(r) for r in ref]}"
    print(f"{'':<34}runs: {runs}")
    ours_us, ref_us = [], []
    for _ in range(args.repeats):
        ours_us.append(stack_overhead_micros(AtariWrapper(palaestra.make(SB3_ID))))
        ref_us.append(stack_overhead_micros(SB3AtariWrapper(gymnasium.make(SB3_ID))))
    o, r = statistics.median(ours_us), statistics.median(ref_us)
    print(
        f"{'':<34}stack without emulation: palaestra {o:.0f} us, SB3 {r:.0f} us per agent step "
        f"(ratio {r / o:.2f}x)"
    )
    frame = palaestra.make(ENV_ID).unwrapped.ale.getScreenRGB()
    warp = WarpFrame(palaestra.make(SB3_ID))
    ours_us = resize_micros(warp.observation, frame)

    def sb3_warp(f: np.ndarray) -> np.ndarray:
        gray = cv2.cvtColor(f, cv2.COLOR_RGB2GRAY)
        return cv2.resize(gray, (84, 84), interpolation=cv2.INTER_AREA)[:, :, None]

    ref_us = resize_micros(sb3_warp, frame)
    print(
        f"{'':<34}WarpFrame 210x160 RGB -> 84x84 gray: palaestra {ours_us:.0f} us, "
        f"SB3 + OpenCV {cv2.__version__} {ref_us:.0f} us"
    )


CASES: dict[str, Callable[[argparse.Namespace], None] | None] = {
    "single": bench_single,
    "preprocessed": bench_preprocessed,
    "sb3-wrapper": bench_sb3_wrapper,
    "vector": bench_vector,
    "memory": bench_memory,
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--quick", action="store_true", help="few steps, for a smoke test")
    args = parser.parse_args()
    if args.quick:
        args.repeats, args.steps = 1, 200
    import ale_py
    import gymnasium

    print(
        f"numpy {np.__version__}, gymnasium {gymnasium.__version__}, ale-py {ale_py.__version__}, "
        f"repeats {args.repeats}, {args.steps} steps each"
    )
    print(f"{'case':<34}{'palaestra':>12}{'gymnasium':>12}{'ratio':>8}   (env-steps/s)")
    for name in args.cases:
        case = CASES[name]
        if case is None:
            print(f"{name:<34}(not implemented yet)")
        else:
            case(args)


if __name__ == "__main__":
    main()
