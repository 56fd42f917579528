"""``RecordVideo``: save episodes (or fixed-length step windows) as videos (Gymnasium 1.x).

Files are ``{name_prefix}-episode-{n}.{ext}`` for episode triggers and
``{name_prefix}-step-{n}.{ext}`` for step triggers, written by
:func:`palaestra.utils.video.save_video`. The extension is ``mp4`` when imageio-ffmpeg is
installed and ``gif`` otherwise (Pillow only), unless ``video_format`` picks one; Gymnasium
always writes MP4 through MoviePy, which palaestra does not need.
"""

from __future__ import annotations

import gc
import os
from collections.abc import Callable
from typing import Any, SupportsFloat

import numpy as np

from palaestra import logger
from palaestra.core import ActType, Env, ObsType, RenderFrame, Wrapper
from palaestra.utils import video
from palaestra.utils.record_constructor import RecordConstructorArgs

__all__ = ["RecordVideo"]


def check_video_settings(
    render_mode: str | None,
    video_format: str | None,
    episode_trigger: Callable[[int], bool] | None,
    step_trigger: Callable[[int], bool] | None,
) -> tuple[str, Callable[[int], bool] | None]:
    """``(video_format, episode_trigger)`` checked as both ``RecordVideo`` wrappers (single and
    vector) check them: the env must render images; ``None`` picks MP4 where imageio-ffmpeg is
    installed, else GIF; with no trigger at all, Gymnasium's episode schedule."""
    if render_mode in {None, "human", "ansi"}:
        raise ValueError(
            f"Render mode is {render_mode}, which is incompatible with RecordVideo. "
            "Initialize your environment with a render_mode that returns an image, "
            "such as rgb_array."
        )
    if video_format is None:
        video_format = "mp4" if video.mp4_available() else "gif"
    if video_format not in ("mp4", "gif"):
        raise ValueError(f"video_format must be 'mp4' or 'gif', got {video_format!r}")
    if episode_trigger is None and step_trigger is None:
        episode_trigger = video.capped_cubic_video_schedule
    return video_format, episode_trigger


class VideoRecording:
    """What the single and vector ``RecordVideo`` share: the video folder, starting a
    recording on an episode or step trigger, capturing while it runs and saving it.

    The wrapper sets the triggers, ``video_format``, ``disable_logger``, ``gc_trigger``,
    ``step_id`` and ``episode_id``, calls :meth:`_init_recording`, and implements
    ``_capture_frame`` (append one frame to ``recorded_frames``).
    """

    episode_trigger: Callable[[int], bool] | None
    step_trigger: Callable[[int], bool] | None
    video_format: str
    disable_logger: bool
    gc_trigger: Callable[[int], bool] | None
    metadata: dict[str, Any]
    step_id: int
    episode_id: int

    def _init_recording(
        self, video_folder: str, fps: int | None, name_prefix: str, video_length: int
    ) -> None:
        self.video_folder = os.path.abspath(video_folder)
        if os.path.isdir(self.video_folder):
            logger.warn(
                f"Overwriting existing videos at {self.video_folder} folder (try specifying a "
                "different `video_folder` for the `RecordVideo` wrapper if this is not desired)"
            )
        os.makedirs(self.video_folder, exist_ok=True)
        self.frames_per_sec: int = fps if fps is not None else self.metadata.get("render_fps", 30)
        self.name_prefix = name_prefix
        self.video_length: float = video_length if video_length != 0 else float("inf")
        self._video_name: str | None = None
        self.recording = False
        self.recorded_frames: list[Any] = []

    def _capture_frame(self) -> None:
        raise NotImplementedError

    def _episode_started(self) -> None:
        """A new episode: an episode recording ends, and the trigger may start the next."""
        self.episode_id += 1
        if self.recording and self.video_length == float("inf"):
            self.stop_recording()
        if self.episode_trigger and self.episode_trigger(self.episode_id):
            self.start_recording(f"{self.name_prefix}-episode-{self.episode_id}")

    def _step_trigger(self) -> None:
        """After step ``step_id``: the step trigger may start a recording."""
        if self.step_trigger and self.step_trigger(self.step_id):
            self.start_recording(f"{self.name_prefix}-step-{self.step_id}")

    def _capture_if_recording(self) -> None:
        if self.recording:
            self._capture_frame()
            if len(self.recorded_frames) > self.video_length:
                self.stop_recording()

    def start_recording(self, video_name: str) -> None:
        """Start recording to ``video_name``; a recording in progress is saved first."""
        if self.recording:
            self.stop_recording()
        self.recording = True
        self._video_name = video_name

    def stop_recording(self) -> None:
        """Save the recorded frames (if any) and stop recording."""
        if not self.recorded_frames:
            logger.warn("Ignored saving a video as there were zero frames to save.")
        else:
            path = os.path.join(self.video_folder, f"{self._video_name}.{self.video_format}")
            video.save_video(self.recorded_frames, path, fps=self.frames_per_sec)
            if not self.disable_logger:
                print(f"Saved {len(self.recorded_frames)} frames to {path}")
        self.recorded_frames = []
        self.recording = False
        self._video_name = None
        if self.gc_trigger and self.gc_trigger(self.episode_id):
            gc.collect()


class RecordVideo(
    VideoRecording, Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs
):
    """Record videos of the episodes chosen by ``episode_trigger`` or the step windows that
    ``step_trigger`` starts.

    With neither trigger, episodes 0, 1, 8, 27, ... 729, 1000, 2000, ... are recorded
    (:func:`~palaestra.utils.video.capped_cubic_video_schedule`). A recording stops at the
    next ``reset`` or, with ``video_length > 0``, after that many frames (possibly spanning
    episodes). ``close()`` saves a recording in progress.
    """

    def __init__(
        self,
        env: Env[ObsType, ActType],
        video_folder: str,
        episode_trigger: Callable[[int], bool] | None = None,
        step_trigger: Callable[[int], bool] | None = None,
        video_length: int = 0,
        name_prefix: str = "rl-video",
        fps: int | None = None,
        disable_logger: bool = True,
        gc_trigger: Callable[[int], bool] | None = lambda episode: True,
        video_format: str | None = None,
    ) -> None:
        RecordConstructorArgs.__init__(
            self,
            video_folder=video_folder,
            episode_trigger=episode_trigger,
            step_trigger=step_trigger,
            video_length=video_length,
            name_prefix=name_prefix,
            fps=fps,
            disable_logger=disable_logger,
            gc_trigger=gc_trigger,
            video_format=video_format,
        )
        Wrapper.__init__(self, env)
        video_format, episode_trigger = check_video_settings(
            env.render_mode, video_format, episode_trigger, step_trigger
        )
        self.episode_trigger = episode_trigger
        self.step_trigger = step_trigger
        self.disable_logger = disable_logger
        self.gc_trigger = gc_trigger
        self.video_format = video_format
        self._init_recording(video_folder, fps, name_prefix, video_length)
        self.render_history: list[RenderFrame] = []
        self.step_id = -1
        self.episode_id = -1

    def _capture_frame(self) -> None:
        frame = self.env.render()
        if isinstance(frame, list):  # rgb_array_list: keep what the user would have seen
            if not frame:
                logger.warn(
                    "Trying to capture render frame but 'env.render()' has just been called. "
                    "The frame cannot be captured."
                )
                return
            self.render_history += frame
            frame = frame[-1]
        if isinstance(frame, np.ndarray):
            self.recorded_frames.append(frame)
        else:
            self.stop_recording()
            logger.warn(
                "Recording stopped: expected type of frame returned by render to be a numpy "
                f"array, got instead {type(frame)}."
            )

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the env; stop an episode recording and maybe start a new one."""
        obs, info = self.env.reset(seed=seed, options=options)
        self._episode_started()
        self._capture_if_recording()
        return obs, info

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the env and record the frame if a recording is on."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.step_id += 1
        self._step_trigger()
        self._capture_if_recording()
        return obs, reward, terminated, truncated, info

    def render(self) -> RenderFrame | list[RenderFrame]:
        """Render the env; with ``*_list`` modes include frames taken while recording."""
        render_out = self.env.render()
        if self.recording and isinstance(render_out, list):
            self.recorded_frames += render_out
        if self.render_history:
            history, self.render_history = self.render_history, []
            return history + list(render_out or [])
        return render_out

    def close(self) -> None:
        """Close the env and save a recording in progress."""
        super().close()
        if self.recording:
            self.stop_recording()

    def stop_recording(self) -> None:
        """Save the recorded frames (if any) and stop recording."""
        assert self.recording, "stop_recording was called, but no recording was started"
        super().stop_recording()

    def __del__(self) -> None:
        # __init__ may have raised before recorded_frames existed
        if getattr(self, "recorded_frames", None):
            logger.warn("Unable to save last video! Did you call close()?")
