"""Frames of the MuJoCo envs, drawn the same way by palaestra's and by Gymnasium's envs.

:func:`frames` makes an env with ``make`` (either library's), resets it with a seed, steps it
with its own seeded action space and renders after the reset and after the steps. ``python -m
tests.envs.mujoco.frames {palaestra,gymnasium} OUT {fast,slow}`` draws those :data:`CASES` and saves
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

# (name, env id, make kwargs, slow): each env's defaults in both image modes, then the camera
# and frame keywords on a few models. The default suite draws the fast ones (~10 s a side on
# two cores with llvmpipe); the depth frames and the other cameras wait for -m slow.
CASES: list[tuple[str, str, dict[str, Any], bool]] = [
    *[(f"{env_id}/rgb", env_id, {"render_mode": "rgb_array"}, False) for env_id in MUJOCO_IDS],
    *[(f"{env_id}/depth", env_id, {"render_mode": "depth_array"}, True) for env_id in MUJOCO_IDS],
    ("Hopper-v5/track", "Hopper-v5", {"render_mode": "rgb_array", "camera_name": "track"}, False),
    ("Walker2d-v5/rgbd", "Walker2d-v5", {"render_mode": "rgbd_tuple"}, False),
    (
        "Reacher-v5/size",
        "Reacher-v5",
        {"render_mode": "rgb_array", "width": 160, "height": 96, "max_geom": 50},
        False,
    ),
    (
        # mjVIS_CONTACTPOINT and mjVIS_COM (the centre of mass) drawn
        "Hopper-v5/visual",
        "Hopper-v5",
        {"render_mode": "rgb_array", "visual_options": {14: True, 20: True}},
        False,
    ),
    ("Humanoid-v5/camera1", "Humanoid-v5", {"render_mode": "rgb_array", "camera_id": 1}, True),
    ("Ant-v5/free", "Ant-v5", {"render_mode": "rgb_array", "camera_id": -1}, True),
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
        True,
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


def main(side: str, out_path: str, slow: bool) -> None:
    """Draw the fast (or the slow) cases with ``side``'s envs; save the frames and backend."""
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
    for name, env_id, kwargs, is_slow in CASES:
        if is_slow != slow:
            continue
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
    main(sys.argv[1], sys.argv[2], sys.argv[3] == "slow")
