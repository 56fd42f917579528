"""``RenderedEnv``: an env that draws its own frames, in every render mode Gymnasium knows.

The classic-control, Box2D, toy-text and Atari envs render alike: a render mode checked at
construction, ``render()`` warning (as Gymnasium does) when there is none, returning the frame
for ``rgb_array`` and showing it in a window, opened on the first
``human`` frame, otherwise. Each family says only how a frame is drawn.
"""

from __future__ import annotations

from typing import Any, TypeVar

import numpy as np

from palaestra import error, logger
from palaestra.core import Env
from palaestra.rendering import window

ObsType = TypeVar("ObsType")
ActType = TypeVar("ActType")


class RenderedEnv(Env[ObsType, ActType]):
    """Render-mode handling and the human window for the single envs that draw themselves.

    Subclasses implement ``_frame()`` (the ``rgb_array`` picture); ``_window_settings()``
    gives the window's title and frame rate.
    """

    _window: Any = None

    def _init_render(self, render_mode: str | None) -> None:
        modes = self.metadata["render_modes"]
        listed = render_mode == "rgb_array_list" and "rgb_array" in modes
        if render_mode is not None and render_mode not in modes and not listed:
            raise error.UnsupportedMode(f"render_mode={render_mode!r} is not one of {modes}")
        if listed and render_mode not in modes:
            # Gymnasium's envs take any mode and leave the list modes to RenderCollection,
            # which make(render_mode="rgb_array_list") adds; its tests build
            # CartPoleEnv(render_mode="rgb_array_list") directly.
            logger.warn(
                "render_mode='rgb_array_list': this env returns one frame per render() call, "
                "as for 'rgb_array'; the list of frames is RenderCollection's job "
                "(make(..., render_mode='rgb_array_list') adds it)"
            )
        self.render_mode = render_mode

    def _frame(self) -> np.ndarray:
        raise NotImplementedError

    def _window_settings(self) -> tuple[str, int]:
        """The human window's title and frames per second (read when it opens)."""
        title = self.spec.id if self.spec is not None else type(self).__name__
        return title, self.metadata["render_fps"]

    def render(self) -> Any:
        """The current frame (``"rgb_array"``) or show it in a window (``"human"``)."""
        if self.render_mode is None:
            name = self.spec.id if self.spec is not None else type(self).__name__
            logger.warn(
                "You are calling render method without specifying any render mode. "
                "You can specify the render_mode at initialization, "
                f'e.g. gym.make("{name}", render_mode="rgb_array")'
            )
            return None
        frame = self._frame()
        if self.render_mode != "human":  # rgb_array, or rgb_array_list on the bare env
            return frame
        if self._window is None:  # created lazily: rgb_array users never need a display
            self._window = window.HumanWindow(*self._window_settings())
        self._window.show(frame)
        return None

    def close(self) -> None:
        """Close the human-mode window if one was opened."""
        if self._window is not None:
            self._window.close()
            self._window = None
