"""What the MuJoCo envs share: the lazy ``mujoco`` import, model loading, stepping and resets.

:class:`MujocoEnv` holds one ``MjModel`` and its ``MjData``; a step writes the action into
``data.ctrl``, advances ``frame_skip`` MuJoCo steps and then computes the constraint forces
(``mj_rnePostConstraint``) that the observations read (``cfrc_ext``), as Gymnasium 1.4.0's
``MujocoEnv`` does, so the same model, seed and actions give the same bits.
"""

from __future__ import annotations

import math
import os
import warnings
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from palaestra import error
from palaestra.envs.box2d._common import box_action, check_bool, check_real
from palaestra.envs.mujoco.rendering import (
    RENDER_MODES,
    MujocoRenderer,
    check_display,
    check_size,
)
from palaestra.envs.rendered import RenderedEnv
from palaestra.spaces import Box

ASSETS = Path(__file__).parent / "assets"

# The mujoco release the parity tests (tests/envs/mujoco) were recorded on: MuJoCo does not
# promise equal bits across releases, so another one warns once.
PARITY_MUJOCO_VERSION = "4.0.0"
_version_checked = False

MUJOCO_ENVS = (
    "the MuJoCo environments: Ant, HalfCheetah, Hopper, Humanoid, HumanoidStandup, "
    "InvertedDoublePendulum, InvertedPendulum, Pusher, Reacher, Swimmer, Walker2d"
)


class MujocoWarning(UserWarning):
    """MuJoCo flagged the simulation (e.g. a NaN or huge acceleration: it reset the state)."""


def import_mujoco() -> Any:
    """The ``mujoco`` module, or ``DependencyNotInstalled`` naming the extra to install.

    The first import with another version than :data:`PARITY_MUJOCO_VERSION` warns once.
    """
    global _version_checked
    try:
        import mujoco
    except ImportError as e:
        raise error.dependency_not_installed("mujoco", "mujoco", MUJOCO_ENVS) from e
    if not _version_checked:
        _version_checked = True
        if mujoco.__version__ != PARITY_MUJOCO_VERSION:
            warnings.warn(
                f"mujoco {mujoco.__version__} is installed; palaestra's MuJoCo envs were checked "
                f"to give Gymnasium's trajectories bit for bit on mujoco {PARITY_MUJOCO_VERSION} "
                "only (other releases may differ in the last bits)",
                stacklevel=3,
            )
    return mujoco


def model_path(xml_file: str | os.PathLike[str]) -> Path:
    """Where ``xml_file`` is: a bare name is one of palaestra's models (``assets/``); a path
    starting with ``.``, ``/`` or ``~`` is the user's file (Gymnasium's rule)."""
    if not isinstance(xml_file, (str, os.PathLike)):
        raise TypeError(f"xml_file must be a path, got {xml_file!r} ({type(xml_file).__name__})")
    text = os.fspath(xml_file)
    if text.startswith(("/", ".")):
        path = Path(text)
    elif text.startswith("~"):
        path = Path(text).expanduser()
    else:
        path = ASSETS / text
    if not path.is_file():
        raise FileNotFoundError(
            f"xml_file {text!r}: no MJCF file at {str(path)!r} (a bare name is looked up in "
            f"{str(ASSETS)!r}; start a path of your own with '.', '/' or '~')"
        )
    return path


def load_model(mujoco: Any, xml_file: str | os.PathLike[str]) -> Any:
    """The compiled ``MjModel`` of ``xml_file``; a file MuJoCo cannot compile raises
    ``InvalidModelFile`` naming the path and MuJoCo's message."""
    path = model_path(xml_file)
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except ValueError as e:
        raise error.InvalidModelFile(
            f"xml_file {os.fspath(xml_file)!r} ({str(path)!r}) does not compile: {e}"
        ) from e


def check_frame_skip(frame_skip: Any) -> int:
    """A positive integer, else ``TypeError``/``ValueError`` naming it."""
    if isinstance(frame_skip, (bool, np.bool_)) or not isinstance(frame_skip, (int, np.integer)):
        raise TypeError(f"frame_skip must be an int, got {frame_skip!r}")
    if frame_skip < 1:
        raise ValueError(f"frame_skip must be >= 1, got {frame_skip!r}")
    return int(frame_skip)


def check_range(name: str, value: Any) -> tuple[float, float]:
    """A ``(low, high)`` pair of numbers (infinities allowed, NaN not), ``low <= high``."""
    if not isinstance(value, (tuple, list, np.ndarray)) or len(value) != 2:
        raise TypeError(f"{name} must be a (low, high) pair, got {value!r}")
    low, high = value
    for bound in (low, high):
        if isinstance(bound, (bool, np.bool_)) or not isinstance(bound, (int, float, np.number)):
            raise TypeError(f"{name} must hold two numbers, got {value!r}")
        if math.isnan(bound):
            raise ValueError(f"{name} must not hold NaN, got {value!r}")
    if low > high:
        raise ValueError(f"{name} must have low <= high, got {value!r}")
    return float(low), float(high)


def check_weights(**weights: Any) -> list[float]:
    """Each keyword a finite real number (``check_real``), in order."""
    return [check_real(name, value) for name, value in weights.items()]


def warning_names(counts: np.ndarray, before: np.ndarray) -> list[str]:
    """The names of MuJoCo's warnings whose counters grew from ``before`` to ``counts``."""
    kinds = import_mujoco().mjtWarning
    return [kinds(int(k)).name for k in np.flatnonzero(counts > before)]


def warn_unstable(who: str, names: list[str], time: float, stacklevel: int) -> None:
    """Raise :class:`MujocoWarning` naming MuJoCo's warnings of one step."""
    warnings.warn(
        f"{who}: MuJoCo reported {', '.join(names)} at time {time:.4f} (the simulation is "
        "unstable; MuJoCo may have reset it)",
        MujocoWarning,
        stacklevel=stacklevel,
    )


class _DefaultCamera:
    """``default_camera_config``'s default: the env's own camera settings (Gymnasium's
    ``DEFAULT_CAMERA_CONFIG``); an explicit None means none, as there."""

    def __repr__(self) -> str:
        return "DEFAULT_CAMERA"

    def __reduce__(self) -> str:
        return "DEFAULT_CAMERA"  # one object, also after a copy


DEFAULT_CAMERA: Any = _DefaultCamera()


class MujocoEnv(RenderedEnv[np.ndarray, np.ndarray]):
    """One MuJoCo model stepped ``frame_skip`` times per action.

    Subclasses build their observation space, then implement ``step``, ``reset_model`` (the
    noisy start state; it returns the first observation) and optionally ``_get_reset_info``.
    The rendering keywords (``render_mode``, ``width``, ``height``, ``camera_id``,
    ``camera_name``, ``default_camera_config``, ``max_geom``, ``visual_options``) are
    Gymnasium's; frames come from :class:`~palaestra.envs.mujoco.rendering.MujocoRenderer`
    (MuJoCo's own renderer, made on the first frame) and ``"human"`` shows the ``rgb_array``
    frame in palaestra's window after every reset and step.
    """

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES)}
    #: the camera settings used when ``default_camera_config`` is not given (Gymnasium's)
    default_camera: ClassVar[dict[str, Any] | None] = None

    def __init__(
        self,
        xml_file: str | os.PathLike[str],
        frame_skip: int,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
        camera_id: int | None = None,
        camera_name: str | None = None,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        max_geom: int = 1000,
        visual_options: dict[int, bool] | None = None,
    ) -> None:
        self._init_render(render_mode)
        if default_camera_config is DEFAULT_CAMERA:
            default_camera_config = self.default_camera  # the renderer keeps a copy
        if render_mode == "human":
            check_display()
        self.frame_skip = check_frame_skip(frame_skip)
        self.xml_file = xml_file
        self.width, self.height = check_size("width", width), check_size("height", height)
        self.camera_id, self.camera_name = camera_id, camera_name
        self.default_camera_config = default_camera_config
        self.max_geom, self.visual_options = max_geom, visual_options
        self._mujoco = import_mujoco()
        self.fullpath = str(model_path(xml_file))
        self.model = load_model(self._mujoco, xml_file)
        # Gymnasium grows the offscreen buffer to the frame size (never shrinks it); done here
        # too so that the two models stay equal field for field.
        glob = self.model.vis.global_
        glob.offwidth = max(glob.offwidth, width)
        glob.offheight = max(glob.offheight, height)
        self.data = self._mujoco.MjData(self.model)
        self._bind_views()
        self.init_qpos = self.data.qpos.ravel().copy()
        self.init_qvel = self.data.qvel.ravel().copy()
        low, high = self.model.actuator_ctrlrange.copy().astype(np.float32).T
        self.action_space = Box(low=low, high=high, dtype=np.float32)
        self.metadata = {**type(self).metadata, "render_fps": int(np.round(1.0 / self.dt))}
        self._renderer = MujocoRenderer(
            self.model,
            width=width,
            height=height,
            camera_id=camera_id,
            camera_name=camera_name,
            default_camera_config=default_camera_config,
            max_geom=max_geom,
            visual_options=visual_options,
        )

    @staticmethod
    def _float_box(size: int) -> Box:
        return Box(low=-np.inf, high=np.inf, shape=(size,), dtype=np.float64)

    def _bind_views(self) -> None:
        """Views of ``data``'s arrays that steps read (they live as long as ``data``): the
        warning counters and, for the row maths, one-row views of ``row_fields``."""
        data = self.data
        self._warning_counts = data.warning.number
        self._ctrl = data.ctrl
        names = dict.fromkeys(self.before_fields + self.row_fields)
        self._rows = {name: getattr(data, name)[None] for name in names}

    # -- the row maths --------------------------------------------------------------------------
    # Each env's observation, reward, termination and info maths is written once, on arrays
    # with a leading row axis: the single env calls it with its one row (views of its MjData),
    # its native batch (palaestra.envs.mujoco.batch) with the stacked arrays of N rows.

    #: MjData arrays that ``rows_step``/``rows_obs`` read, and that ``rows_before`` reads
    row_fields: ClassVar[tuple[str, ...]] = ("qpos", "qvel")
    before_fields: ClassVar[tuple[str, ...]] = ()
    #: info keys (and the reward) that Gymnasium's single env gives as Python scalars
    python_infos: ClassVar[dict[str, type]] = {}
    python_reward: ClassVar[type | None] = None

    def rows_before(self, rows: dict[str, np.ndarray]) -> Any:
        """What a step's maths needs from before the physics (e.g. positions), per row; it
        must not be a view of ``rows``' arrays (the single env's rows are its live data)."""
        return None

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        """The observations ``[R, obs_dim]`` of the rows' states."""
        raise NotImplementedError

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """After the physics: ``(obs [R, obs_dim], reward [R], terminated [R] bool, infos)``,
        each info an ``[R, ...]`` array; ``actions`` are the checked actions ``[R, act_dim]``."""
        raise NotImplementedError

    def step(self, action: Any) -> tuple[np.ndarray, Any, bool, bool, dict[str, Any]]:
        """Apply ``action`` for ``frame_skip`` MuJoCo steps (the row maths on this env's row)."""
        action = self._check_action(action)
        rows = self._rows
        before = self.rows_before(rows)
        self.do_simulation(action, self.frame_skip)
        obs, reward, terminated, infos = self.rows_step(rows, before, action[None])
        info = {key: value[0] for key, value in infos.items()}
        for key, kind in self.python_infos.items():
            info[key] = kind(info[key])
        r = reward[0] if self.python_reward is None else self.python_reward(reward[0])
        return obs[0], r, bool(terminated[0]), False, self._add_warnings(info)

    def _get_obs(self) -> np.ndarray:
        return self.rows_obs(self._rows)[0]

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        del state["_mujoco"]  # a module: imported again by the copy
        del state["_warning_counts"], state["_rows"], state["_ctrl"]  # views of its MjData
        state.pop("_window", None)  # a human window stays with the original
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._mujoco = import_mujoco()
        self._bind_views()

    def _frame(self) -> Any:
        mode = str(self.render_mode)  # render() calls this only with a mode
        if mode in ("human", "rgb_array_list"):  # the window and the list take rgb frames
            mode = "rgb_array"
        return self._renderer.render(self.model, self.data, mode)

    def close(self) -> None:
        """Free the renderer's OpenGL resources and close the human window, if any."""
        self._renderer.close()
        super().close()

    @property
    def dt(self) -> float:
        """Seconds of simulated time per ``step``: the model's timestep times ``frame_skip``."""
        return float(self.model.opt.timestep * self.frame_skip)

    def _check_action(self, action: Any) -> np.ndarray:
        # A float action keeps its dtype: the control costs square it as Gymnasium does (a
        # float32 action's cost is a float32 sum).
        return box_action(action, self.action_space, keep_float_dtype=True)

    def do_simulation(self, ctrl: np.ndarray, n_frames: int) -> None:
        """Write ``ctrl`` and advance ``n_frames`` MuJoCo steps; MuJoCo's warnings of those
        steps are raised as :class:`MujocoWarning` and kept in ``self._step_warnings``."""
        mujoco, data = self._mujoco, self.data
        # MuJoCo's warning counters as one array (reading them struct by struct cost more than
        # HalfCheetah's physics); they only grow, so equal bytes mean no new warning.
        counts = self._warning_counts
        before = counts.tobytes()
        self._ctrl[:] = ctrl
        mujoco.mj_step(self.model, data, nstep=n_frames)
        # cfrc_ext and friends are only computed on request (no force sensors in the models)
        mujoco.mj_rnePostConstraint(self.model, data)
        if counts.tobytes() == before:
            self._step_warnings = []
        else:
            self._step_warnings = warning_names(counts, np.frombuffer(before, counts.dtype))
            warn_unstable(type(self).__name__, self._step_warnings, data.time, stacklevel=4)
        if self.render_mode == "human":  # every step calls this once: Gymnasium's step's frame
            self.render()

    def _add_warnings(self, info: dict[str, Any]) -> dict[str, Any]:
        """``info`` with ``"mujoco_warnings"`` when MuJoCo flagged this step."""
        if self._step_warnings:
            info["mujoco_warnings"] = list(self._step_warnings)
        return info

    def set_state(self, qpos: np.ndarray, qvel: np.ndarray) -> None:
        """Set joint positions and velocities and recompute what follows from them."""
        qpos, qvel = np.asarray(qpos), np.asarray(qvel)
        if qpos.shape != (self.model.nq,) or qvel.shape != (self.model.nv,):
            raise ValueError(
                f"set_state expects qpos of shape {(self.model.nq,)} and qvel of shape "
                f"{(self.model.nv,)}, got {qpos.shape} and {qvel.shape}"
            )
        self.data.qpos[:] = qpos
        self.data.qvel[:] = qvel
        self._mujoco.mj_forward(self.model, self.data)

    def state_vector(self) -> np.ndarray:
        """``qpos`` then ``qvel``, one float64 vector."""
        return np.concatenate([self.data.qpos.flat, self.data.qvel.flat])

    def get_body_com(self, body_name: str) -> np.ndarray:
        """The world position of the body's frame (a view into ``data.xpos``)."""
        return self.data.body(body_name).xpos

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Back to the model's initial state plus the env's reset noise."""
        super().reset(seed=seed)
        self._mujoco.mj_resetData(self.model, self.data)
        self._step_warnings = []
        observation = self.reset_model()
        info = self._get_reset_info()
        if self.render_mode == "human":
            self.render()
        return observation, info

    def reset_model(self) -> np.ndarray:
        """Put the noisy start state into ``data``; return the first observation."""
        raise NotImplementedError

    def _get_reset_info(self) -> dict[str, Any]:
        return {}

    def _uniform_noise(self, size: int) -> np.ndarray:
        scale = self._reset_noise_scale
        return self.np_random.uniform(low=-scale, high=scale, size=size)

    def _noisy_reset(self, normal_qvel: bool) -> None:
        """``init_qpos`` plus uniform noise, ``init_qvel`` plus uniform or scaled normal noise."""
        qpos = self.init_qpos + self._uniform_noise(self.model.nq)
        if normal_qvel:
            qvel = self.init_qvel + self._reset_noise_scale * self.np_random.standard_normal(
                self.model.nv
            )
        else:
            qvel = self.init_qvel + self._uniform_noise(self.model.nv)
        self.set_state(qpos, qvel)

    _reset_noise_scale: float


def check_flags(**flags: Any) -> list[bool]:
    """Each keyword a bool (``check_bool``), in order."""
    return [check_bool(name, value) for name, value in flags.items()]
