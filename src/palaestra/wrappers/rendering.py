"""Render-mode wrappers used by ``make()``: ``RenderCollection`` and ``HumanRendering``.

``make(id, render_mode="rgb_array_list")`` wraps an ``rgb_array`` env in
:class:`RenderCollection`; ``make(id, render_mode="human")`` on an env that only draws
``rgb_array`` wraps it in :class:`HumanRendering`, which shows frames in a
:class:`palaestra.rendering.window.HumanWindow` (pygame, matplotlib or a notebook) instead of
Gymnasium's pygame-only window.
"""

from __future__ import annotations

from copy import deepcopy
from typing import Any, SupportsFloat

import numpy as np

from palaestra.core import ActType, Env, ObsType, RenderFrame, Wrapper
from palaestra.rendering.window import HumanWindow
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.render_noise import AddWhiteNoise, ObstructView

# AddWhiteNoise and ObstructView are at Gymnasium's path (gymnasium.wrappers.rendering) too
__all__ = ["AddWhiteNoise", "HumanRendering", "ObstructView", "RenderCollection"]


class RenderCollection(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Collect a frame after every ``reset`` and ``step``; ``render()`` returns the list.

    With ``pop_frames`` the list is emptied by each ``render()``; with ``reset_clean`` it is
    emptied by each ``reset()`` (Gymnasium 1.x semantics).
    """

    def __init__(
        self, env: Env[ObsType, ActType], pop_frames: bool = True, reset_clean: bool = True
    ) -> None:
        RecordConstructorArgs.__init__(self, pop_frames=pop_frames, reset_clean=reset_clean)
        Wrapper.__init__(self, env)
        if env.render_mode is None:
            raise ValueError("Expected env.render_mode to be not None")
        if env.render_mode.endswith("_list"):
            raise ValueError(
                f"Expected env.render_mode to not end with '_list', got '{env.render_mode}'"
            )
        self.frame_list: list[RenderFrame] = []
        self.pop_frames = pop_frames
        self.reset_clean = reset_clean
        self.metadata = deepcopy(self.env.metadata)
        modes = self.metadata.setdefault("render_modes", [])
        if f"{env.render_mode}_list" not in modes:
            modes.append(f"{env.render_mode}_list")

    @property
    def render_mode(self) -> str:  # type: ignore[override]
        """The inner render mode with ``_list`` appended."""
        return f"{self.env.render_mode}_list"

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner env and collect a frame."""
        output = self.env.step(action)
        self.frame_list.append(self.env.render())
        return output

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env, clear the frames if ``reset_clean``, and collect a frame."""
        output = self.env.reset(seed=seed, options=options)
        if self.reset_clean:
            self.frame_list = []
        self.frame_list.append(self.env.render())
        return output

    def render(self) -> list[RenderFrame]:
        """The collected frames (and, with ``pop_frames``, a fresh empty list afterwards)."""
        frames = self.frame_list
        if self.pop_frames:
            self.frame_list = []
        return frames


def check_human_rendering(wrapper: Any) -> None:
    """What both ``HumanRendering`` wrappers (single and vector) check of the env they wrap:
    a render mode in ``wrapper.ACCEPTED_RENDER_MODES`` and a ``render_fps`` to pace the
    window; ``"human"`` is then added to the wrapper's render modes."""
    env = wrapper.env
    if env.render_mode not in wrapper.ACCEPTED_RENDER_MODES:
        raise ValueError(
            f"Expected env.render_mode to be one of {list(wrapper.ACCEPTED_RENDER_MODES)} "
            f"but got '{env.render_mode}'"
        )
    if "render_fps" not in env.metadata:
        raise ValueError(
            "The base environment must specify 'render_fps' to be used with the "
            "HumanRendering wrapper"
        )
    if "human" not in wrapper.metadata.get("render_modes", []):
        wrapper.metadata = deepcopy(env.metadata)
        wrapper.metadata.setdefault("render_modes", []).append("human")


class HumanRendering(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Show an ``rgb_array`` env in a window after every ``reset`` and ``step``.

    The window never blocks the caller beyond pacing to ``metadata["render_fps"]``, and
    ``close()`` closes only this env's window (see :mod:`palaestra.rendering.window`).
    """

    ACCEPTED_RENDER_MODES = ("rgb_array", "rgb_array_list", "depth_array", "depth_array_list")

    def __init__(self, env: Env[ObsType, ActType], backend: str | None = None) -> None:
        # recorded, so that env.spec rebuilds the stack with the same window backend
        RecordConstructorArgs.__init__(self, backend=backend)
        Wrapper.__init__(self, env)
        self.window: Any = None  # set first: close() may run on a half-built wrapper
        self.screen_size: tuple[int, int] | None = None
        self._backend = backend
        check_human_rendering(self)

    @property
    def render_mode(self) -> str:  # type: ignore[override]
        """Always ``"human"``."""
        return "human"

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner env and show the new frame."""
        result = self.env.step(action)
        self._render_frame()
        return result

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env and show the first frame."""
        result = self.env.reset(seed=seed, options=options)
        self._render_frame()
        return result

    def render(self) -> None:
        """Nothing to return: frames are shown by ``step`` and ``reset``."""
        return None

    def _render_frame(self) -> None:
        frame = self.env.render()
        if isinstance(frame, list):
            if not frame:
                return  # the list was just popped by someone else's render() call
            frame = frame[-1]
        if not isinstance(frame, np.ndarray):
            raise TypeError(f"Expected env.render() to return a numpy array, got {type(frame)}")
        if frame.ndim == 2:  # depth_array: show it as grey
            frame = np.repeat(_to_uint8(frame)[:, :, None], 3, axis=2)
        size = (frame.shape[0], frame.shape[1])
        if self.screen_size is None:
            self.screen_size = size
        if size != self.screen_size:
            raise ValueError(f"The frame size changed from {self.screen_size} to {size}")
        if self.window is None:
            spec = self.env.spec
            title = spec.id if spec is not None else type(self.env.unwrapped).__name__
            fps = int(self.env.metadata["render_fps"])
            self.window = HumanWindow(title, fps, backend=self._backend)
        self.window.show(frame)

    def close(self) -> None:
        """Close this env's window, then the inner env."""
        if self.window is not None:
            self.window.close()
            self.window = None
        super().close()


def _to_uint8(depth: np.ndarray) -> np.ndarray:
    """Scale a depth map to 0-255 for display."""
    depth = np.asarray(depth, dtype=np.float64)
    lo, hi = float(np.nanmin(depth)), float(np.nanmax(depth))
    scaled = (depth - lo) / (hi - lo) if hi > lo else np.zeros_like(depth)
    return (np.nan_to_num(scaled) * 255).astype(np.uint8)
