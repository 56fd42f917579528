"""Frames of the MuJoCo envs, drawn the same way by palaestra's and by Gymnasium's envs.

:func:`frames` makes an env with ``make`` (either library's), resets it with a seed, steps it
with its own seeded action space and renders after the reset and after the steps. ``python -m
tests.envs.mujoco.frames {palaestra,gymnasium} OUT`` draws every :data:`CASES` entry and saves
the frames to the ``.npz`` file ``OUT`` with the OpenGL backend used; on palaestra's side
``gymnasium`` is blocked from import. Each side runs in its own interpreter so that both pick
their backend from the same ``MUJOCO_GL`` (PyOpenGL binds one platform per process).
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

MUJOCO_IDS = [
    "Ant-v5",
    "HalfCheetah-v5",
    "Hopper-v5",
    "Humanoid-v5",
    "HumanoidStandup-v5",
    "InvertedDoublePendulum-v5",
    "InvertedPendulum-v5",
    "Pusher-v5",
    "Reacher-v5",
    "Swimmer-v5",
    "Walker2d-v5",
]

# (name, env id, make kwargs): each env's defaults in both image modes, then the camera and
# frame keywords on a few models.
CASES: list[tuple[str, str, dict[str, Any]]] = [
    *[(f"{env_id}/rgb", env_id, {"render_mode": "rgb_array"}) for env_id in MUJOCO_IDS],
    *[(f"{env_id}/depth", env_id, {"render_mode": "depth_array"}) for env_id in MUJOCO_IDS],
    ("Hopper-v5/track", "Hopper-v5", {"render_mode": "rgb_array", "camera_name": "track"}),
    ("Humanoid-v5/camera1", "Humanoid-v5", {"render_mode": "rgb_array", "camera_id": 1}),
    ("Ant-v5/free", "Ant-v5", {"render_mode": "rgb_array", "camera_id": -1}),
    ("Walker2d-v5/rgbd", "Walker2d-v5", {"render_mode": "rgbd_tuple"}),
    (
        "Reacher-v5/size",
        "Reacher-v5",
        {"render_mode": "rgb_array", "width": 160, "height": 96, "max_geom": 50},
    ),
    (
        "HalfCheetah-v5/config",
        "HalfCheetah-v5",
        {
            "render_mode": "rgb_array",
            "default_camera_config": {
                "distance": 2.5,
                "elevation": -35.0,
                "azimuth": 60.0,
                "lookat": np.array([0.5, 0.0, 0.3]),
            },
        },
    ),
    # mjVIS_COM (centres of mass) and mjVIS_CONTACTPOINT drawn
    (
        "Hopper-v5/visual",
        "Hopper-v5",
        {"render_mode": "rgb_array", "visual_options": {14: True, 20: True}},
    ),
]

STEPS = 15


def frames(make: Callable[..., Any], env_id: str, kwargs: dict[str, Any]) -> list[np.ndarray]:
    """The frames after ``reset(seed=4)`` and after :data:`STEPS` sampled actions."""
    env = make(env_id, **kwargs)
    env.reset(seed=4)
    env.action_space.seed(5)
    out = []
    for shown in (env.render(),):
        out.extend(shown if isinstance(shown, tuple) else [shown])
    for _ in range(STEPS):
        env.step(env.action_space.sample())
    shown = env.render()
    out.extend(shown if isinstance(shown, tuple) else [shown])
    env.close()
    return out


def main(side: str, out_path: str) -> None:
    """Draw every case with ``side``'s envs and save the frames and the backend used."""
    warnings.simplefilter("ignore")  # mujoco's version and deprecation notices
    if side == "palaestra":
        sys.modules["gymnasium"] = None  # type: ignore[assignment]  # any import of it fails
        import palaestra
        from palaestra.envs.mujoco import rendering

        make = palaestra.make
    else:
        import gymnasium

        make = gymnasium.make
    arrays: dict[str, np.ndarray] = {}
    for name, env_id, kwargs in CASES:
        for i, frame in enumerate(frames(make, env_id, kwargs)):
            arrays[f"{name}/{i}"] = frame
    if side == "palaestra":
        arrays["backend"] = np.array(rendering._working_backend)
        arrays["package"] = np.array(palaestra.__file__)
        arrays["gymnasium_loaded"] = np.array(
            [m for m in sys.modules if m.startswith("gymnasium.")], dtype=str
        )
    np.savez(out_path, **arrays)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
