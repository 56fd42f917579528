"""HumanWindow with pygame's dummy video driver, matplotlib's Agg backend and no backend."""

from __future__ import annotations

import sys
import time

import numpy as np
import pytest

from palaestra.error import DependencyNotInstalled
from palaestra.rendering import scenes, window
from palaestra.rendering.window import HumanWindow, _PygameDisplay, choose_backend

# matplotlib runs headless (Agg) here; the warning about it has its own test below.
pytestmark = pytest.mark.filterwarnings("ignore:.*opens no window")


@pytest.fixture
def pygame_dummy(monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    pygame = pytest.importorskip("pygame")
    yield pygame
    _PygameDisplay.owners.clear()
    pygame.display.quit()


def _screen(pygame) -> np.ndarray:
    return pygame.surfarray.array3d(pygame.display.get_surface()).swapaxes(0, 1)


def test_pygame_shows_the_frame(pygame_dummy):
    win = HumanWindow("CartPole-v1", fps=0, backend="pygame")
    frame = scenes.render_cartpole((0.5, 0, 0.3, 0))
    win.show(frame)
    assert pygame_dummy.display.get_caption()[0] == "CartPole-v1"
    np.testing.assert_array_equal(_screen(pygame_dummy), frame)
    win.close()
    assert not pygame_dummy.display.get_init()
    win.close()  # twice is fine


def test_pygame_closing_one_window_keeps_the_other_alive(pygame_dummy):
    a = HumanWindow("a", fps=0, backend="pygame")
    b = HumanWindow("b", fps=0, backend="pygame")
    a.show(scenes.render_cartpole((0, 0, 0, 0)))
    b.show(scenes.render_pendulum(0.3, 1.0))  # another size: the display is resized
    a.close()
    assert pygame_dummy.display.get_init()
    frame = scenes.render_pendulum(1.0, -1.0)
    b.show(frame)
    np.testing.assert_array_equal(_screen(pygame_dummy), frame)
    b.close()
    assert not pygame_dummy.display.get_init()


def test_pygame_window_reopens_after_close(pygame_dummy):
    win = HumanWindow("x", fps=0, backend="pygame")
    frame = scenes.render_acrobot(0.2, 0.1)
    win.show(frame)
    win.close()
    win.show(frame)
    np.testing.assert_array_equal(_screen(pygame_dummy), frame)
    win.close()


def test_matplotlib_agg_updates_in_place_and_closes_only_its_figure():
    plt = pytest.importorskip("matplotlib.pyplot")
    other = plt.figure()
    win = HumanWindow("MountainCar-v0", fps=0, backend="matplotlib")
    first = scenes.render_mountain_car(-0.5, 0.5)
    win.show(first)
    fig = win._impl._fig
    second = scenes.render_mountain_car(0.1, 0.5)
    win.show(second)
    assert win._impl._fig is fig  # same figure, new data
    np.testing.assert_array_equal(np.asarray(win._impl._image.get_array()), second)
    win.close()
    assert not plt.fignum_exists(fig.number)
    assert plt.fignum_exists(other.number)
    plt.close(other)


def test_fps_paces_frames_without_delaying_slow_callers():
    win = HumanWindow("x", fps=50, backend="matplotlib")
    frame = np.zeros((20, 30, 3), np.uint8)
    start = time.perf_counter()
    for _ in range(6):
        win.show(frame)
    assert time.perf_counter() - start >= 5 / 50 * 0.9
    win.close()


def test_bad_frames_and_backends():
    with pytest.raises(ValueError, match="backend"):
        HumanWindow("x", fps=30, backend="tk")
    win = HumanWindow("x", fps=30, backend="matplotlib")
    with pytest.raises(ValueError, match=r"\(H, W, 3\) uint8"):
        win.show(np.zeros((4, 4), np.float64))
    win.close()


def test_backend_choice(monkeypatch):
    monkeypatch.setitem(sys.modules, "pygame", None)
    assert choose_backend() == "matplotlib"
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(DependencyNotInstalled, match=r'pip install "palaestra\[render\]"'):
        HumanWindow("x", fps=30)


def test_closing_one_human_env_never_breaks_another(pygame_dummy):
    """Gymnasium's close() calls pygame.quit(), killing every other env's window."""
    palaestra = pytest.importorskip("palaestra")
    if not hasattr(palaestra, "make"):
        pytest.skip("palaestra.make not available yet")
    a = palaestra.make("CartPole-v1", render_mode="human")
    b = palaestra.make("Pendulum-v1", render_mode="human")
    a.unwrapped.metadata = {**a.unwrapped.metadata, "render_fps": 0}  # no pacing in tests
    b.unwrapped.metadata = {**b.unwrapped.metadata, "render_fps": 0}
    a.reset(seed=0)
    b.reset(seed=0)
    a.step(a.action_space.sample())
    a.close()
    for _ in range(3):
        b.step(b.action_space.sample())  # raised "video system not initialized" in Gymnasium
    assert pygame_dummy.display.get_init()
    assert pygame_dummy.display.get_surface().get_size() == (500, 500)
    b.close()
    assert not pygame_dummy.display.get_init()


@pytest.mark.filterwarnings("default")
def test_headless_matplotlib_says_why_no_window_appears(monkeypatch):
    pytest.importorskip("matplotlib")
    monkeypatch.setattr(window, "_warned_headless", False)
    with pytest.warns(UserWarning, match="which opens no window"):
        win = HumanWindow("x", fps=0, backend="matplotlib")
    win.close()
