"""RenderCollection and HumanRendering (Gymnasium 1.x semantics, palaestra's window)."""

from __future__ import annotations

import numpy as np
import pytest

from palaestra.core import Env
from palaestra.wrappers.rendering import HumanRendering, RenderCollection

pytestmark = pytest.mark.filterwarnings("ignore:.*opens no window")  # headless matplotlib


class Painter(Env):
    """Each frame's value is the number of steps taken since the last reset."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 1000}

    def __init__(self, render_mode="rgb_array"):
        from palaestra.spaces import Discrete

        self.render_mode = render_mode
        self.action_space = self.observation_space = Discrete(2)
        self.t = 0
        self.closed = False

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return 0, {}

    def step(self, action):
        self.t += 1
        return 0, 0.0, False, False, {}

    def render(self):
        return np.full((8, 12, 3), self.t, np.uint8)

    def close(self):
        self.closed = True


def values(frames):
    return [int(f[0, 0, 0]) for f in frames]


def test_render_collection_pops_and_cleans():
    env = RenderCollection(Painter())
    assert env.render_mode == "rgb_array_list"
    assert "rgb_array_list" in env.metadata["render_modes"]
    assert "rgb_array_list" not in Painter.metadata["render_modes"]  # copied, not mutated
    env.reset()
    env.step(0)
    env.step(0)
    assert values(env.render()) == [0, 1, 2]
    assert env.render() == []
    env.step(0)
    env.reset()
    assert values(env.render()) == [0]


def test_render_collection_keep_frames():
    env = RenderCollection(Painter(), pop_frames=False, reset_clean=False)
    env.reset()
    env.step(0)
    env.reset()
    assert values(env.render()) == [0, 1, 0]
    assert values(env.render()) == [0, 1, 0]


@pytest.mark.parametrize(("mode", "match"), [(None, "not None"), ("rgb_array_list", "_list")])
def test_render_collection_rejects(mode, match):
    with pytest.raises(ValueError, match=match):
        RenderCollection(Painter(render_mode=mode))


def test_human_rendering_shows_every_frame_and_closes_its_window():
    plt = pytest.importorskip("matplotlib.pyplot")
    env = HumanRendering(Painter(), backend="matplotlib")
    assert env.render_mode == "human" and "human" in env.metadata["render_modes"]
    env.reset()
    env.step(0)
    assert env.render() is None
    image = env.window._impl._image
    assert int(np.asarray(image.get_array())[0, 0, 0]) == 1
    fig = env.window._impl._fig
    env.close()
    assert not plt.fignum_exists(fig.number) and env.window is None
    assert env.unwrapped.closed


def test_human_rendering_over_a_frame_list():
    pytest.importorskip("matplotlib")
    env = HumanRendering(RenderCollection(Painter()), backend="matplotlib")
    env.reset()
    env.step(0)
    env.step(0)
    assert int(np.asarray(env.window._impl._image.get_array())[0, 0, 0]) == 2
    env.close()


def test_human_rendering_rejects():
    with pytest.raises(ValueError, match="render_mode to be one of"):
        HumanRendering(Painter(render_mode=None))
    painter = Painter()
    painter.metadata = {"render_modes": ["rgb_array"]}
    with pytest.raises(ValueError, match="render_fps"):
        HumanRendering(painter)


def test_closing_one_human_env_keeps_another_alive(monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    pygame = pytest.importorskip("pygame")
    a, b = HumanRendering(Painter(), "pygame"), HumanRendering(Painter(), "pygame")
    a.reset()
    b.reset()
    a.close()
    b.step(0)  # would raise "video system not initialized" if a had quit pygame
    assert pygame.display.get_init()
    b.close()
    assert not pygame.display.get_init()
