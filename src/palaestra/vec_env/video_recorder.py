"""``VecVideoRecorder``: record the tiled frames of a ``VecEnv`` to MP4 (SB3's wrapper).

A recording starts when ``record_video_trigger(step)`` is true (at a reset or after a step) and
keeps ``video_length`` steps; the file is ``{name_prefix}-step-{a}-to-step-{b}.mp4``, written
through :func:`palaestra.utils.video.save_video` (imageio-ffmpeg, the ``video`` extra; SB3 needs
moviepy). ``video_suffix=".gif"`` writes a GIF with Pillow instead.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import numpy as np

from palaestra import logger
from palaestra.utils.video import save_video
from palaestra.vec_env.base import StepReturn, VecEnv, VecEnvWrapper


class VecVideoRecorder(VecEnvWrapper):
    """Record ``venv.render()`` frames (the envs need ``render_mode="rgb_array"``)."""

    def __init__(
        self,
        venv: VecEnv,
        video_folder: str,
        record_video_trigger: Callable[[int], bool],
        video_length: int = 200,
        name_prefix: str = "rl-video",
        video_suffix: str = ".mp4",
    ) -> None:
        super().__init__(venv)
        if venv.render_mode != "rgb_array":
            raise ValueError(f"The render_mode must be 'rgb_array', not {venv.render_mode}")
        fps = venv.get_attr("metadata", indices=0)[0].get("render_fps", 30)
        self.frames_per_sec = fps if fps else 30
        self.record_video_trigger = record_video_trigger
        self.video_folder = os.path.abspath(video_folder)
        os.makedirs(self.video_folder, exist_ok=True)
        self.name_prefix, self.video_length, self.video_suffix = (
            name_prefix,
            video_length,
            video_suffix,
        )
        self.step_id = 0
        self.recording = False
        self.recorded_frames: list[np.ndarray] = []
        self.video_name, self.video_path = "", ""

    def reset(self) -> Any:
        """Reset; start recording if the trigger says so."""
        obs = self.venv.reset()
        if self.record_video_trigger(self.step_id):
            self._start_video_recorder()
        return obs

    def step_wait(self) -> StepReturn:
        """Step; capture a frame while recording, save once ``video_length`` is exceeded."""
        obs, rewards, dones, infos = self.venv.step_wait()
        self.step_id += 1
        if self.recording:
            self._capture_frame()
            if len(self.recorded_frames) > self.video_length:
                print(f"Saving video to {self.video_path}")
                self._stop_recording()
        elif self.record_video_trigger(self.step_id):
            self._start_video_recorder()
        return obs, rewards, dones, infos

    def _start_video_recorder(self) -> None:
        if self.recording:
            self._stop_recording()
        end = self.step_id + self.video_length
        self.video_name = f"{self.name_prefix}-step-{self.step_id}-to-step-{end}{self.video_suffix}"
        self.video_path = os.path.join(self.video_folder, self.video_name)
        self.recording = True
        self._capture_frame()

    def _capture_frame(self) -> None:
        frame = self.venv.render()
        if isinstance(frame, np.ndarray):
            self.recorded_frames.append(frame)
        else:
            self._stop_recording()
            logger.warn(
                "Recording stopped: expected type of frame returned by render to be a numpy "
                f"array, got instead {type(frame)}."
            )

    def _stop_recording(self) -> None:
        if self.recorded_frames:
            save_video(self.recorded_frames, self.video_path, fps=self.frames_per_sec)
        else:
            logger.warn("Ignored saving a video as there were zero frames to save.")
        self.recorded_frames = []
        self.recording = False

    def close(self) -> None:
        """Close the envs, then save a recording in progress."""
        super().close()
        if self.recording:
            self._stop_recording()
