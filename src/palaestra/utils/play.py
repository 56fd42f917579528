"""Gymnasium's ``play``: drive an ``rgb_array`` env from the keyboard in a pygame window, and
``PlayPlot``: live matplotlib plots of values computed from each step.

pygame and matplotlib are imported when a game or a plot starts, never by importing this
module (Gymnasium imports both, and switches matplotlib to TkAgg, at import).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from palaestra.core import Env
from palaestra.error import dependency_not_installed

__all__ = ["MissingKeysToAction", "PlayPlot", "PlayableGame", "display_arr", "play"]


class MissingKeysToAction(Exception):
    """The env has no ``get_keys_to_action`` and no ``keys_to_action`` was given."""


def _pygame() -> Any:
    try:
        import pygame
    except ImportError as exc:
        raise dependency_not_installed("pygame", "play", "palaestra.utils.play") from exc
    return pygame


def _keys_to_action(env: Env[Any, Any], keys_to_action: Any) -> dict[Any, Any]:
    """The mapping given, or the env's own (``get_keys_to_action``), checked."""
    if keys_to_action is None:
        if env.has_wrapper_attr("get_keys_to_action"):
            keys_to_action = env.get_wrapper_attr("get_keys_to_action")()
        elif env.spec is None:
            raise ValueError(
                "The environment must have an `env.spec` to auto-detect missing keys to action "
                "mappings."
            )
        else:
            raise MissingKeysToAction(
                f"{env.spec.id} does not have explicit key to action mapping, please specify "
                "one manually"
            )
    if not isinstance(keys_to_action, dict):
        raise TypeError(f"keys_to_action must be a dictionary, got {type(keys_to_action)}")
    return keys_to_action


def _key_codes(env: Env[Any, Any], keys_to_action: dict[Any, Any]) -> dict[tuple[int, ...], Any]:
    """``{sorted key codes: action}``: characters as their ``ord``, single keys as 1-tuples;
    every action must be in the action space (Gymnasium's checks and messages). ``()`` is the
    action while no key is held (MountainCar's own mapping has it; Gymnasium refuses it)."""
    codes: dict[tuple[int, ...], Any] = {}
    for keys, action in keys_to_action.items():
        combination = keys if isinstance(keys, tuple) else (keys,)
        if not all(isinstance(k, (str, int)) for k in combination):
            raise TypeError(
                f"All keys in key combination tuple must be integers or strings, got {keys!r}"
            )
        if action not in env.action_space:
            raise ValueError(
                f"Action {action} is not a valid action in the environment action space: "
                f"{env.action_space}"
            )
        codes[tuple(sorted(ord(k) if isinstance(k, str) else k for k in combination))] = action
    return codes


class PlayableGame:
    """The pygame window of :func:`play`: which keys matter, which are pressed, its size."""

    def __init__(
        self,
        env: Env[Any, Any],
        keys_to_action: dict[tuple[int, ...], Any] | None = None,
        zoom: float | None = None,
    ) -> None:
        if env.render_mode not in {"rgb_array", "rgb_array_list"}:
            raise ValueError(
                "PlayableGame wrapper works only with rgb_array and rgb_array_list render "
                f"modes, but your environment render_mode = {env.render_mode}."
            )
        if zoom is not None and zoom <= 0:
            raise ValueError(f"Zoom must be a positive float, got {zoom}")
        self.pygame = _pygame()
        self.env = env
        mapping = _keys_to_action(env, keys_to_action)
        self.relevant_keys = {k for keys in mapping for k in keys}
        frame = _frame(env)
        width, height = frame.shape[1], frame.shape[0]
        if zoom is not None:
            width, height = int(width * zoom), int(height * zoom)
        self.original_video_size = self.video_size = (width, height)
        self.screen = self.pygame.display.set_mode(self.video_size, self.pygame.RESIZABLE)
        self.pressed_keys: set[int] = set()
        self.running = True

    def process_event(self, event: Any) -> None:
        """Track the relevant keys; Escape or closing the window stops; a resize rescales."""
        pg = self.pygame
        if event.type == pg.KEYDOWN:
            if event.key in self.relevant_keys:
                self.pressed_keys.add(event.key)
            elif event.key == pg.K_ESCAPE:
                self.running = False
        elif event.type == pg.KEYUP:
            self.pressed_keys.discard(event.key)
        elif event.type == pg.QUIT:
            self.running = False
        elif event.type == pg.WINDOWRESIZED:
            scale = min(
                event.x / self.original_video_size[0], event.y / self.original_video_size[1]
            )
            self.video_size = (
                round(scale * self.original_video_size[0]),
                round(scale * self.original_video_size[1]),
            )


def _frame(env: Env[Any, Any]) -> np.ndarray:
    rendered = env.render()
    if isinstance(rendered, list):
        rendered = rendered[-1]
    if not isinstance(rendered, np.ndarray):
        raise TypeError(f"play needs env.render() to return an image array, got {type(rendered)}")
    return rendered


def display_arr(
    screen: Any, arr: np.ndarray, video_size: tuple[int, int], transpose: bool | None
) -> None:
    """Draw a ``uint8`` frame (HWC when ``transpose``) centred on ``screen``, scaled."""
    if not isinstance(arr, np.ndarray) or arr.dtype != np.uint8:
        raise TypeError(f"display_arr needs a uint8 numpy array, got {arr!r:.60}")
    pygame = _pygame()
    image = pygame.surfarray.make_surface(arr.swapaxes(0, 1) if transpose else arr)
    image = pygame.transform.scale(image, video_size)
    width, height = screen.get_size()
    screen.fill((0, 0, 0))
    screen.blit(image, ((width - video_size[0]) / 2, (height - video_size[1]) / 2))


def play(
    env: Env[Any, Any],
    transpose: bool | None = True,
    fps: int | None = None,
    zoom: float | None = None,
    callback: Callable[..., Any] | None = None,
    keys_to_action: dict[Any, Any] | None = None,
    seed: int | None = None,
    noop: Any = 0,
    wait_on_player: bool = False,
) -> None:
    """Play ``env`` with the keyboard until the window closes or Escape is pressed.

    Each frame steps the env with the action of the keys held (``noop`` for none; with
    ``wait_on_player`` no step until a key is held) and calls
    ``callback(obs_t, obs_tp1, action, reward, terminated, truncated, info)``; an episode
    that ends starts again with ``reset(seed=seed)``. ``fps`` defaults to the env's
    ``render_fps``."""
    env.reset(seed=seed)
    codes = _key_codes(env, _keys_to_action(env, keys_to_action))
    game = PlayableGame(env, codes, zoom)
    pygame = game.pygame
    if fps is None:
        fps = env.metadata.get("render_fps", 30)
        if not isinstance(fps, int):
            raise TypeError(f"Expected env.metadata['render_fps'] to be an integer, got {fps!r}")
    done, obs = True, None
    clock = pygame.time.Clock()
    while game.running:
        if done:
            done = False
            obs, _ = env.reset(seed=seed)  # (Gymnasium keeps the (obs, info) pair here)
        elif not wait_on_player or game.pressed_keys:
            action = codes.get(tuple(sorted(game.pressed_keys)), noop)
            previous = obs
            obs, reward, terminated, truncated, info = env.step(action)
            done = terminated or truncated
            if callback is not None:
                callback(previous, obs, action, reward, terminated, truncated, info)
        if obs is not None:
            display_arr(game.screen, _frame(env), game.video_size, transpose)
        for event in pygame.event.get():
            game.process_event(event)
        pygame.display.flip()
        clock.tick(fps)
    pygame.quit()


class PlayPlot:
    """Live scatter plots of the last ``horizon_timesteps`` values: pass ``plotter.callback``
    to :func:`play`; ``callback`` returns one value per name in ``plot_names``."""

    def __init__(
        self,
        callback: Callable[..., Iterable[float]],
        horizon_timesteps: int,
        plot_names: list[str],
    ) -> None:
        try:
            import matplotlib.pyplot as plt
        except ImportError as exc:
            raise dependency_not_installed("matplotlib", "render", "PlayPlot") from exc
        self._plt = plt
        self.data_callback, self.horizon_timesteps = callback, horizon_timesteps
        self.plot_names = list(plot_names)
        self.fig, ax = plt.subplots(len(self.plot_names))
        self.ax = [ax] if len(self.plot_names) == 1 else list(ax)
        for axis, name in zip(self.ax, self.plot_names, strict=True):
            axis.set_title(name)
        self.t = 0
        self.cur_plot: list[Any] = [None] * len(self.plot_names)
        self.data: list[deque[float]] = [deque(maxlen=horizon_timesteps) for _ in self.plot_names]

    def callback(
        self,
        obs_t: Any,
        obs_tp1: Any,
        action: Any,
        rew: float,
        terminated: bool,
        truncated: bool,
        info: dict[str, Any],
    ) -> None:
        """Add this step's values and redraw."""
        points = self.data_callback(obs_t, obs_tp1, action, rew, terminated, truncated, info)
        for point, series in zip(points, self.data, strict=True):
            series.append(point)
        self.t += 1
        low, high = max(0, self.t - self.horizon_timesteps), self.t
        for i, plot in enumerate(self.cur_plot):
            if plot is not None:
                plot.remove()
            self.cur_plot[i] = self.ax[i].scatter(range(low, high), list(self.data[i]), c="blue")
            self.ax[i].set_xlim(low, high)
        self._plt.pause(0.000001)
