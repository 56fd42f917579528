"""The ``render_mode="human"`` window: pygame when installed, else matplotlib, else a notebook.

Backends, chosen once per window (or forced with ``backend=``):

- ``"notebook"`` inside a Jupyter kernel: an inline image updated in place
  (:class:`palaestra.rendering.notebook.LiveView`); a desktop window would steal focus and,
  on macOS, freeze the kernel.
- ``"pygame"`` when pygame imports. Events are pumped on every ``show`` so the OS never marks
  the window as hung. pygame has one display per process, so live windows share it (the last
  shown frame is on screen) and ``close()`` shuts the display only when no other
  ``HumanWindow`` is still open — closing one env never breaks another.
- ``"matplotlib"`` otherwise: a figure updated with ``draw_idle`` + ``flush_events``, never
  ``plt.pause`` (which blocks, and raises the window over the user's work on every frame).

Frames are paced to ``fps`` with ``time.sleep``, which releases the GIL; a caller slower than
``fps`` is never delayed.
"""

from __future__ import annotations

import os
import time
from typing import Any

import numpy as np

from palaestra import logger
from palaestra.error import DependencyNotInstalled, dependency_not_installed
from palaestra.rendering.notebook import LiveView, in_notebook

__all__ = ["BACKENDS", "HumanWindow", "choose_backend"]

BACKENDS = ("notebook", "pygame", "matplotlib")


def _importable(name: str) -> bool:
    try:
        __import__(name)
    except ImportError:
        return False
    return True


def choose_backend() -> str:
    """The backend a new window gets here; ``DependencyNotInstalled`` if there is none."""
    if in_notebook():
        return "notebook"
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    if _importable("pygame"):
        return "pygame"
    if _importable("matplotlib"):
        return "matplotlib"
    raise DependencyNotInstalled(
        str(dependency_not_installed("matplotlib", "render", 'render_mode="human"'))
        + "; pygame works as well"
    )


class _PygameDisplay:
    """The process-wide pygame display, shared by every live pygame window."""

    owners: set[int] = set()  # ids of open windows using the display
    size: tuple[int, int] | None = None
    caption: str | None = None

    @classmethod
    def show(cls, owner: int, title: str, frame: np.ndarray) -> None:
        import pygame

        cls.owners.add(owner)
        if not pygame.display.get_init():
            pygame.display.init()
            cls.size = cls.caption = None
        h, w = frame.shape[:2]
        if cls.size != (w, h) or pygame.display.get_surface() is None:
            pygame.display.set_mode((w, h))
            cls.size = (w, h)
        if cls.caption != title:
            pygame.display.set_caption(title)
            cls.caption = title
        pygame.surfarray.blit_array(pygame.display.get_surface(), frame[:, :, :3].swapaxes(0, 1))
        pygame.display.flip()
        pygame.event.pump()  # keeps the window responsive; the OS flags unpumped windows hung

    @classmethod
    def release(cls, owner: int) -> None:
        if owner not in cls.owners:
            return
        cls.owners.discard(owner)
        if not cls.owners:
            import pygame

            pygame.display.quit()  # not pygame.quit(): other pygame users may still need it
            cls.size = cls.caption = None


_warned_headless = False


def _warn_if_headless(backend: str) -> None:
    """Say once why no window appears when matplotlib can only draw to files."""
    global _warned_headless
    try:
        from matplotlib.backends import BackendFilter, backend_registry

        headless = set(backend_registry.list_builtin(BackendFilter.NON_INTERACTIVE))
    except ImportError:  # matplotlib < 3.9
        headless = {"agg", "cairo", "pdf", "pgf", "ps", "svg", "template"}
    if backend.lower() in headless and not _warned_headless:
        _warned_headless = True
        logger.warn(
            f"matplotlib's backend is {backend!r}, which opens no window, so "
            "render_mode='human' shows nothing; install pygame or choose an interactive "
            "backend (e.g. MPLBACKEND=TkAgg)"
        )


class _MatplotlibFigure:
    """A figure of its own per window; closing it leaves other figures alone."""

    def __init__(self, title: str) -> None:
        import matplotlib
        import matplotlib.pyplot as plt

        _warn_if_headless(matplotlib.get_backend())
        self._plt = plt
        self._title = title
        self._fig: Any = None
        self._image: Any = None

    def show(self, frame: np.ndarray) -> None:
        if self._fig is None or not self._plt.fignum_exists(self._fig.number):
            h, w = frame.shape[:2]
            self._fig = self._plt.figure(figsize=(w / 100, h / 100), dpi=100)
            manager = self._fig.canvas.manager
            if manager is not None:
                manager.set_window_title(self._title)
            ax = self._fig.add_axes((0, 0, 1, 1))
            ax.set_axis_off()
            self._image = ax.imshow(frame, interpolation="nearest")
            self._plt.show(block=False)
        else:
            self._image.set_data(frame)
        self._fig.canvas.draw_idle()
        self._fig.canvas.flush_events()  # runs the GUI event loop once, without sleeping

    def close(self) -> None:
        if self._fig is not None:
            self._plt.close(self._fig)
            self._fig = None


class HumanWindow:
    """A window showing ``(H, W, 3) uint8`` frames at up to ``fps`` frames per second.

    >>> win = HumanWindow("CartPole-v1", fps=50, backend="matplotlib")
    >>> win.show(np.zeros((40, 60, 3), np.uint8)); win.close(); win.close()
    """

    def __init__(self, title: str, fps: int, *, backend: str | None = None) -> None:
        if backend is not None and backend not in BACKENDS:
            raise ValueError(f"unknown backend {backend!r}, expected one of {BACKENDS}")
        self.title = title
        self.fps = fps
        self.backend = backend or choose_backend()
        self._closed = False
        self._next_time: float | None = None
        self._impl: Any = None
        if self.backend == "matplotlib":
            self._impl = _MatplotlibFigure(title)
        elif self.backend == "notebook":
            self._impl = LiveView()

    def show(self, frame: np.ndarray) -> None:
        """Display ``frame``, then wait (GIL released) until the next frame is due."""
        frame = np.asarray(frame)
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] not in (3, 4):
            raise ValueError(f"expected an (H, W, 3) uint8 frame, got {frame.shape} {frame.dtype}")
        self._closed = False  # showing again after close() reopens, as Gymnasium's envs do
        if self.backend == "pygame":
            _PygameDisplay.show(id(self), self.title, frame)
        elif self.backend == "notebook":
            self._impl.update(frame)
        else:
            self._impl.show(frame)
        self._pace()

    def _pace(self) -> None:
        if not self.fps or self.fps <= 0:
            return
        now = time.perf_counter()
        if self._next_time is not None and self._next_time > now:
            time.sleep(self._next_time - now)
            now = self._next_time
        self._next_time = now + 1.0 / self.fps

    def close(self) -> None:
        """Close this window only; calling it twice is harmless."""
        if self._closed:
            return
        self._closed = True
        self._next_time = None
        if self.backend == "pygame":
            _PygameDisplay.release(id(self))
        elif self._impl is not None:
            self._impl.close()

    def __del__(self) -> None:
        # A forgotten window must not keep the shared pygame display alive forever.
        try:
            self.close()
        except Exception:
            pass
