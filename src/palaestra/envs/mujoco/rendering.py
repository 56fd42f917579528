"""MuJoCo's own OpenGL renderer for the MuJoCo envs, offscreen, on a headless backend if need be.

A frame is what Gymnasium 1.4.0's MuJoCo envs draw: MuJoCo's scene (``mjv_updateScene``) drawn
by MuJoCo's renderer (``mjr_render``) into its offscreen buffer and read back
(``mjr_readPixels``), seen by a free camera that looks at the median of the geoms' positions
from the model's extent unless ``default_camera_config`` says otherwise, or by one of the
model's fixed cameras (``camera_id`` / ``camera_name``). On the same ``MUJOCO_GL`` backend the
pixels are Gymnasium's, byte for byte (tests/envs/mujoco/test_rendering.py).

Where palaestra differs, on purpose:

- a ``camera_name`` the model lacks, or a ``camera_id`` outside ``[-1, ncam)``, raises
  ``ValueError`` at construction (Gymnasium silently uses the free camera for an unknown name,
  and MuJoCo ends the whole process on an out-of-range id);
- ``default_camera_config`` keys and ``visual_options`` flags are checked at construction;
- frames are C-contiguous arrays (Gymnasium returns views with a negative row stride);
- the OpenGL context is made current before every frame, so several envs can render in turn
  on one thread.

``depth_array`` is MuJoCo's depth buffer as Gymnasium returns it: values in ``[0, 1]``,
non-linear in distance; :func:`depth_to_meters` converts it. The backend is ``MUJOCO_GL``
(``egl``, ``osmesa``, ``glfw``, or ``cgl`` on macOS) when set, else the first that works of
glfw (only where a display exists), egl and osmesa on Linux, cgl and glfw on macOS, glfw on
Windows. The GL context, scene and MuJoCo render context are made on the first frame, freed
by :meth:`MujocoRenderer.close`, and left out of pickles and deep copies (a copy makes its own
on its first frame, with the same camera).
"""

from __future__ import annotations

import operator
import os
import platform
from typing import Any

import numpy as np

from palaestra import error
from palaestra.rendering.notebook import in_notebook

__all__ = [
    "RENDER_MODES",
    "MujocoRenderer",
    "backend_order",
    "check_display",
    "check_size",
    "depth_to_meters",
    "gl_context",
]

RENDER_MODES = ("human", "rgb_array", "depth_array", "rgbd_tuple")

# MuJoCo's camera fields that default_camera_config may set, and those that are vectors.
CAMERA_FIELDS = (
    "type",
    "fixedcamid",
    "trackbodyid",
    "lookat",
    "distance",
    "azimuth",
    "elevation",
    "orthographic",
)
_VECTOR_FIELDS = ("lookat",)

_BACKENDS = {"Linux": ("glfw", "egl", "osmesa"), "Darwin": ("cgl", "glfw"), "Windows": ("glfw",)}
_working_backend: str | None = None  # PyOpenGL binds one platform per process: keep the first


def _mujoco() -> Any:
    # Imported where used: the env that owns a renderer has imported it already (and said
    # which extra installs it when it could not).
    import mujoco

    return mujoco


def _has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def check_display() -> None:
    """``UnsupportedMode`` when ``render_mode="human"`` has nowhere to show its frames: on
    Linux outside a notebook, with neither ``DISPLAY`` nor ``WAYLAND_DISPLAY`` set (SDL's
    ``dummy``/``offscreen`` video drivers count as a display: pygame draws into them)."""
    if platform.system() != "Linux" or _has_display() or in_notebook():
        return
    if os.environ.get("SDL_VIDEODRIVER", "").lower() in ("dummy", "offscreen"):
        return
    raise error.UnsupportedMode(
        "render_mode='human' needs a display, and this machine has none (neither DISPLAY nor "
        "WAYLAND_DISPLAY is set): render with render_mode='rgb_array' and save the frames "
        "(RecordVideo, or `palaestra record` for a trained agent)"
    )


def backend_order() -> tuple[str, ...]:
    """The OpenGL backends tried, in order: ``MUJOCO_GL`` alone when set, else the platform's.

    ``RuntimeError`` names a ``MUJOCO_GL`` value this platform has no backend for.
    """
    system = platform.system()
    known = _BACKENDS.get(system, ("glfw",))
    chosen = os.environ.get("MUJOCO_GL", "").strip().lower()
    if chosen:
        if chosen not in known:
            raise RuntimeError(
                f"MUJOCO_GL={os.environ['MUJOCO_GL']!r} is not an OpenGL backend MuJoCo offers "
                f"on {system}: expected one of {known!r} (or leave MUJOCO_GL unset)"
            )
        return (chosen,)
    if system == "Linux" and not _has_display():
        return tuple(b for b in known if b != "glfw")  # glfw needs an X or Wayland display
    return known


def _context_class(backend: str) -> Any:
    if backend == "egl":
        from mujoco.egl import GLContext
    elif backend == "osmesa":
        from mujoco.osmesa import GLContext
    elif backend == "cgl":
        from mujoco.cgl import GLContext
    else:
        from mujoco.glfw import GLContext
    return GLContext


def gl_context(width: int, height: int) -> tuple[Any, str]:
    """A current OpenGL context from the first backend of :func:`backend_order` that works,
    and that backend's name; ``RuntimeError`` saying what each one answered if none does."""
    global _working_backend
    order = backend_order()
    if _working_backend in order:
        order = (_working_backend, *(b for b in order if b != _working_backend))
    failures = []
    platform_before = os.environ.get("PYOPENGL_PLATFORM")
    for backend in order:
        try:
            context = _context_class(backend)(width, height)
            context.make_current()
        except Exception as e:  # an ImportError, OSError or GL error, depending on the backend
            failures.append(f"{backend}: {type(e).__name__}: {e}")
            # mujoco.egl/osmesa claim PyOpenGL's platform on import; give it back for the next
            if platform_before is None:
                os.environ.pop("PYOPENGL_PLATFORM", None)
            continue
        _working_backend = backend
        return context, backend
    raise RuntimeError(
        "MuJoCo found no OpenGL backend to render with ("
        + "; ".join(failures)
        + "). On a headless Linux machine install EGL (Debian/Ubuntu: apt-get install libegl1 "
        "libegl-mesa0 libgl1 libgl1-mesa-dri) and set MUJOCO_GL=egl, or install OSMesa "
        "(libosmesa6) and set MUJOCO_GL=osmesa"
    )


def depth_to_meters(depth: np.ndarray, model: Any) -> np.ndarray:
    """Distances (in model units) from the camera for a ``depth_array`` frame of ``model``.

    MuJoCo's depth buffer holds ``d`` in ``[0, 1]``; with its clipping planes ``near`` and
    ``far`` (``model.vis.map`` times ``model.stat.extent``) the distance is
    ``near / (1 - d * (1 - near / far))``.
    """
    extent = float(model.stat.extent)
    near = float(model.vis.map.znear) * extent
    far = float(model.vis.map.zfar) * extent
    return near / (1.0 - np.asarray(depth, dtype=np.float64) * (1.0 - near / far))


def check_size(name: str, value: Any) -> int:
    """A positive int (a frame size, ``max_geom``), else ``TypeError``/``ValueError`` naming it."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an int, got {value!r}")
    if value < 1:
        raise ValueError(f"{name} must be >= 1, got {value!r}")
    return int(value)


def _apply_camera_config(camera: Any, config: dict[str, Any]) -> None:
    for key, value in config.items():
        if key in _VECTOR_FIELDS:
            getattr(camera, key)[:] = value
        else:
            setattr(camera, key, value)


class MujocoRenderer:
    """Frames of one env's ``MjModel``/``MjData``, drawn by MuJoCo on first request.

    The arguments are Gymnasium's ``MujocoEnv`` rendering keywords; they are checked here, so
    a bad one fails when the env is made, not on its first frame.
    """

    def __init__(
        self,
        model: Any,
        *,
        width: int,
        height: int,
        camera_id: int | None = None,
        camera_name: str | None = None,
        default_camera_config: dict[str, Any] | None = None,
        max_geom: int = 1000,
        visual_options: dict[int, bool] | None = None,
    ) -> None:
        self.width = check_size("width", width)
        self.height = check_size("height", height)
        self.max_geom = check_size("max_geom", max_geom)
        self.camera_id = self._resolve_camera(model, camera_id, camera_name)
        self.default_camera_config = self._check_camera_config(default_camera_config)
        self.visual_options = self._check_visual_options(visual_options)
        self.backend: str | None = None
        self._gl: dict[str, Any] | None = None
        # The free camera's pose, fixed on the first frame (its look-at point is where the geoms
        # are then); kept through pickling so a copy frames the scene as the original does.
        self._camera_pose: dict[str, Any] | None = None

    def _resolve_camera(self, model: Any, camera_id: Any, camera_name: Any) -> int:
        mujoco = _mujoco()
        if camera_id is not None and camera_name is not None:
            raise ValueError(
                "Both `camera_id` and `camera_name` cannot be specified at the same time "
                f"(got camera_id={camera_id!r}, camera_name={camera_name!r})."
            )
        names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, i) for i in range(model.ncam)]
        if camera_name is not None:
            if not isinstance(camera_name, str):
                raise TypeError(f"camera_name must be a str, got {camera_name!r}")
            found = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera_name)
            if found < 0:
                named = [n for n in names if n]
                raise ValueError(
                    f"camera_name={camera_name!r}: the model has no camera of that name "
                    f"(its named cameras: {named!r}; camera_id=-1 is the free camera)"
                )
            return int(found)
        if camera_id is None:
            # Gymnasium's default: the free camera, placed by default_camera_config, even where
            # the model has a "track" camera.
            return -1
        if isinstance(camera_id, (bool, np.bool_)) or not isinstance(camera_id, (int, np.integer)):
            raise TypeError(f"camera_id must be an int, got {camera_id!r}")
        if not -1 <= camera_id < model.ncam:
            raise ValueError(
                f"camera_id={camera_id!r} is out of range: the model has {model.ncam} "
                f"camera(s) {names!r}, so camera_id must be in [-1, {model.ncam - 1}] "
                "(-1 is the free camera)"
            )
        return int(camera_id)

    def _check_camera_config(self, config: Any) -> dict[str, Any] | None:
        if config is None:
            return None
        if not isinstance(config, dict):
            raise TypeError(f"default_camera_config must be a dict or None, got {config!r}")
        unknown = [key for key in config if key not in CAMERA_FIELDS]
        if unknown:
            raise ValueError(
                f"default_camera_config has unknown key(s) {unknown!r}: expected MuJoCo camera "
                f"fields {CAMERA_FIELDS!r}"
            )
        try:  # on a scratch camera, so a bad value fails now
            _apply_camera_config(_mujoco().MjvCamera(), config)
        except (TypeError, ValueError) as e:
            raise ValueError(f"default_camera_config={config!r} cannot be applied: {e}") from e
        return dict(config)

    def _check_visual_options(self, options: Any) -> dict[int, bool]:
        if options is None:
            return {}
        if not isinstance(options, dict):
            raise TypeError(f"visual_options must be a dict or None, got {options!r}")
        count = int(_mujoco().mjtVisFlag.mjNVISFLAG)
        checked = {}
        for flag, value in options.items():
            try:  # an int or a mujoco.mjtVisFlag member
                index = operator.index(flag) if not isinstance(flag, (bool, np.bool_)) else -1
            except TypeError:
                index = -1
            if not 0 <= index < count:
                raise ValueError(
                    f"visual_options key {flag!r} is not a MuJoCo visualisation flag: expected "
                    f"an mjtVisFlag (an int in [0, {count}))"
                )
            if not isinstance(value, (bool, np.bool_, int, np.integer)):
                raise TypeError(f"visual_options[{flag!r}] must be a bool, got {value!r}")
            checked[index] = bool(value)
        return checked

    # -- GL resources ----------------------------------------------------------------------

    def _open(self, model: Any, data: Any) -> dict[str, Any]:
        mujoco = _mujoco()
        context, self.backend = gl_context(self.width, self.height)
        option = mujoco.MjvOption()
        for flag, value in self.visual_options.items():
            option.flags[flag] = value
        camera = mujoco.MjvCamera()
        if self._camera_pose is None:
            camera.type = mujoco.mjtCamera.mjCAMERA_FREE
            camera.fixedcamid = -1
            camera.lookat[:] = np.median(data.geom_xpos, axis=0)
            camera.distance = model.stat.extent
            if self.default_camera_config is not None:
                _apply_camera_config(camera, self.default_camera_config)
            self._camera_pose = {
                key: np.array(getattr(camera, key))
                if key in _VECTOR_FIELDS
                else getattr(camera, key)
                for key in CAMERA_FIELDS
            }
        else:
            _apply_camera_config(camera, self._camera_pose)
        if self.camera_id == -1:
            camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        else:
            camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        camera.fixedcamid = self.camera_id
        gl = {
            "context": context,
            "scene": mujoco.MjvScene(model, maxgeom=self.max_geom),
            "option": option,
            "perturb": mujoco.MjvPerturb(),
            "camera": camera,
            "render_context": mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150),
            "viewport": mujoco.MjrRect(0, 0, self.width, self.height),
        }
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, gl["render_context"])
        return gl

    def render(self, model: Any, data: Any, mode: str) -> Any:
        """The frame of ``data`` for ``mode``: ``(H, W, 3) uint8`` for ``rgb_array`` (and
        ``human``), ``(H, W) float32`` for ``depth_array``, both for ``rgbd_tuple``."""
        if mode not in RENDER_MODES:
            raise ValueError(f"render mode {mode!r} is not one of {RENDER_MODES!r}")
        mujoco = _mujoco()
        if self._gl is None:
            self._gl = self._open(model, data)
        gl = self._gl
        gl["context"].make_current()
        mujoco.mjv_updateScene(
            model,
            data,
            gl["option"],
            gl["perturb"],
            gl["camera"],
            mujoco.mjtCatBit.mjCAT_ALL,
            gl["scene"],
        )
        mujoco.mjr_render(gl["viewport"], gl["scene"], gl["render_context"])
        want_depth = mode in ("depth_array", "rgbd_tuple")
        want_rgb = not mode == "depth_array"
        rgb = np.empty((self.height, self.width, 3), np.uint8) if want_rgb else None
        depth = np.empty((self.height, self.width), np.float32) if want_depth else None
        mujoco.mjr_readPixels(rgb, depth, gl["viewport"], gl["render_context"])
        # OpenGL's rows run bottom to top
        if mode == "depth_array":
            return np.ascontiguousarray(depth[::-1])  # type: ignore[index]
        rgb = np.ascontiguousarray(rgb[::-1])  # type: ignore[index]
        if mode == "rgbd_tuple":
            return rgb, np.ascontiguousarray(depth[::-1])  # type: ignore[index]
        return rgb

    def close(self) -> None:
        """Free the GL context and MuJoCo's render context; a later frame makes new ones."""
        gl, self._gl = self._gl, None
        if gl is None:
            return
        try:
            gl["context"].make_current()
            gl["render_context"].free()
        finally:
            gl["context"].free()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # at interpreter exit the GL libraries may be gone already
            pass

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_gl"] = None  # GL objects are bound to this process and thread
        return state
