"""The tutorial's rendering blocks run on palaestra with pygame unavailable.

The blocks run in one fresh interpreter (each in its own namespace) where
``sys.modules["pygame"] = None`` (any ``import pygame`` raises ImportError), with
``import gymnasium as gym`` replaced by ``import palaestra as gym``; the run fails if
anything imported pygame. Changes to the tutorial's text, and why:

- loops that draw with matplotlib are shortened (100 -> 30, 1500 -> 20, 200 -> 20 steps) to
  keep the suite fast;
- ``from IPython import display`` gets a no-op stub when IPython is not installed
  (the venv has none; in Jupyter it is the real module);
- the GIF block's trained ``DQN.load("dqn_mountaincar")`` policy is replaced by random
  actions (the agent is not under test here, the frames and the GIF are).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

PRELUDE = """
import sys, types
sys.modules["pygame"] = None  # no pygame: `import pygame` raises ImportError
import matplotlib
matplotlib.use("Agg")
try:
    from IPython import display
except ImportError:
    ipy = types.ModuleType("IPython")
    # matplotlib asks whether it runs in IPython, and which version
    ipy.get_ipython, ipy.version_info = (lambda: None), (9, 0, 0)
    ipy.display = types.SimpleNamespace(
        clear_output=lambda wait=False: None, display=lambda *a, **k: None
    )
    sys.modules["IPython"] = ipy
"""

RENDER_BLOCK = """
import palaestra as gym
import matplotlib.pyplot as plt
from IPython import display
env = gym.make('MountainCar-v0', render_mode='rgb_array')
obs, info = env.reset()
plt.figure(figsize=(6, 4))
for _ in range(30):
    action = env.action_space.sample()
    obs, reward, terminated, truncated, info = env.step(action)
    frame = env.render()
    plt.clf()
    plt.imshow(frame)
    plt.axis('off')
    display.clear_output(wait=True)
    display.display(plt.gcf())
env.close()
plt.close()
assert frame.shape == (400, 600, 3) and frame.dtype.name == "uint8"
"""

ANIMATION_BLOCK = """
import palaestra as gym
import matplotlib.pyplot as plt
import matplotlib.animation as animation
import numpy as np
env = gym.make('MountainCar-v0', render_mode='rgb_array')
obs, info = env.reset()
frames = []
for _ in range(200):
    action = env.action_space.sample()
    obs, reward, terminated, truncated, info = env.step(action)
    frames.append(env.render())
    if terminated or truncated:
        obs, info = env.reset()
env.close()
# Create animation
fig, ax = plt.subplots(figsize=(6, 4))
ax.axis('off')
img = ax.imshow(frames[0])
def update(frame_idx):
    img.set_data(frames[frame_idx])
    return [img]
ani = animation.FuncAnimation(fig, update, frames=len(frames), interval=50, blit=True)
plt.show()
assert len(frames) == 200
"""

EPISODE_BLOCK = """
import palaestra as gym
import matplotlib.pyplot as plt
from IPython import display
import time
env = gym.make('MountainCar-v0', render_mode='rgb_array')
num_steps = 20
obs, info = env.reset()
plt.figure(figsize=(6, 4))
for step in range(num_steps):
    # Take random action
    action = env.action_space.sample()
    # Apply the action
    obs, reward, terminated, truncated, info = env.step(action)
    # Render the environment
    frame = env.render()
    plt.clf()
    plt.imshow(frame)
    plt.axis('off')
    display.clear_output(wait=True)
    display.display(plt.gcf())
    time.sleep(0.001)
    # If the episode is done, start another one
    if terminated or truncated:
        obs, info = env.reset()
plt.close()
"""

GIF_BLOCK = """
import palaestra as gym
import matplotlib.pyplot as plt
import matplotlib.animation as animation
from pathlib import Path
import os
# Create assets directory if it doesn't exist
Path("./assets").mkdir(exist_ok=True)
env = gym.make('MountainCar-v0', render_mode='rgb_array')
# Collect frames
obs, info = env.reset()
frames = []
for step in range(20):
    action = env.action_space.sample()  # the tutorial uses model.predict(obs)
    obs, reward, terminated, truncated, info = env.step(action)
    frames.append(env.render())
    if terminated:
        print(f"Success! Reached goal in {step} steps")
        break
env.close()
# Create animation and save as GIF
fig, ax = plt.subplots(figsize=(6, 4))
ax.axis('off')
img = ax.imshow(frames[0])
def update(frame_idx):
    img.set_data(frames[frame_idx])
    return [img]
ani = animation.FuncAnimation(fig, update, frames=len(frames), interval=50, blit=True)
ani.save('./assets/mountain_car_trained.gif', writer='pillow', fps=20)
plt.close()
print(f"GIF saved to ./assets/mountain_car_trained.gif with {len(frames)} frames")
from PIL import Image
with Image.open('./assets/mountain_car_trained.gif') as gif:
    assert gif.n_frames > 1
"""


SAVE_VIDEO_BLOCK = """
import palaestra as gym
from palaestra.utils.video import save_video
env = gym.make('MountainCar-v0', render_mode='rgb_array_list')
env.reset(seed=0)
for _ in range(30):
    env.step(env.action_space.sample())
save_video(env.render(), "car.gif", fps=20)
"""

BLOCKS = {
    "render-loop": RENDER_BLOCK,
    "animation": ANIMATION_BLOCK,
    "full-episode": EPISODE_BLOCK,
    "gif": GIF_BLOCK,
    "save-video": SAVE_VIDEO_BLOCK,
}

# Runs every block in one interpreter (a fresh namespace each) to pay the matplotlib import
# once, and reports per block: "ok" or the traceback.
RUNNER = """
import contextlib, io, json, os, traceback
results, outputs = {}, {}
for name, code in json.loads(sys.argv[2]).items():
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(code, name, "exec"), {"__name__": "__main__", "sys": sys})
        results[name] = "ok"
    except BaseException:
        results[name] = traceback.format_exc()
    outputs[name] = out.getvalue()
    os.chdir(sys.argv[1])
results["no-pygame"] = "ok" if sys.modules.get("pygame") is None else "pygame was imported"
print(json.dumps({"results": results, "outputs": outputs}))
"""


@pytest.fixture(scope="module")
def tutorial_run(tmp_path_factory):
    for name in ("matplotlib", "PIL", "palaestra.envs.classic_control"):
        pytest.importorskip(name)
    workdir = tmp_path_factory.mktemp("tutorial")
    proc = subprocess.run(
        [sys.executable, "-c", PRELUDE + RUNNER, str(workdir), json.dumps(BLOCKS)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=workdir,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    return workdir, report["results"], report["outputs"]


@pytest.mark.parametrize("block", ["render-loop", "animation", "full-episode"])
def test_tutorial_block_runs_without_pygame(tutorial_run, block):
    _, results, _ = tutorial_run
    assert results[block] == "ok", results[block]
    assert results["no-pygame"] == "ok"


def test_tutorial_gif_block_runs_without_pygame(tutorial_run):
    workdir, results, outputs = tutorial_run
    assert results["gif"] == "ok", results["gif"]
    assert "GIF saved to ./assets/mountain_car_trained.gif with 20 frames" in outputs["gif"]
    assert (workdir / "assets" / "mountain_car_trained.gif").stat().st_size > 0


def test_palaestra_save_video_replaces_the_animation_detour(tutorial_run):
    """The one-call alternative to FuncAnimation + ani.save, also without pygame."""
    from PIL import Image

    workdir, results, _ = tutorial_run
    assert results["save-video"] == "ok", results["save-video"]
    with Image.open(workdir / "car.gif") as gif:
        assert gif.size == (600, 400) and gif.n_frames > 1


def test_scenes_need_numpy_only():
    """The rasterizer imports nothing optional: pygame, Pillow and matplotlib are blocked."""
    code = """
import sys
for name in ("pygame", "PIL", "matplotlib", "imageio", "IPython"):
    sys.modules[name] = None
from palaestra.rendering import scenes
assert scenes.render_cartpole((0, 0, 0.1, 0)).shape == (400, 600, 3)
assert scenes.render_mountain_car(-0.5, 0.45).shape == (400, 600, 3)
assert scenes.render_pendulum(0.5, 1.0).shape == (500, 500, 3)
assert scenes.render_acrobot(0.5, 0.1).shape == (500, 500, 3)
print("OK")
"""
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.stdout == "OK\n", result.stderr[-2000:]
