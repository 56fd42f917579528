"""The MuJoCo robots that move about: HalfCheetah, Hopper, Walker2d, Swimmer, Ant, Humanoid and
HumanoidStandup (v5).

Rewards, terminations, observations and reset noise follow Gymnasium 1.4.0's v5 envs, with
the float operations in the same order and on the same dtypes (a float32 action's control
cost is a float32 sum, as there), so rewards and infos are the same bits.
"""

from __future__ import annotations

import os
from typing import Any, ClassVar

import numpy as np

from palaestra.envs.mujoco._base import (
    DEFAULT_CAMERA,
    MujocoEnv,
    check_flags,
    check_range,
    check_weights,
)

__all__ = [
    "AntEnv",
    "HalfCheetahEnv",
    "HopperEnv",
    "HumanoidEnv",
    "HumanoidStandupEnv",
    "SwimmerEnv",
    "Walker2dEnv",
]

_INF = float("inf")


def _x_reward_info(forward_reward: Any, ctrl_cost: Any) -> dict[str, Any]:
    return {"reward_forward": forward_reward, "reward_ctrl": -ctrl_cost}


def _ctrl_costs(weight: float, actions: np.ndarray) -> np.ndarray:
    """``weight`` times each row's sum of squared actions (a float32 row sums in float32)."""
    return weight * np.square(actions).sum(axis=1)  # the method: np.sum's wrapper costs more


def _x_progress(env: MujocoEnv, rows: dict[str, np.ndarray], before: np.ndarray) -> Any:
    """Each row's x position after the step, its x velocity and the forward reward."""
    x_after = rows["qpos"][:, 0]
    x_velocity = (x_after - before) / env.dt
    return x_after, x_velocity, env._forward_reward_weight * x_velocity  # type: ignore[attr-defined]


def _qpos_x_before(rows: dict[str, np.ndarray]) -> np.ndarray:
    return rows["qpos"][:, 0].copy()


class HalfCheetahEnv(MujocoEnv):
    """A planar cat-like robot rewarded for running forward (+x) with little control effort."""

    default_camera = {"distance": 4.0}

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "half_cheetah.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        forward_reward_weight: float = 1.0,
        ctrl_cost_weight: float = 0.1,
        reset_noise_scale: float = 0.1,
        exclude_current_positions_from_observation: bool = True,
        **kwargs: Any,
    ) -> None:
        self._forward_reward_weight, self._ctrl_cost_weight, self._reset_noise_scale = (
            check_weights(
                forward_reward_weight=forward_reward_weight,
                ctrl_cost_weight=ctrl_cost_weight,
                reset_noise_scale=reset_noise_scale,
            )
        )
        (self._exclude_current_positions_from_observation,) = check_flags(
            exclude_current_positions_from_observation=exclude_current_positions_from_observation
        )
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        skipped = int(self._exclude_current_positions_from_observation)
        self.observation_structure = {
            "skipped_qpos": skipped,
            "qpos": self.data.qpos.size - skipped,
            "qvel": self.data.qvel.size,
        }
        self.observation_space = self._float_box(
            self.data.qpos.size + self.data.qvel.size - skipped
        )

    before_fields = ("qpos",)

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared actions."""
        return _ctrl_costs(self._ctrl_cost_weight, np.asarray(action)[None])[0]

    def rows_before(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        return _qpos_x_before(rows)

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        x_after, x_velocity, forward_reward = _x_progress(self, rows, before)
        ctrl_cost = _ctrl_costs(self._ctrl_cost_weight, actions)
        reward = forward_reward - ctrl_cost
        info = {
            "x_position": x_after,
            "x_velocity": x_velocity,
            **_x_reward_info(forward_reward, ctrl_cost),
        }
        return self.rows_obs(rows), reward, np.zeros(len(reward), bool), info

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        skipped = int(self._exclude_current_positions_from_observation)
        return np.concatenate((rows["qpos"][:, skipped:], rows["qvel"]), axis=1)

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=True)
        return self._get_obs()

    def _get_reset_info(self) -> dict[str, Any]:
        return {"x_position": self.data.qpos[0]}


class _PlanarWalker(MujocoEnv):
    """Hopper and Walker2d: forward progress plus a survival bonus while healthy."""

    def __init__(
        self,
        xml_file: str | os.PathLike[str],
        frame_skip: int,
        default_camera_config: dict[str, Any] | None,
        forward_reward_weight: float,
        ctrl_cost_weight: float,
        healthy_reward: float,
        terminate_when_unhealthy: bool,
        healthy_z_range: tuple[float, float],
        healthy_angle_range: tuple[float, float],
        reset_noise_scale: float,
        exclude_current_positions_from_observation: bool,
        **kwargs: Any,
    ) -> None:
        (
            self._forward_reward_weight,
            self._ctrl_cost_weight,
            self._healthy_reward,
            self._reset_noise_scale,
        ) = check_weights(
            forward_reward_weight=forward_reward_weight,
            ctrl_cost_weight=ctrl_cost_weight,
            healthy_reward=healthy_reward,
            reset_noise_scale=reset_noise_scale,
        )
        self._terminate_when_unhealthy, self._exclude_current_positions_from_observation = (
            check_flags(
                terminate_when_unhealthy=terminate_when_unhealthy,
                exclude_current_positions_from_observation=exclude_current_positions_from_observation,
            )
        )
        self._healthy_z_range = check_range("healthy_z_range", healthy_z_range)
        self._healthy_angle_range = check_range("healthy_angle_range", healthy_angle_range)
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        skipped = int(self._exclude_current_positions_from_observation)
        self.observation_structure = {
            "skipped_qpos": skipped,
            "qpos": self.data.qpos.size - skipped,
            "qvel": self.data.qvel.size,
        }
        self.observation_space = self._float_box(
            self.data.qpos.size + self.data.qvel.size - skipped
        )

    before_fields = ("qpos",)

    def rows_healthy(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        """Whether each row is upright: height and torso angle (and for Hopper, the state)
        inside their ranges."""
        raise NotImplementedError

    @property
    def is_healthy(self) -> bool:
        """Whether the robot is upright (:meth:`rows_healthy` of this env's state)."""
        return bool(self.rows_healthy(self._rows)[0])

    @property
    def healthy_reward(self) -> float:
        """``healthy_reward`` while healthy, else 0."""
        return self.is_healthy * self._healthy_reward

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared actions."""
        return _ctrl_costs(self._ctrl_cost_weight, np.asarray(action)[None])[0]

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        skipped = int(self._exclude_current_positions_from_observation)
        velocity = np.clip(rows["qvel"], -10, 10)
        return np.concatenate((rows["qpos"][:, skipped:], velocity), axis=1)

    def rows_before(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        return _qpos_x_before(rows)

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        x_after, x_velocity, forward_reward = _x_progress(self, rows, before)
        observation = self.rows_obs(rows)
        healthy = self.rows_healthy(rows)
        healthy_reward = healthy * self._healthy_reward
        ctrl_cost = _ctrl_costs(self._ctrl_cost_weight, actions)
        reward = (forward_reward + healthy_reward) - ctrl_cost
        terminated = ~healthy & self._terminate_when_unhealthy
        info = {
            "x_position": x_after,
            "z_distance_from_origin": rows["qpos"][:, 1] - self.init_qpos[1],
            "x_velocity": x_velocity,
            **_x_reward_info(forward_reward, ctrl_cost),
            "reward_survive": healthy_reward,
        }
        return observation, reward, terminated, info

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=False)
        return self._get_obs()

    def _get_reset_info(self) -> dict[str, Any]:
        return {
            "x_position": self.data.qpos[0],
            "z_distance_from_origin": self.data.qpos[1] - self.init_qpos[1],
        }


class HopperEnv(_PlanarWalker):
    """A one-legged planar robot rewarded for hopping forward without falling."""

    default_camera = {
        "trackbodyid": 2,
        "distance": 3.0,
        "lookat": np.array((0.0, 0.0, 1.15)),
        "elevation": -20.0,
    }

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "hopper.xml",
        frame_skip: int = 4,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        forward_reward_weight: float = 1.0,
        ctrl_cost_weight: float = 1e-3,
        healthy_reward: float = 1.0,
        terminate_when_unhealthy: bool = True,
        healthy_state_range: tuple[float, float] = (-100.0, 100.0),
        healthy_z_range: tuple[float, float] = (0.7, _INF),
        healthy_angle_range: tuple[float, float] = (-0.2, 0.2),
        reset_noise_scale: float = 5e-3,
        exclude_current_positions_from_observation: bool = True,
        **kwargs: Any,
    ) -> None:
        self._healthy_state_range = check_range("healthy_state_range", healthy_state_range)
        super().__init__(
            xml_file,
            frame_skip,
            default_camera_config,
            forward_reward_weight,
            ctrl_cost_weight,
            healthy_reward,
            terminate_when_unhealthy,
            healthy_z_range,
            healthy_angle_range,
            reset_noise_scale,
            exclude_current_positions_from_observation,
            **kwargs,
        )

    python_infos = {"reward_survive": float}  # Gymnasium's is a bool times a float

    def rows_healthy(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        """Height, torso angle and every other state component inside their ranges."""
        qpos = rows["qpos"]
        z, angle = qpos[:, 1], qpos[:, 2]
        state = np.concatenate((qpos[:, 2:], rows["qvel"]), axis=1)
        low_state, high_state = self._healthy_state_range
        low_z, high_z = self._healthy_z_range
        low_angle, high_angle = self._healthy_angle_range
        return (
            np.all((low_state < state) & (state < high_state), axis=1)
            & ((low_z < z) & (z < high_z))
            & ((low_angle < angle) & (angle < high_angle))
        )


class Walker2dEnv(_PlanarWalker):
    """A two-legged planar robot rewarded for walking forward without falling."""

    default_camera = {
        "trackbodyid": 2,
        "distance": 4.0,
        "lookat": np.array((0.0, 0.0, 1.15)),
        "elevation": -20.0,
    }

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "walker2d_v5.xml",
        frame_skip: int = 4,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        forward_reward_weight: float = 1.0,
        ctrl_cost_weight: float = 1e-3,
        healthy_reward: float = 1.0,
        terminate_when_unhealthy: bool = True,
        healthy_z_range: tuple[float, float] = (0.8, 2.0),
        healthy_angle_range: tuple[float, float] = (-1.0, 1.0),
        reset_noise_scale: float = 5e-3,
        exclude_current_positions_from_observation: bool = True,
        **kwargs: Any,
    ) -> None:
        super().__init__(
            xml_file,
            frame_skip,
            default_camera_config,
            forward_reward_weight,
            ctrl_cost_weight,
            healthy_reward,
            terminate_when_unhealthy,
            healthy_z_range,
            healthy_angle_range,
            reset_noise_scale,
            exclude_current_positions_from_observation,
            **kwargs,
        )

    def rows_healthy(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        """Height and torso angle inside their ranges."""
        qpos = rows["qpos"]
        z, angle = qpos[:, 1], qpos[:, 2]
        low_z, high_z = self._healthy_z_range
        low_angle, high_angle = self._healthy_angle_range
        return ((low_z < z) & (z < high_z)) & ((low_angle < angle) & (angle < high_angle))


def _xy_info(qpos: np.ndarray) -> dict[str, Any]:
    """Positions and distance from the origin of each row (``qpos`` is ``[R, nq]``)."""
    return {
        "x_position": qpos[:, 0],
        "y_position": qpos[:, 1],
        "distance_from_origin": np.linalg.norm(qpos[:, 0:2], ord=2, axis=1),
    }


def _xy_velocities(env: MujocoEnv, xy_after: np.ndarray, before: np.ndarray) -> Any:
    velocity = (xy_after - before) / env.dt
    return velocity[:, 0], velocity[:, 1]


class SwimmerEnv(MujocoEnv):
    """A three-link robot in a viscous fluid, rewarded for swimming forward (+x)."""

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "swimmer.xml",
        frame_skip: int = 4,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        forward_reward_weight: float = 1.0,
        ctrl_cost_weight: float = 1e-4,
        reset_noise_scale: float = 0.1,
        exclude_current_positions_from_observation: bool = True,
        **kwargs: Any,
    ) -> None:
        self._forward_reward_weight, self._ctrl_cost_weight, self._reset_noise_scale = (
            check_weights(
                forward_reward_weight=forward_reward_weight,
                ctrl_cost_weight=ctrl_cost_weight,
                reset_noise_scale=reset_noise_scale,
            )
        )
        (self._exclude_current_positions_from_observation,) = check_flags(
            exclude_current_positions_from_observation=exclude_current_positions_from_observation
        )
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        skipped = 2 * int(self._exclude_current_positions_from_observation)
        self.observation_structure = {
            "skipped_qpos": skipped,
            "qpos": self.data.qpos.size - skipped,
            "qvel": self.data.qvel.size,
        }
        self.observation_space = self._float_box(
            self.data.qpos.size + self.data.qvel.size - skipped
        )

    before_fields = ("qpos",)

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared actions."""
        return _ctrl_costs(self._ctrl_cost_weight, np.asarray(action)[None])[0]

    def rows_before(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        return rows["qpos"][:, 0:2].copy()

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        qpos = rows["qpos"]
        x_velocity, y_velocity = _xy_velocities(self, qpos[:, 0:2], before)
        forward_reward = self._forward_reward_weight * x_velocity
        ctrl_cost = _ctrl_costs(self._ctrl_cost_weight, actions)
        reward = forward_reward - ctrl_cost
        info = {
            **_xy_info(qpos),
            "x_velocity": x_velocity,
            "y_velocity": y_velocity,
            **_x_reward_info(forward_reward, ctrl_cost),
        }
        return self.rows_obs(rows), reward, np.zeros(len(reward), bool), info

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        skipped = 2 * int(self._exclude_current_positions_from_observation)
        return np.concatenate((rows["qpos"][:, skipped:], rows["qvel"]), axis=1)

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=False)
        return self._get_obs()

    def _get_reset_info(self) -> dict[str, Any]:
        return {key: value[0] for key, value in _xy_info(self._rows["qpos"]).items()}


class AntEnv(MujocoEnv):
    """A four-legged 3D robot rewarded for moving forward (+x) while its torso stays up."""

    default_camera = {"distance": 4.0}

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "ant.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        forward_reward_weight: float = 1,
        ctrl_cost_weight: float = 0.5,
        contact_cost_weight: float = 5e-4,
        healthy_reward: float = 1.0,
        main_body: int | str = 1,
        terminate_when_unhealthy: bool = True,
        healthy_z_range: tuple[float, float] = (0.2, 1.0),
        contact_force_range: tuple[float, float] = (-1.0, 1.0),
        reset_noise_scale: float = 0.1,
        exclude_current_positions_from_observation: bool = True,
        include_cfrc_ext_in_observation: bool = True,
        **kwargs: Any,
    ) -> None:
        (
            self._forward_reward_weight,
            self._ctrl_cost_weight,
            self._contact_cost_weight,
            self._healthy_reward,
            self._reset_noise_scale,
        ) = check_weights(
            forward_reward_weight=forward_reward_weight,
            ctrl_cost_weight=ctrl_cost_weight,
            contact_cost_weight=contact_cost_weight,
            healthy_reward=healthy_reward,
            reset_noise_scale=reset_noise_scale,
        )
        (
            self._terminate_when_unhealthy,
            self._exclude_current_positions_from_observation,
            self._include_cfrc_ext_in_observation,
        ) = check_flags(
            terminate_when_unhealthy=terminate_when_unhealthy,
            exclude_current_positions_from_observation=exclude_current_positions_from_observation,
            include_cfrc_ext_in_observation=include_cfrc_ext_in_observation,
        )
        self._healthy_z_range = check_range("healthy_z_range", healthy_z_range)
        self._contact_force_range = check_range("contact_force_range", contact_force_range)
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self._main_body = _check_body(self, main_body)
        self._main_body_id = self.data.body(main_body).id
        skipped = 2 * int(self._exclude_current_positions_from_observation)
        cfrc = self.data.cfrc_ext[1:].size * int(self._include_cfrc_ext_in_observation)
        self.observation_structure = {
            "skipped_qpos": skipped,
            "qpos": self.data.qpos.size - skipped,
            "qvel": self.data.qvel.size,
            "cfrc_ext": cfrc,
        }
        self.observation_space = self._float_box(
            self.data.qpos.size + self.data.qvel.size - skipped + cfrc
        )

    row_fields = ("qpos", "qvel", "xpos", "cfrc_ext")
    before_fields = ("xpos",)

    def rows_healthy(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        """A finite state with the torso's height inside ``healthy_z_range``, per row."""
        state = np.concatenate((rows["qpos"], rows["qvel"]), axis=1)
        low_z, high_z = self._healthy_z_range
        return np.isfinite(state).all(axis=1) & ((low_z <= state[:, 2]) & (state[:, 2] <= high_z))

    @property
    def is_healthy(self) -> bool:
        """A finite state with the torso's height inside ``healthy_z_range``."""
        return bool(self.rows_healthy(self._rows)[0])

    @property
    def healthy_reward(self) -> Any:
        """``healthy_reward`` while healthy, else 0."""
        return self.is_healthy * self._healthy_reward

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared actions."""
        return _ctrl_costs(self._ctrl_cost_weight, np.asarray(action)[None])[0]

    def rows_contact_forces(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        """The bodies' external forces (``cfrc_ext``, ``[R, nbody, 6]``), clipped to
        ``contact_force_range``."""
        low, high = self._contact_force_range
        return np.clip(rows["cfrc_ext"], low, high)

    @property
    def contact_forces(self) -> np.ndarray:
        """The bodies' external forces (``cfrc_ext``), clipped to ``contact_force_range``."""
        return self.rows_contact_forces(self._rows)[0]

    @property
    def contact_cost(self) -> Any:
        """``contact_cost_weight`` times the sum of squared clipped contact forces."""
        return _square_sums(self._contact_cost_weight, self.rows_contact_forces(self._rows))[0]

    def rows_before(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        return rows["xpos"][:, self._main_body_id, :2].copy()

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        xy_after = rows["xpos"][:, self._main_body_id, :2]
        x_velocity, y_velocity = _xy_velocities(self, xy_after, before)
        forces = self.rows_contact_forces(rows)
        observation = self._obs_of(rows, forces)
        forward_reward = x_velocity * self._forward_reward_weight
        healthy = self.rows_healthy(rows)
        healthy_reward = healthy * self._healthy_reward
        ctrl_cost = _ctrl_costs(self._ctrl_cost_weight, actions)
        contact_cost = _square_sums(self._contact_cost_weight, forces)
        reward = (forward_reward + healthy_reward) - (ctrl_cost + contact_cost)
        terminated = ~healthy & self._terminate_when_unhealthy
        info = {
            **_xy_info(rows["qpos"]),
            "x_velocity": x_velocity,
            "y_velocity": y_velocity,
            **_x_reward_info(forward_reward, ctrl_cost),
            "reward_contact": -contact_cost,
            "reward_survive": healthy_reward,
        }
        return observation, reward, terminated, info

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        return self._obs_of(rows, self.rows_contact_forces(rows))

    def _obs_of(self, rows: dict[str, np.ndarray], forces: np.ndarray) -> np.ndarray:
        skipped = 2 * int(self._exclude_current_positions_from_observation)
        parts = [rows["qpos"][:, skipped:], rows["qvel"]]
        if self._include_cfrc_ext_in_observation:
            parts.append(forces[:, 1:].reshape(len(forces), -1))
        return np.concatenate(parts, axis=1)

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=True)
        return self._get_obs()

    def _get_reset_info(self) -> dict[str, Any]:
        return {key: value[0] for key, value in _xy_info(self._rows["qpos"]).items()}


def _check_body(env: MujocoEnv, body: Any) -> int | str:
    """A body of ``env``'s model given by id or name, else ``ValueError`` naming it."""
    try:
        env.data.body(body)
    except (KeyError, IndexError, TypeError) as e:
        names = [env.model.body(i).name for i in range(env.model.nbody)]
        raise ValueError(
            f"main_body {body!r} is not a body of {env.fullpath!r}: expected an id in "
            f"[0, {env.model.nbody}) or one of {names}"
        ) from e
    return body


def _square_sums(weight: float, arrays: np.ndarray) -> np.ndarray:
    """``weight`` times the sum of squares of each row's array (``[R, ...]``)."""
    return weight * np.square(arrays).reshape(len(arrays), -1).sum(axis=1)


def mass_centers(body_mass: np.ndarray, xipos: np.ndarray) -> np.ndarray:
    """The (x, y) of each row's centre of mass (``xipos`` is ``[R, nbody, 3]``)."""
    total = np.einsum("b,rbj->rj", body_mass, xipos)
    return (total / body_mass.sum())[:, 0:2]


def mass_center(model: Any, data: Any) -> np.ndarray:
    """The (x, y) of the model's centre of mass."""
    return mass_centers(model.body_mass, data.xipos[None])[0]


class _Humanoid(MujocoEnv):
    """Humanoid and HumanoidStandup: one body, the same observation and reset noise."""

    def _humanoid_init(
        self,
        exclude_current_positions_from_observation: bool,
        include_cinert_in_observation: bool,
        include_cvel_in_observation: bool,
        include_qfrc_actuator_in_observation: bool,
        include_cfrc_ext_in_observation: bool,
    ) -> None:
        (
            self._exclude_current_positions_from_observation,
            self._include_cinert_in_observation,
            self._include_cvel_in_observation,
            self._include_qfrc_actuator_in_observation,
            self._include_cfrc_ext_in_observation,
        ) = check_flags(
            exclude_current_positions_from_observation=exclude_current_positions_from_observation,
            include_cinert_in_observation=include_cinert_in_observation,
            include_cvel_in_observation=include_cvel_in_observation,
            include_qfrc_actuator_in_observation=include_qfrc_actuator_in_observation,
            include_cfrc_ext_in_observation=include_cfrc_ext_in_observation,
        )

    def _set_observation_space(self) -> None:
        data = self.data
        structure = {
            "skipped_qpos": 2 * int(self._exclude_current_positions_from_observation),
            "qpos": data.qpos.size - 2 * int(self._exclude_current_positions_from_observation),
            "qvel": data.qvel.size,
            "cinert": data.cinert[1:].size * int(self._include_cinert_in_observation),
            "cvel": data.cvel[1:].size * int(self._include_cvel_in_observation),
            "qfrc_actuator": (data.qvel.size - 6) * int(self._include_qfrc_actuator_in_observation),
            "cfrc_ext": data.cfrc_ext[1:].size * int(self._include_cfrc_ext_in_observation),
            "ten_length": 0,
            "ten_velocity": 0,
        }
        self.observation_structure = structure
        size = sum(n for key, n in structure.items() if key != "skipped_qpos")
        self.observation_space = self._float_box(size)

    row_fields: ClassVar[tuple[str, ...]] = (
        "qpos",
        "qvel",
        "cinert",
        "cvel",
        "qfrc_actuator",
        "cfrc_ext",
        "ctrl",
        "ten_length",
        "ten_velocity",
    )

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        n = len(rows["qpos"])
        skipped = 2 * int(self._exclude_current_positions_from_observation)
        parts = [rows["qpos"][:, skipped:], rows["qvel"]]
        if self._include_cinert_in_observation:
            parts.append(rows["cinert"][:, 1:].reshape(n, -1))
        if self._include_cvel_in_observation:
            parts.append(rows["cvel"][:, 1:].reshape(n, -1))
        if self._include_qfrc_actuator_in_observation:
            parts.append(rows["qfrc_actuator"][:, 6:])
        if self._include_cfrc_ext_in_observation:
            parts.append(rows["cfrc_ext"][:, 1:].reshape(n, -1))
        return np.concatenate(parts, axis=1)

    @staticmethod
    def _tendon_info(rows: dict[str, np.ndarray]) -> dict[str, Any]:
        return {
            "tendon_length": rows["ten_length"].copy(),
            "tendon_velocity": rows["ten_velocity"].copy(),
        }

    def _positions_info(self, rows: dict[str, np.ndarray]) -> dict[str, Any]:
        """Humanoid's reset info, per row (and the start of its step info)."""
        qpos = rows["qpos"]
        return {
            "x_position": qpos[:, 0],
            "y_position": qpos[:, 1],
            **self._tendon_info(rows),
            "distance_from_origin": np.linalg.norm(qpos[:, 0:2], ord=2, axis=1),
        }

    def _get_reset_info(self) -> dict[str, Any]:
        return {key: value[0] for key, value in self._positions_info(self._rows).items()}

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=False)
        return self._get_obs()


class HumanoidEnv(_Humanoid):
    """A 3D two-legged robot rewarded for walking forward (+x) without falling."""

    default_camera = {
        "trackbodyid": 1,
        "distance": 4.0,
        "lookat": np.array((0.0, 0.0, 2.0)),
        "elevation": -20.0,
    }

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "humanoid.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        forward_reward_weight: float = 1.25,
        ctrl_cost_weight: float = 0.1,
        contact_cost_weight: float = 5e-7,
        contact_cost_range: tuple[float, float] = (-_INF, 10.0),
        healthy_reward: float = 5.0,
        terminate_when_unhealthy: bool = True,
        healthy_z_range: tuple[float, float] = (1.0, 2.0),
        reset_noise_scale: float = 1e-2,
        exclude_current_positions_from_observation: bool = True,
        include_cinert_in_observation: bool = True,
        include_cvel_in_observation: bool = True,
        include_qfrc_actuator_in_observation: bool = True,
        include_cfrc_ext_in_observation: bool = True,
        **kwargs: Any,
    ) -> None:
        (
            self._forward_reward_weight,
            self._ctrl_cost_weight,
            self._contact_cost_weight,
            self._healthy_reward,
            self._reset_noise_scale,
        ) = check_weights(
            forward_reward_weight=forward_reward_weight,
            ctrl_cost_weight=ctrl_cost_weight,
            contact_cost_weight=contact_cost_weight,
            healthy_reward=healthy_reward,
            reset_noise_scale=reset_noise_scale,
        )
        self._contact_cost_range = check_range("contact_cost_range", contact_cost_range)
        self._healthy_z_range = check_range("healthy_z_range", healthy_z_range)
        (self._terminate_when_unhealthy,) = check_flags(
            terminate_when_unhealthy=terminate_when_unhealthy
        )
        self._humanoid_init(
            exclude_current_positions_from_observation,
            include_cinert_in_observation,
            include_cvel_in_observation,
            include_qfrc_actuator_in_observation,
            include_cfrc_ext_in_observation,
        )
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self._set_observation_space()

    row_fields: ClassVar[tuple[str, ...]] = (*_Humanoid.row_fields, "xipos")
    before_fields = ("xipos",)

    def rows_healthy(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        """The torso's height inside ``healthy_z_range``, per row."""
        low_z, high_z = self._healthy_z_range
        z = rows["qpos"][:, 2]
        return (low_z < z) & (z < high_z)

    @property
    def is_healthy(self) -> bool:
        """The torso's height inside ``healthy_z_range``."""
        return bool(self.rows_healthy(self._rows)[0])

    @property
    def healthy_reward(self) -> Any:
        """``healthy_reward`` while healthy, else 0."""
        return self.is_healthy * self._healthy_reward

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared controls (``data.ctrl``, float64)."""
        return _ctrl_costs(self._ctrl_cost_weight, self._rows["ctrl"])[0]

    def rows_contact_cost(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        """``contact_cost_weight`` times the sum of squared ``cfrc_ext``, clipped to
        ``contact_cost_range``, per row."""
        low, high = self._contact_cost_range
        return np.clip(_square_sums(self._contact_cost_weight, rows["cfrc_ext"]), low, high)

    @property
    def contact_cost(self) -> Any:
        """``contact_cost_weight`` times the sum of squared ``cfrc_ext``, clipped to
        ``contact_cost_range``."""
        return self.rows_contact_cost(self._rows)[0]

    def rows_before(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        return mass_centers(self.model.body_mass, rows["xipos"])

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        xy_after = mass_centers(self.model.body_mass, rows["xipos"])
        x_velocity, y_velocity = _xy_velocities(self, xy_after, before)
        observation = self.rows_obs(rows)
        forward_reward = self._forward_reward_weight * x_velocity
        healthy = self.rows_healthy(rows)
        healthy_reward = healthy * self._healthy_reward
        ctrl_cost = _ctrl_costs(self._ctrl_cost_weight, rows["ctrl"])
        contact_cost = self.rows_contact_cost(rows)
        reward = (forward_reward + healthy_reward) - (ctrl_cost + contact_cost)
        terminated = ~healthy & self._terminate_when_unhealthy
        info = {
            **self._positions_info(rows),
            "x_velocity": x_velocity,
            "y_velocity": y_velocity,
            "reward_survive": healthy_reward,
            **_x_reward_info(forward_reward, ctrl_cost),
            "reward_contact": -contact_cost,
        }
        return observation, reward, terminated, info


class HumanoidStandupEnv(_Humanoid):
    """The humanoid lying on its back, rewarded for raising its torso (height per timestep)."""

    default_camera = {
        "trackbodyid": 1,
        "distance": 4.0,
        "lookat": np.array((0.0, 0.0, 0.8925)),
        "elevation": -20.0,
    }

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "humanoidstandup.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        uph_cost_weight: float = 1,
        ctrl_cost_weight: float = 0.1,
        impact_cost_weight: float = 0.5e-6,
        impact_cost_range: tuple[float, float] = (-_INF, 10.0),
        reset_noise_scale: float = 1e-2,
        exclude_current_positions_from_observation: bool = True,
        include_cinert_in_observation: bool = True,
        include_cvel_in_observation: bool = True,
        include_qfrc_actuator_in_observation: bool = True,
        include_cfrc_ext_in_observation: bool = True,
        **kwargs: Any,
    ) -> None:
        # uph_cost_weight is accepted and stored, but Gymnasium 1.4.0's reward does not use it
        (
            self._uph_cost_weight,
            self._ctrl_cost_weight,
            self._impact_cost_weight,
            self._reset_noise_scale,
        ) = check_weights(
            uph_cost_weight=uph_cost_weight,
            ctrl_cost_weight=ctrl_cost_weight,
            impact_cost_weight=impact_cost_weight,
            reset_noise_scale=reset_noise_scale,
        )
        self._impact_cost_range = check_range("impact_cost_range", impact_cost_range)
        self._humanoid_init(
            exclude_current_positions_from_observation,
            include_cinert_in_observation,
            include_cvel_in_observation,
            include_qfrc_actuator_in_observation,
            include_cfrc_ext_in_observation,
        )
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self._set_observation_space()

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        height = rows["qpos"][:, 2]
        uph_cost = (height - 0) / self.model.opt.timestep
        quad_ctrl_cost = _ctrl_costs(self._ctrl_cost_weight, rows["ctrl"])
        low, high = self._impact_cost_range
        quad_impact_cost = np.clip(
            _square_sums(self._impact_cost_weight, rows["cfrc_ext"]), low, high
        )
        reward = uph_cost - quad_ctrl_cost - quad_impact_cost + 1
        info = {
            **self._positions_info(rows),
            "reward_linup": uph_cost,
            "reward_quadctrl": -quad_ctrl_cost,
            "reward_impact": -quad_impact_cost,
        }
        return self.rows_obs(rows), reward, np.zeros(len(reward), bool), info

    def _positions_info(self, rows: dict[str, np.ndarray]) -> dict[str, Any]:
        qpos = rows["qpos"]
        return {
            "x_position": qpos[:, 0],
            "y_position": qpos[:, 1],
            "z_distance_from_origin": qpos[:, 2] - self.init_qpos[2],
            **self._tendon_info(rows),
        }
