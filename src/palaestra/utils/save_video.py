"""Gymnasium's ``gymnasium.utils.save_video`` path: ``save_video`` and its episode trigger.

``save_video(frames, video_folder, episode_trigger=..., step_trigger=..., fps=...)`` writes
the videos Gymnasium's function writes, with the same file names
(``{name_prefix}-episode-{i}.mp4``, ``{name_prefix}-step-{i}.mp4``) and the same triggers,
through :func:`palaestra.utils.video.save_video` (imageio-ffmpeg, the ``video`` extra) instead
of MoviePy, so each file is written atomically.

``palaestra.utils.save_video`` was palaestra's ``save_video(frames, path, fps)`` before this
module took the name; calling the module still does exactly that, so both
``from palaestra.utils.save_video import save_video`` (Gymnasium's code) and
``palaestra.utils.save_video(frames, "run.gif")`` keep working.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from palaestra.utils import video
from palaestra.utils.video import capped_cubic_video_schedule

__all__ = ["capped_cubic_video_schedule", "save_video"]


def save_video(
    frames: list[np.ndarray],
    video_folder: str | os.PathLike[str],
    episode_trigger: Callable[[int], bool] | None = None,
    step_trigger: Callable[[int], bool] | None = None,
    video_length: int | None = None,
    name_prefix: str = "rl-video",
    episode_index: int = 0,
    step_starting_index: int = 0,
    save_logger: Any = None,
    **kwargs: Any,
) -> None:
    """Write an episode's ``frames`` as MP4 files in ``video_folder``, as Gymnasium does.

    With neither trigger, ``capped_cubic_video_schedule`` picks the episodes. An episode that
    ``episode_trigger(episode_index)`` selects is written whole (or its first
    ``video_length`` frames) to ``{name_prefix}-episode-{episode_index}.mp4``; each step ``i``
    (counted from ``step_starting_index``; frame 0 is the reset's) that ``step_trigger(i)``
    selects starts a clip of ``video_length`` frames (to the end if None) written to
    ``{name_prefix}-step-{i}.mp4``. ``fps`` (a keyword, as MoviePy needs it) is required;
    other MoviePy keywords are refused. ``save_logger`` other than None prints each file.
    """
    fps = kwargs.pop("fps", None)
    if kwargs:
        raise TypeError(
            f"save_video takes fps= for the clip, got other MoviePy arguments {sorted(kwargs)} "
            "(palaestra writes with imageio-ffmpeg)"
        )
    if fps is None:
        raise TypeError("save_video needs fps=<frames per second> (Gymnasium passes it to MoviePy)")
    if not isinstance(frames, (list, np.ndarray)):
        raise TypeError(f"Expected a list of frames, got a {type(frames).__name__} instead.")
    if video_length is not None and not (isinstance(video_length, int) and video_length > 0):
        raise ValueError(f"video_length must be a positive int or None, got {video_length!r}")
    if episode_trigger is None and step_trigger is None:
        episode_trigger = capped_cubic_video_schedule
    folder = Path(os.path.abspath(video_folder))
    folder.mkdir(parents=True, exist_ok=True)

    def write(clip: Any, name: str) -> None:
        path = video.save_video(clip, folder / f"{name_prefix}-{name}.mp4", fps=fps)
        if save_logger is not None:  # MoviePy's logger prints its progress; this the file
            print(f"Saved video {path}")

    if episode_trigger is not None and episode_trigger(episode_index):
        write(frames[:video_length], f"episode-{episode_index}")
    if step_trigger is not None:
        # frame 0 comes from reset: step i's frame is frame i - step_starting_index + 1
        for step_index, start in enumerate(range(1, len(frames)), start=step_starting_index):
            if step_trigger(step_index):
                end = None if video_length is None else start + video_length
                write(frames[start:end], f"step-{step_index}")


class _SaveVideoModule(ModuleType):
    """This module, callable as palaestra's ``save_video(frames, path, fps)`` was."""

    def __call__(self, frames: Any, path: str | os.PathLike[str], fps: float = 30) -> Path:
        """:func:`palaestra.utils.video.save_video`: ``frames`` to ``path`` (.gif or .mp4)."""
        return video.save_video(frames, path, fps=fps)


sys.modules[__name__].__class__ = _SaveVideoModule
