"""Frames of a MuJoCo env drawn offscreen by MuJoCo's own OpenGL renderer.

The camera is Gymnasium 1.4.0's: with no ``camera_id``/``camera_name`` a free camera looking at
the median of the geoms' positions (when the first frame is drawn) from the model's extent,
then ``default_camera_config`` applied; otherwise the model's fixed camera. The scene, the
150% font context and the offscreen buffer are MuJoCo's ``mjv``/``mjr`` calls in Gymnasium's
order, so on the same OpenGL backend the frames are the same bytes. The backend is
``MUJOCO_GL`` (``egl``, ``osmesa`` or ``glfw``) or, unset, the first of those that works.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from palaestra import error

OFFSCREEN_MODES = ("rgb_array", "depth_array", "rgbd_tuple")
_BACKENDS = ("egl", "osmesa", "glfw")


def _gl_context(mujoco: Any, width: int, height: int) -> tuple[Any, str]:
    """An OpenGL context of ``MUJOCO_GL``'s backend, or the first one that works."""
    chosen = os.environ.get("MUJOCO_GL")
    if chosen is not None and chosen not in _BACKENDS:
        raise ValueError(f"MUJOCO_GL must be one of {_BACKENDS} to render, got {chosen!r}")
    failures = []
    for backend in (chosen,) if chosen else _BACKENDS:
        try:
            module = __import__(f"mujoco.{backend}", fromlist=["GLContext"])
            return module.GLContext(width, height), backend
        except Exception as e:  # each backend fails in its own way (ImportError, OSError, ...)
            failures.append(f"{backend}: {type(e).__name__}: {e}")
    raise error.DependencyNotInstalled(
        "no OpenGL backend for MuJoCo's renderer could start ("
        + "; ".join(failures)
        + "): install EGL or OSMesa (Debian: libegl1 or libosmesa6) and set MUJOCO_GL=egl or "
        "MUJOCO_GL=osmesa"
    )


class OffscreenRenderer:
    """Draws ``model``'s state in ``data`` into ``width`` x ``height`` frames."""

    def __init__(
        self,
        mujoco: Any,
        model: Any,
        data: Any,
        width: int,
        height: int,
        camera_id: int,
        default_camera_config: dict[str, Any] | None,
        max_geom: int,
        visual_options: dict[int, bool] | None,
    ) -> None:
        self._mujoco, self.model, self.data = mujoco, model, data
        self.context, self.backend = _gl_context(mujoco, width, height)
        self.context.make_current()
        self.viewport = mujoco.MjrRect(0, 0, width, height)
        self.scene = mujoco.MjvScene(model, max_geom)
        self.option = mujoco.MjvOption()
        for flag, value in (visual_options or {}).items():
            self.option.flags[flag] = value
        self.perturb = mujoco.MjvPerturb()
        self.mjr = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self.mjr)
        camera = self.camera = mujoco.MjvCamera()
        camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        camera.fixedcamid = -1
        for axis in range(3):
            camera.lookat[axis] = np.median(data.geom_xpos[:, axis])
        camera.distance = model.stat.extent
        for key, value in (default_camera_config or {}).items():
            if isinstance(value, np.ndarray):
                getattr(camera, key)[:] = value
            else:
                setattr(camera, key, value)
        camera.type = (
            mujoco.mjtCamera.mjCAMERA_FREE if camera_id == -1 else mujoco.mjtCamera.mjCAMERA_FIXED
        )
        camera.fixedcamid = camera_id

    def render(self, mode: str) -> Any:
        """The frame: ``(H, W, 3) uint8`` (``rgb_array``), ``(H, W) float32`` depth buffer
        values in [0, 1] (``depth_array``), or both (``rgbd_tuple``)."""
        mujoco, rect = self._mujoco, self.viewport
        self.context.make_current()
        mujoco.mjv_updateScene(
            self.model,
            self.data,
            self.option,
            self.perturb,
            self.camera,
            mujoco.mjtCatBit.mjCAT_ALL,
            self.scene,
        )
        mujoco.mjr_render(rect, self.scene, self.mjr)
        rgb = np.zeros((rect.height, rect.width, 3), dtype=np.uint8)
        depth = np.zeros((rect.height, rect.width), dtype=np.float32)
        mujoco.mjr_readPixels(rgb, depth, rect, self.mjr)
        # OpenGL's rows run bottom-up
        if mode == "rgb_array":
            return rgb[::-1].copy()
        if mode == "depth_array":
            return depth[::-1].copy()
        return rgb[::-1].copy(), depth[::-1].copy()

    def close(self) -> None:
        """Free the OpenGL context (the frame buffers go with it)."""
        if self.context is not None:
            self.mjr.free()
            self.context.free()
            self.context = None
