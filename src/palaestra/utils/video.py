"""Write a list of ``(H, W, 3) uint8`` frames to a GIF or MP4 file with one call.

GIF needs Pillow; MP4 needs imageio with the imageio-ffmpeg backend. Both are in the
``video`` extra: ``pip install "palaestra[video]"``. Neither is imported until a file of that
kind is written.
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterable
from pathlib import Path
from typing import BinaryIO

import numpy as np

from palaestra.error import dependency_not_installed
from palaestra.utils.atomic_write import atomic_path

__all__ = [
    "capped_cubic_video_schedule",
    "encode_gif",
    "mp4_available",
    "save_video",
    "validate_frames",
]

SUPPORTED_SUFFIXES = (".gif", ".mp4")


def validate_frames(frames: Iterable[np.ndarray]) -> list[np.ndarray]:
    """Check that ``frames`` is a non-empty sequence of equal-shape ``(H, W, 3) uint8`` arrays.

    >>> len(validate_frames([np.zeros((4, 6, 3), np.uint8)] * 2))
    2
    >>> validate_frames([])
    Traceback (most recent call last):
    ...
    ValueError: save_video needs at least one frame, got none
    """
    if isinstance(frames, np.ndarray) and frames.ndim == 4:
        frames = list(frames)  # a [T, H, W, 3] stack
    out = list(frames)
    if not out:
        raise ValueError("save_video needs at least one frame, got none")
    first_shape = None
    for i, frame in enumerate(out):
        if not isinstance(frame, np.ndarray):
            raise TypeError(f"frame {i} is a {type(frame).__name__}, expected a numpy array")
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
            raise ValueError(
                f"frame {i} has shape {frame.shape} and dtype {frame.dtype}, "
                "expected (H, W, 3) uint8 (an RGB image as returned by render())"
            )
        if first_shape is None:
            first_shape = frame.shape
        elif frame.shape != first_shape:
            raise ValueError(
                f"frame {i} has shape {frame.shape} but frame 0 has {first_shape}; "
                "all frames of a video must have the same size"
            )
    return out


def capped_cubic_video_schedule(episode_id: int) -> bool:
    """Gymnasium's default recording trigger: episodes 0, 1, 8, 27, ..., 729, then every 1000th.

    >>> [i for i in range(3001) if capped_cubic_video_schedule(i)][:12]
    [0, 1, 8, 27, 64, 125, 216, 343, 512, 729, 1000, 2000]
    """
    if episode_id < 1000:
        return round(episode_id ** (1.0 / 3)) ** 3 == episode_id
    return episode_id % 1000 == 0


def mp4_available() -> bool:
    """Whether MP4 can be written here (imageio and imageio-ffmpeg importable)."""
    try:
        import imageio  # noqa: F401
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        return False
    return True


def save_video(frames: Iterable[np.ndarray], path: str | os.PathLike[str], fps: float = 30) -> Path:
    """Write ``frames`` to ``path`` (``.gif`` or ``.mp4``) at ``fps`` frames per second.

    The folder is created if needed and the written path is returned. GIFs loop forever and
    use an adaptive 256-colour (fast octree) palette per frame; GIF stores delays in
    hundredths of a second, so ``fps`` is rounded to the nearest 10 ms per frame, and Pillow
    merges identical consecutive frames into one longer frame (playback time is unchanged).

    Raises ``ValueError``/``TypeError`` for bad frames, a bad ``fps`` or an unsupported
    suffix, and :class:`palaestra.error.DependencyNotInstalled` naming the ``pip install``
    when Pillow (GIF) or imageio-ffmpeg (MP4) is missing.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUPPORTED_SUFFIXES:
        raise ValueError(
            f"cannot write {str(path)!r}: supported video formats are "
            f"{', '.join(SUPPORTED_SUFFIXES)} (choose the format with the file suffix)"
        )
    if not (isinstance(fps, (int, float)) and np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a positive number, got {fps!r}")
    checked = validate_frames(frames)
    path.parent.mkdir(parents=True, exist_ok=True)
    # Written beside the target and moved into place: an interrupted recording never leaves
    # a truncated video. ffmpeg picks the container from the name, so the temporary file keeps
    # the suffix.
    with atomic_path(path, suffix=".tmp" + path.suffix) as temp:
        if suffix == ".gif":
            _write_gif(checked, temp, fps)
        else:
            _write_mp4(checked, temp, fps)
    return path


def encode_gif(frames: Iterable[np.ndarray], fps: float = 30) -> bytes:
    """The bytes of a looping GIF of ``frames`` (for inline display), as written by save_video."""
    buffer = io.BytesIO()
    _write_gif(validate_frames(frames), buffer, fps)
    return buffer.getvalue()


def _write_gif(frames: list[np.ndarray], path: Path | BinaryIO, fps: float) -> None:
    try:
        from PIL import Image
    except ImportError as e:
        raise dependency_not_installed("Pillow", "video", "writing GIF files") from e
    # An adaptive palette per frame keeps anti-aliased edges smooth (the default web palette
    # bands them). Fast octree instead of median cut: ~6 instead of ~45 ms per 600x400 frame
    # (benchmarks/render.py), colours within a few levels (white may come back as 254).
    images = [Image.fromarray(f).quantize(256, method=Image.Quantize.FASTOCTREE) for f in frames]
    duration = max(round(1000 / fps / 10) * 10, 10)  # GIF delays are in 1/100 s
    images[0].save(
        path,
        format="GIF",
        save_all=True,
        append_images=images[1:],
        duration=duration,
        loop=0,  # loop forever
        optimize=True,
        disposal=1,  # keep the previous frame under the next one (lets frames be deltas)
    )


def _write_mp4(frames: list[np.ndarray], path: Path, fps: float) -> None:
    try:
        import imageio.v2 as imageio
        import imageio_ffmpeg  # noqa: F401  (imageio's ffmpeg plugin needs it)
    except ImportError as e:
        raise dependency_not_installed("imageio-ffmpeg", "video", "writing MP4 files") from e
    # macro_block_size=2: H.264 with yuv420p needs even sizes only; imageio's default of 16
    # would rescale 600x400 frames to 608x400.
    with imageio.get_writer(
        path, format="FFMPEG", mode="I", fps=fps, codec="libx264", macro_block_size=2
    ) as writer:
        for frame in frames:
            writer.append_data(frame)  # type: ignore[attr-defined]
