"""Notebook helpers against a fake ``IPython.display`` (IPython may not be installed)."""

from __future__ import annotations

import base64
import io
import sys
import types

import numpy as np
import pytest

from palaestra.error import DependencyNotInstalled
from palaestra.rendering import notebook, scenes
from palaestra.rendering.window import HumanWindow

Image = pytest.importorskip("PIL.Image")


class FakeHandle:
    def __init__(self, log):
        self.log = log

    def update(self, obj):
        self.log.append(("update", obj))


@pytest.fixture
def fake_ipython(monkeypatch):
    """Install a fake IPython.display that records what would be shown."""
    log: list = []
    display_mod = types.ModuleType("IPython.display")
    display_mod.Image = lambda data, format: ("Image", format, data)
    display_mod.HTML = lambda html: ("HTML", html)

    def display(obj, display_id=None):
        log.append(("display", obj, display_id))
        return FakeHandle(log) if display_id else None

    display_mod.display = display
    ipython = types.ModuleType("IPython")
    ipython.display = display_mod
    ipython.get_ipython = lambda: None
    monkeypatch.setitem(sys.modules, "IPython", ipython)
    monkeypatch.setitem(sys.modules, "IPython.display", display_mod)
    return log


def _decode_png(data: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))


class FakeEnv:
    def __init__(self, frame):
        self.frame = frame

    def render(self):
        return self.frame


def test_show_env_list_and_array(fake_ipython):
    frame = scenes.render_cartpole((0, 0, 0.1, 0))
    notebook.show(FakeEnv(frame))
    notebook.show([np.zeros_like(frame), frame])
    notebook.show(frame)
    assert len(fake_ipython) == 3
    for _, (kind, fmt, data), _ in fake_ipython:
        assert (kind, fmt) == ("Image", "png")
        np.testing.assert_array_equal(_decode_png(data), frame)


def test_live_view_updates_one_output_in_place(fake_ipython):
    view = notebook.LiveView()
    frames = [scenes.render_mountain_car(p, 0.5) for p in (-0.5, -0.4, -0.3)]
    for f in frames:
        view.update(f)
    kinds = [entry[0] for entry in fake_ipython]
    assert kinds == ["display", "update", "update"]  # displayed once, never cleared
    assert fake_ipython[0][2] is True  # display_id=True
    np.testing.assert_array_equal(_decode_png(fake_ipython[-1][1][2]), frames[-1])


def test_play_returns_an_inline_gif(fake_ipython):
    frames = [scenes.render_pendulum(t, 1.0) for t in (0.0, 0.5, 1.0)]
    kind, html = notebook.play(frames, fps=10)
    assert kind == "HTML" and html.startswith('<img src="data:image/gif;base64,')
    gif = Image.open(io.BytesIO(base64.b64decode(html.split(",", 1)[1].split('"')[0])))
    assert gif.n_frames == 3 and gif.size == (500, 500)


def test_human_window_uses_the_notebook_inside_jupyter(fake_ipython, monkeypatch):
    shell = type("ZMQInteractiveShell", (), {})()
    monkeypatch.setattr(sys.modules["IPython"], "get_ipython", lambda: shell)
    assert notebook.in_notebook()
    win = HumanWindow("CartPole-v1", fps=0)
    assert win.backend == "notebook"
    win.show(scenes.render_cartpole((0, 0, 0, 0)))
    win.show(scenes.render_cartpole((0.1, 0, 0, 0)))
    assert [e[0] for e in fake_ipython] == ["display", "update"]
    win.close()


def test_helpful_errors(monkeypatch):
    monkeypatch.setitem(sys.modules, "IPython", None)
    monkeypatch.setitem(sys.modules, "IPython.display", None)
    assert not notebook.in_notebook()
    with pytest.raises(DependencyNotInstalled, match="pip install ipython"):
        notebook.show(np.zeros((2, 2, 3), np.uint8))
    with pytest.raises(ValueError, match="render_mode='rgb_array'"):
        notebook.to_frame(FakeEnv(None))
    with pytest.raises(ValueError, match="empty"):
        notebook.to_frame([])
