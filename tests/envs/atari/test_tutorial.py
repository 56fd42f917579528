"""The tutorial's Breakout block, with only its import line changed.

Two changes to run it in a test, neither in the block's palaestra code: ``from IPython import
display`` gets a no-op stub when IPython is not installed (this venv has none), and the default
suite plays 40 of the block's 1000 random steps (the ``slow`` run plays all 1000).
"""

from __future__ import annotations

import types

import pytest
from tests.tutorial.test_env_blocks import run_block

pytest.importorskip("ale_py")
pytest.importorskip("matplotlib")

BREAKOUT_BLOCK = """
import gymnasium as gym
import matplotlib.pyplot as plt
from IPython import display
import time
env = gym.make("ALE/Breakout-v5", render_mode='rgb_array')
print("Observation Space:", env.observation_space)
print("Action Space:", env.action_space)
obs, info = env.reset()
plt.figure(figsize=(6, 8))
for i in range(1000):
    action = env.action_space.sample()
    obs, reward, terminated, truncated, info = env.step(action)
    frame = env.render()
    plt.clf()
    plt.imshow(frame)
    plt.axis('off')
    display.clear_output(wait=True)
    display.display(plt.gcf())
    time.sleep(0.01)
    if terminated or truncated:
        obs, info = env.reset()
plt.close()
"""

TUTORIAL_OUTPUT = [
    "Observation Space: Box(0, 255, (210, 160, 3), uint8)",
    "Action Space: Discrete(4)",
]


@pytest.fixture
def ipython_display(monkeypatch: pytest.MonkeyPatch) -> None:
    """A no-op ``IPython.display`` where IPython is missing (in Jupyter it is the real one)."""
    try:
        import IPython  # noqa: F401
    except ImportError:
        ipy = types.ModuleType("IPython")
        ipy.get_ipython, ipy.version_info = (lambda: None), (9, 0, 0)  # type: ignore[attr-defined]
        ipy.display = types.SimpleNamespace(  # type: ignore[attr-defined]
            clear_output=lambda wait=False: None, display=lambda *a, **k: None
        )
        monkeypatch.setitem(__import__("sys").modules, "IPython", ipy)


def run_breakout(steps: int) -> tuple[str, dict]:
    return run_block(BREAKOUT_BLOCK.replace("range(1000)", f"range({steps})"), "palaestra")


@pytest.mark.usefixtures("ipython_display")
def test_breakout_block_prints_the_tutorials_spaces() -> None:
    out, ns = run_breakout(40)
    assert out.splitlines() == TUTORIAL_OUTPUT
    assert type(ns["env"].unwrapped).__module__ == "palaestra.envs.atari.env"
    frame = ns["frame"]
    assert frame.shape == (210, 160, 3) and frame.dtype.name == "uint8"


@pytest.mark.slow
@pytest.mark.usefixtures("ipython_display")
def test_breakout_block_runs_its_1000_steps() -> None:
    out, ns = run_breakout(1000)
    assert out.splitlines() == TUTORIAL_OUTPUT
    assert ns["i"] == 999
