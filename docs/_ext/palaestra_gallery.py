"""The environment gallery: one page per env family, one entry per registered env id.

When the build starts, every id in ``palaestra.registry`` is made, its spaces and limits are
read from the live env, and a short animation is rendered by palaestra itself (``rgb_array``
frames of a seeded random policy, written as a GIF with Pillow). The GIFs are cached in
``docs/_build/gallery-cache/``, keyed by a hash of the env id, its spec, the env's source file
and this file, so a build renders only what changed; they are never committed.

The prose (what the env is, rewards, episode end, version history) is in ``env_notes.py``.
An id with no notes fails the build, so a newly registered env cannot be left out.
"""

from __future__ import annotations

import hashlib
import importlib
import inspect
import multiprocessing
import os
import shutil
import time
import zlib
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import env_notes
import numpy as np
from sphinx.application import Sphinx
from sphinx.errors import ExtensionError
from sphinx.util import logging

logger = logging.getLogger(__name__)

FAMILIES = env_notes.FAMILIES
# Steps of the random policy filmed per env, and the frame size limit (frames are subsampled).
STEPS = 60
MAX_SIDE = 200
MUJOCO_SIDE = 192  # MuJoCo renders in software (EGL, llvmpipe) on CI: its cost grows with pixels
RENDER_VERSION = "3"
# Random steps taken before filming, per family: many Atari games play an intro of a few
# seconds in which no action matters, and the film would show only that.
WARMUP = {"atari": 150}


def family_of(env_id: str) -> str:
    """The gallery page an id belongs on: the package its entry point lives in."""
    import palaestra

    entry = palaestra.spec(env_id).entry_point
    module = entry.split(":")[0] if isinstance(entry, str) else entry.__module__
    parts = module.split(".")
    if parts[:2] != ["palaestra", "envs"] or parts[2] not in FAMILIES:
        raise ExtensionError(f"env id {env_id!r}: entry point {entry!r} is in no gallery family")
    return parts[2]


def gallery_ids() -> dict[str, list[str]]:
    """Every registered id, grouped by family, in registration order."""
    import palaestra

    groups: dict[str, list[str]] = {name: [] for name in FAMILIES}
    for env_id in palaestra.registry:
        groups[family_of(env_id)].append(env_id)
    return groups


def page_anchor(env_id: str) -> str:
    """The HTML id of an env's section (what MyST makes of its heading)."""
    return env_id.lower().replace("/", "").replace(".", "").replace("_", "-")


def file_stem(env_id: str) -> str:
    return env_id.replace("/", "_")


def _source_hash(env_id: str) -> str:
    import palaestra

    spec = palaestra.spec(env_id)
    entry = spec.entry_point
    module = importlib.import_module(
        entry.split(":")[0] if isinstance(entry, str) else entry.__module__
    )
    digest = hashlib.sha256()
    digest.update(
        repr(
            (env_id, sorted(spec.kwargs.items()), spec.max_episode_steps, STEPS, MAX_SIDE)
        ).encode()
    )
    digest.update(Path(inspect.getfile(module)).read_bytes())
    digest.update(RENDER_VERSION.encode())
    warmup = WARMUP.get(family_of(env_id))
    if warmup:
        digest.update(f"warmup {warmup}".encode())
    return digest.hexdigest()[:16]


def _render_kwargs(env_id: str) -> dict[str, Any]:
    if family_of(env_id) == "mujoco":
        return {"width": MUJOCO_SIDE, "height": MUJOCO_SIDE}
    return {}


def render_gif(env_id: str, path: Path) -> int:
    """Film a seeded random policy on ``env_id`` into ``path``; returns the number of frames."""
    from PIL import Image

    import palaestra

    env = palaestra.make(env_id, render_mode="rgb_array", **_render_kwargs(env_id))
    spec_skip = palaestra.spec(env_id).kwargs.get("frameskip", 4)
    # Atari's NoFrameskip ids step one emulator frame at a time: film every 4th.
    stride = 4 if family_of(env_id) == "atari" and spec_skip == 1 else 1
    # A seed of its own per id: two ids of one game (ALE/X-v5, XNoFrameskip-v4) or one model
    # (CartPole-v0/v1) would otherwise film the same random episode.
    seed = zlib.crc32(env_id.encode()) % 10_000
    env.action_space.seed(seed)
    env.reset(seed=seed)
    for _ in range(WARMUP.get(family_of(env_id), 0) * stride):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()
    frames = [env.render()]
    for step in range(STEPS * stride):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if step % stride == stride - 1:
            frames.append(env.render())
        if terminated or truncated:
            env.reset()
    env.close()
    rgb = []
    for frame in frames:
        image = Image.fromarray(np.asarray(frame, dtype=np.uint8))
        scale = MAX_SIDE / max(image.size)
        if scale < 1:
            image = image.resize(
                (round(image.width * scale), round(image.height * scale)), Image.Resampling.BILINEAR
            )
        rgb.append(image)
    # One palette for the whole clip (from a few frames side by side), no dithering: fast, and
    # the colours do not flicker between frames.
    sample = rgb[:: max(1, len(rgb) // 6)]
    strip = Image.new("RGB", (sum(i.width for i in sample), max(i.height for i in sample)))
    x = 0
    for image in sample:
        strip.paste(image, (x, 0))
        x += image.width
    palette = strip.quantize(colors=96)
    images = [image.quantize(palette=palette, dither=Image.Dither.NONE) for image in rgb]
    fps = env.metadata.get("render_fps") or 30
    tmp = path.with_suffix(".tmp.gif")
    images[0].save(
        tmp, save_all=True, append_images=images[1:], duration=int(1000 / min(fps, 30)), loop=0
    )
    tmp.replace(path)
    return len(images)


def _render_one(env_id: str, path: str) -> str:
    render_gif(env_id, Path(path))
    return env_id


def _render_missing(env_ids: list[str], cache: Path) -> int:
    """Render the animations not in the cache, on every core; returns how many were rendered."""
    todo = []
    for env_id in env_ids:
        stem = file_stem(env_id)
        cached = cache / f"{stem}-{_source_hash(env_id)}.gif"
        if not cached.exists():
            for old in cache.glob(f"{stem}-*.gif"):
                old.unlink()
            todo.append((env_id, str(cached)))
    if not todo:
        return 0
    # Fresh interpreters (spawn): no OpenGL context or torch state is inherited from the build.
    context = multiprocessing.get_context("spawn")
    # PALAESTRA_DOCS_JOBS caps the workers on a shared machine; CI uses every core.
    jobs = int(os.environ.get("PALAESTRA_DOCS_JOBS") or os.cpu_count() or 1)
    with ProcessPoolExecutor(max_workers=min(len(todo), jobs), mp_context=context) as pool:
        for env_id in pool.map(_render_one, *zip(*todo)):
            logger.debug("gallery: rendered %s", env_id)
    return len(todo)


def _spec_rows(env_id: str) -> list[tuple[str, str]]:
    import palaestra

    spec = palaestra.spec(env_id)
    env = palaestra.make(env_id)
    rows = [
        ("Observation space", f"`{env.observation_space}`"),
        ("Action space", f"`{env.action_space}`"),
        (
            "Time limit (`max_episode_steps`)",
            str(spec.max_episode_steps) if spec.max_episode_steps else "none",
        ),
        (
            "Reward threshold",
            str(spec.reward_threshold) if spec.reward_threshold is not None else "none",
        ),
        ("Make it", f'`palaestra.make("{env_id}")`'),
        ("Class", f"`{spec.entry_point}`"),
    ]
    if spec.kwargs:
        args = ", ".join(f"{k}={v!r}" for k, v in spec.kwargs.items())
        rows.append(("Registered arguments", f"`{args}`"))
    env.close()
    return rows


def write_pages(app: Sphinx) -> None:
    src = Path(app.srcdir) / "envs"
    anim = src / "anim"
    anim.mkdir(parents=True, exist_ok=True)
    cache = Path(app.outdir).parent / "gallery-cache"
    cache.mkdir(parents=True, exist_ok=True)
    groups = gallery_ids()
    start = time.perf_counter()
    rendered = _render_missing([env_id for ids in groups.values() for env_id in ids], cache)
    index = [
        "# Environment gallery",
        "",
        "Every environment palaestra registers, one page per family. Each entry shows the spaces and",
        "limits read from the live environment, what the rewards are, when an episode ends, the",
        "version history, and an animation of a random policy drawn by palaestra when this site was",
        "built (`make docs` renders them once and caches them in `docs/_build/gallery-cache/`).",
        "",
        "```{toctree}",
        ":maxdepth: 1",
        "",
    ]
    for family, ids in groups.items():
        info = FAMILIES[family]
        index.append(family)
        lines = [f"# {info['title']}", "", info["intro"].strip(), ""]
        for env_id in ids:
            notes = env_notes.notes_for(env_id)
            if notes is None:
                raise ExtensionError(f"env id {env_id!r} has no entry in docs/_ext/env_notes.py")
            stem = file_stem(env_id)
            cached = cache / f"{stem}-{_source_hash(env_id)}.gif"
            target = anim / f"{stem}.gif"
            if not target.exists() or target.read_bytes() != cached.read_bytes():
                shutil.copyfile(cached, target)
            lines += [f"(env-{stem})=", f"## {env_id}", ""]
            lines += [
                f"```{{image}} anim/{stem}.gif",
                f":alt: {env_id}, a random policy, rendered by palaestra",
                ":class: palaestra-anim",
                "```",
                "",
            ]
            lines += [notes["summary"].strip(), ""]
            lines += ["| | |", "|---|---|"]
            lines += [f"| {k} | {v} |" for k, v in _spec_rows(env_id)]
            lines += [""]
            for title, field in (
                ("Rewards", "rewards"),
                ("Episode end", "end"),
                ("Version history", "versions"),
            ):
                lines += [f"**{title}.** {notes[field].strip()}", ""]
        _write_if_changed(src / f"{family}.md", "\n".join(lines))
    index.append("```")
    _write_if_changed(src / "index.md", "\n".join(index) + "\n")
    logger.info(
        "gallery: %d animations rendered, the rest cached (%.1f s)",
        rendered,
        time.perf_counter() - start,
    )


def _write_if_changed(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def setup(app: Sphinx) -> dict[str, Any]:
    app.connect("builder-inited", write_pages)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
