"""Reference frames from Gymnasium's pygame renderer for given states (test helper)."""

from __future__ import annotations

import os

import numpy as np

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "hide")

# (env id, state) pairs: upright, tilted both ways, near the edges, wrapped angles.
CARTPOLE_STATES = [(0.0, 0, 0.0, 0), (-1.3, 0, 0.2, 0), (2.1, 0, -0.21, 0), (0.37, 0, 1.2, 0)]
MOUNTAIN_POSITIONS = [-1.2, -0.9, -0.52, -0.1, 0.3, 0.5, 0.6]
PENDULUM_STATES = [(0.0, None), (0.3, -1.5), (-2.5, 2.0), (3.1, 0.6), (1.2, -0.02)]
ACROBOT_STATES = [(0.0, 0.0), (0.6, -1.1), (-2.9, 2.5), (3.0, 0.1)]


def gym_frame(env_id: str, state: object, **kwargs: object) -> np.ndarray:
    """Render Gymnasium's env ``env_id`` with its internal state set to ``state``."""
    import gymnasium

    env = gymnasium.make(env_id, render_mode="rgb_array", **kwargs)
    env.reset(seed=0)
    raw = env.unwrapped
    if env_id.startswith("Pendulum"):
        theta, last_u = state  # type: ignore[misc]
        raw.state = np.array([theta, 0.0])
        raw.last_u = last_u
    elif env_id.startswith("Acrobot"):
        raw.state = np.array([*state, 0.0, 0.0])  # type: ignore[misc]
    elif env_id.startswith("MountainCar"):
        raw.state = np.array([state, 0.0])
    else:
        raw.state = np.array(state, dtype=np.float64)
    frame = env.render()
    env.close()
    return frame


def similarity(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """(mean absolute difference per channel, fraction of pixels differing by > 32 anywhere)."""
    diff = np.abs(a.astype(np.int16) - b.astype(np.int16))
    return float(diff.mean()), float((diff.max(axis=2) > 32).mean())
