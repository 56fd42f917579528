"""``palaestra envs``: the registered ids with their spaces, reward thresholds, time limits and
the algorithms with a shipped preset for them (what ``palaestra train ALGO ID`` starts from).

Classic-control envs are built (unwrapped, no rendering: microseconds) to read their spaces.
Atari envs are not: loading a ROM takes ale-py and time, so their spaces are described from
the registration kwargs, and the rows are marked.
"""

from __future__ import annotations

import argparse
import importlib.util
import re
from typing import Any

import palaestra
from palaestra import presets
from palaestra.envs.atari.games import ENTRY_POINT as _ATARI_ENTRY
from palaestra.envs.registration import load_env_creator

__all__ = ["add_parser", "env_rows", "run"]

_ATARI_OBS = {
    "rgb": "Box(0, 255, (210, 160, 3), uint8)",
    "grayscale": "Box(0, 255, (210, 160), uint8)",
    "ram": "Box(0, 255, (128,), uint8)",
}


def _one_line(space: Any) -> str:
    return re.sub(r"\s*\n\s*", " ", str(space))


def _spaces(spec: Any) -> tuple[str, str, bool]:
    """``(observation space, action space, is_atari)`` as text."""
    entry = spec.entry_point
    if entry == _ATARI_ENTRY:
        obs = _ATARI_OBS.get(spec.kwargs.get("obs_type", "rgb"), "?")
        full = spec.kwargs.get("full_action_space", False)
        return obs, "Discrete(18)" if full else "Discrete(<=18)", True

    try:
        creator = load_env_creator(entry) if isinstance(entry, str) else entry
        env = creator(**spec.kwargs)
    except Exception:  # a third-party entry point may fail in any way: show the row anyway
        return "?", "?", False
    try:
        # One line per row: numpy wraps long Box bounds (LunarLander's 8) over several lines.
        return _one_line(env.observation_space), _one_line(env.action_space), False
    finally:
        env.close()


def preset_algos() -> dict[str, str]:
    """``{env id: "algo,algo"}``: the algorithms with a shipped preset for each id, sorted,
    joined without spaces so that the table's column stays one word."""
    by_env: dict[str, list[str]] = {}
    for algo, envs in presets.available().items():
        for env_id in envs:
            by_env.setdefault(env_id, []).append(algo)
    return {env_id: ",".join(sorted(algos)) for env_id, algos in by_env.items()}


def env_rows(text: str | None = None) -> list[tuple[str, str, str, str, str, str, bool]]:
    """``(id, observation, action, reward threshold, max steps, presets, is_atari)`` for each
    registered id whose id contains ``text`` (case-insensitive); ``presets`` is
    :func:`preset_algos`' entry, ``"-"`` where there is none."""
    rows = []
    with_presets = preset_algos()
    for env_id, spec in palaestra.registry.items():
        if text and text.lower() not in env_id.lower():
            continue
        obs, act, atari = _spaces(spec)
        threshold = "-" if spec.reward_threshold is None else f"{spec.reward_threshold:g}"
        limit = "-" if spec.max_episode_steps is None else str(spec.max_episode_steps)
        rows.append((env_id, obs, act, threshold, limit, with_presets.get(env_id, "-"), atari))
    return sorted(rows, key=lambda r: (r[6], r[0].lower()))  # Atari after the others


def add_parser(sub: Any) -> None:
    """Register ``envs`` on the subcommand parsers."""
    p = sub.add_parser(
        "envs",
        help="list the registered env ids",
        description="List the registered env ids with their observation and action spaces, "
        "reward thresholds, time limits and the algorithms with a shipped preset for the id "
        "(palaestra train ALGO ID uses it). Atari ids (marked *) need ale-py to run.",
    )
    p.add_argument(
        "--filter",
        metavar="TEXT",
        help="only ids containing TEXT (case-insensitive), e.g. --filter cart",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The ``envs`` command."""
    rows = env_rows(args.filter)
    if not rows:
        print(f"no registered env id contains {args.filter!r}")
        return 0
    # The observation space goes last: a Box's bounds can be long.
    header = ("id", "action space", "threshold", "max steps", "presets", "observation space")
    table = [(f"{r[0]} *" if r[6] else r[0], r[2], r[3], r[4], r[5], r[1]) for r in rows]
    widths = [max(len(h), *(len(t[i]) for t in table)) for i, h in enumerate(header)]
    line = "  ".join(f"{{:<{w}}}" for w in widths)
    print(line.format(*header).rstrip())
    print("  ".join("-" * w for w in widths))
    for t in table:
        print(line.format(*t).rstrip())
    n_atari = sum(r[6] for r in rows)
    if n_atari:
        have = importlib.util.find_spec("ale_py") is not None
        state = "installed" if have else 'not installed: pip install "palaestra[atari]"'
        print(
            f"\n* {n_atari} Atari ids: need ale-py ({state}); spaces shown without loading the "
            "ROM (the minimal action set has up to 18 actions, depending on the game)"
        )
    print(f"{len(rows)} env ids")
    return 0
