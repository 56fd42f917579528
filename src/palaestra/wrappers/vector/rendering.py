"""Vector ``HumanRendering`` and ``RecordVideo`` (``gymnasium.wrappers.vector``): the frames
of all sub-envs tiled into one picture, shown in a window after each ``reset``/``step`` or
saved as videos of the episodes of env 0.

Tiling follows Gymnasium: ``HumanRendering`` grows a grid until it holds every env, keeping
the screen's aspect, and scales each frame to its cell; ``RecordVideo`` picks the rows x
columns grid whose aspect is nearest ``video_aspect_ratio``. Gymnasium scales with OpenCV's
bilinear filter and shows the window with pygame; palaestra scales with its area filter
(nearest pixel when enlarging) and shows the window with ``rendering.window.HumanWindow``, so
no OpenCV is needed and the window never blocks the caller.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from palaestra import logger
from palaestra.rendering.window import HumanWindow
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.vector.vector_env import AutoresetMode, VectorEnv, VectorWrapper
from palaestra.wrappers.record_video import VideoRecording, check_video_settings
from palaestra.wrappers.rendering import check_human_rendering
from palaestra.wrappers.resize import resize_area

__all__ = ["HumanRendering", "RecordVideo"]


def _scale(frame: np.ndarray, height: int, width: int) -> np.ndarray:
    """``frame`` (H, W, C) resized to (height, width): area average when shrinking (no
    OpenCV), nearest pixel otherwise."""
    h, w = frame.shape[:2]
    if (height, width) == (h, w):
        return frame
    if height <= h and width <= w:
        return resize_area(frame, (height, width))
    rows = np.minimum((np.arange(height) * h) // height, h - 1)
    cols = np.minimum((np.arange(width) * w) // width, w - 1)
    return frame[rows][:, cols]


def _frames(env: VectorEnv[Any, Any, Any]) -> list[np.ndarray]:
    rendered = env.render()
    if rendered is None or len(rendered) != env.num_envs:
        raise ValueError(
            f"expected env.render() to return {env.num_envs} frames, got {rendered!r:.80}"
        )
    frames = [f[-1] if isinstance(f, list) else f for f in rendered]
    if not all(isinstance(f, np.ndarray) for f in frames):
        raise TypeError(
            "Expected `env.render()` to return a numpy array, actually returned "
            f"{[type(f) for f in frames]}"
        )
    return frames


class HumanRendering(VectorWrapper[Any, Any, Any], RecordConstructorArgs):
    """Show the sub-envs' ``rgb_array`` frames tiled in one window (``screen_size`` as
    ``(width, height)``; default: one frame's size)."""

    ACCEPTED_RENDER_MODES = ("rgb_array", "rgb_array_list", "depth_array", "depth_array_list")

    def __init__(
        self,
        env: VectorEnv[Any, Any, Any],
        screen_size: tuple[int, int] | None = None,
        backend: str | None = None,
    ) -> None:
        VectorWrapper.__init__(self, env)
        RecordConstructorArgs.__init__(self, screen_size=screen_size, backend=backend)
        self.window: Any = None  # first: close() may run on a half-built wrapper
        self.screen_size = screen_size
        self.scaled_subenv_size: tuple[int, int] | None = None  # (width, height)
        self.num_rows: int | None = None
        self.num_cols: int | None = None
        self._backend = backend
        check_human_rendering(self)

    @property
    def render_mode(self) -> str:  # type: ignore[override]
        """Always ``"human"``."""
        return "human"

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        result = self.env.reset(**kwargs)
        self._render_frame()
        return result

    def step(self, actions: Any) -> Any:
        result = self.env.step(actions)
        self._render_frame()
        return result

    def render(self) -> None:
        """Nothing to return: frames are shown by ``step`` and ``reset``."""
        return None

    def _layout(self, width: int, height: int) -> None:
        """Gymnasium's grid: add a column or a row (the side with room) until every env fits,
        then the largest scale at which the grid fits the screen."""
        assert self.screen_size is not None
        screen_w, screen_h = self.screen_size
        width_ratio, height_ratio = width / screen_w, height / screen_h
        rows = cols = 1
        while rows * cols < self.num_envs:
            if rows * height_ratio == cols * width_ratio:
                rows, cols = rows + 1, cols + 1
            elif rows * height_ratio > cols * width_ratio:
                cols += 1
            else:
                rows += 1
        scale = min(screen_w / (cols * width), screen_h / (rows * height))
        self.num_rows, self.num_cols = rows, cols
        self.scaled_subenv_size = (int(width * scale), int(height * scale))

    def tiled_frame(self) -> np.ndarray:
        """The current frames tiled as the window shows them, ``(height, width, 3)`` uint8."""
        frames = [np.asarray(f, dtype=np.uint8) for f in _frames(self.env)]
        height, width = frames[0].shape[:2]
        if self.screen_size is None:
            self.screen_size = (width, height)
        if self.scaled_subenv_size is None:
            self._layout(width, height)
        assert self.scaled_subenv_size is not None and self.num_cols is not None
        cell_w, cell_h = self.scaled_subenv_size
        screen_w, screen_h = self.screen_size
        merged = np.zeros((screen_h, screen_w, 3), dtype=np.uint8)
        for i, frame in enumerate(frames):
            row, col = divmod(i, self.num_cols)
            x, y = col * cell_w, row * cell_h
            merged[y : y + cell_h, x : x + cell_w] = _scale(frame[..., :3], cell_h, cell_w)
        return merged

    def _render_frame(self) -> None:
        merged = self.tiled_frame()
        if self.window is None:
            fps = int(self.env.metadata["render_fps"])
            title = self.env.spec.id if self.env.spec is not None else "vector env"
            self.window = HumanWindow(title, fps, backend=self._backend)
        self.window.show(merged)

    def close(self, **kwargs: Any) -> None:
        if self.window is not None:
            self.window.close()
            self.window = None
        self.env.close(**kwargs)


class RecordVideo(VideoRecording, VectorWrapper[Any, Any, Any], RecordConstructorArgs):
    """Save videos of the tiled frames (``record_first_only``: env 0's alone) of the
    episodes of env 0 that ``episode_trigger`` picks, or of the step windows ``step_trigger``
    starts; with neither, episodes 0, 1, 8, 27, ... (Gymnasium's schedule). A recording stops
    when env 0's episode ends or after ``video_length`` frames; ``close()`` saves one in
    progress. Files are ``{name_prefix}-episode-{n}`` / ``-step-{n}``, MP4 with
    imageio-ffmpeg installed, else GIF (``video_format`` picks)."""

    def __init__(
        self,
        env: VectorEnv[Any, Any, Any],
        video_folder: str,
        video_aspect_ratio: tuple[int, int] = (1, 1),
        record_first_only: bool = False,
        episode_trigger: Callable[[int], bool] | None = None,
        step_trigger: Callable[[int], bool] | None = None,
        video_length: int = 0,
        name_prefix: str = "rl-video",
        fps: int | None = None,
        disable_logger: bool = True,
        gc_trigger: Callable[[int], bool] | None = lambda episode: True,
        video_format: str | None = None,
    ) -> None:
        VectorWrapper.__init__(self, env)
        RecordConstructorArgs.__init__(
            self,
            video_folder=video_folder,
            episode_trigger=episode_trigger,
            step_trigger=step_trigger,
            video_length=video_length,
            name_prefix=name_prefix,
            disable_logger=disable_logger,
        )
        video_format, episode_trigger = check_video_settings(
            env.render_mode, video_format or None, episode_trigger, step_trigger
        )
        self.autoreset_mode = env.metadata.get("autoreset_mode", AutoresetMode.NEXT_STEP)
        if self.autoreset_mode == AutoresetMode.SAME_STEP:  # Gymnasium's warning
            logger.warn(
                "Vector environment's autoreset mode is same-step "
                "(https://farama.org/Vector-Autoreset-Mode). Recorded episodes will not contain "
                "the last frame of the episode."
            )
        self.has_autoreset = False
        self.episode_trigger, self.step_trigger = episode_trigger, step_trigger
        self.disable_logger, self.gc_trigger = disable_logger, gc_trigger
        self.record_first_only, self.video_aspect_ratio = record_first_only, video_aspect_ratio
        self.video_format = video_format
        self.frame_rows = self.frame_cols = -1
        self._init_recording(video_folder, fps, name_prefix, video_length)
        self.step_id = self.episode_id = -1

    def _grid(self, n: int, height: int, width: int) -> None:
        """The rows x columns (a divisor pair of ``n``) whose aspect is nearest the target."""
        target = self.video_aspect_ratio[0] / self.video_aspect_ratio[1]
        best, best_diff = (1, n), float("inf")
        for rows in range(1, int(n**0.5) + 1):
            if n % rows == 0:
                diff = abs((n // rows) * width / (rows * height) - target)
                if diff < best_diff:
                    best, best_diff = (rows, n // rows), diff
        self.frame_rows, self.frame_cols = best

    def _capture_frame(self) -> None:
        frames = _frames(self.env)
        if self.record_first_only:
            frames = frames[:1]
        height, width, channels = frames[0].shape
        if self.frame_cols == -1:
            self._grid(len(frames), height, width)
        grid = np.zeros(
            (self.frame_rows * height, self.frame_cols * width, channels), frames[0].dtype
        )
        for i, frame in enumerate(frames):
            row, col = divmod(i, self.frame_cols)
            grid[row * height : (row + 1) * height, col * width : (col + 1) * width] = frame
        self.recorded_frames.append(grid)

    def reset(
        self, *, seed: Any = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset; a reset of env 0 starts its next episode (and maybe a recording)."""
        if options is None or "reset_mask" not in options or options["reset_mask"][0]:
            self._episode_started()
        result = self.env.reset(seed=seed, options=options)
        self._capture_if_recording()
        self.has_autoreset = False
        return result

    def step(self, actions: Any) -> Any:
        """Step; env 0's episode ends start its next one where the autoreset mode says."""
        obs, rewards, terminations, truncations, infos = self.env.step(actions)
        self.step_id += 1
        ended = bool(terminations[0] or truncations[0])
        if self.autoreset_mode == AutoresetMode.NEXT_STEP:
            if self.has_autoreset:  # this step reset env 0
                self._episode_started()
            self.has_autoreset = ended
        elif self.autoreset_mode == AutoresetMode.SAME_STEP and ended:
            self._episode_started()
        self._step_trigger()
        self._capture_if_recording()
        return obs, rewards, terminations, truncations, infos

    def close(self, **kwargs: Any) -> None:
        """Close the env and save a recording in progress."""
        self.env.close(**kwargs)
        if self.recording:
            self.stop_recording()
