"""The MuJoCo robots that move about: HalfCheetah, Hopper, Walker2d, Swimmer, Ant, Humanoid and
HumanoidStandup (v5).

Rewards, terminations, observations and reset noise follow Gymnasium 1.4.0's v5 envs, with
the float operations in the same order and on the same dtypes (a float32 action's control
cost is a float32 sum, as there), so rewards and infos are the same bits.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from palaestra.envs.mujoco._base import (
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


class HalfCheetahEnv(MujocoEnv):
    """A planar cat-like robot rewarded for running forward (+x) with little control effort."""

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "half_cheetah.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = None,
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
        if default_camera_config is None:
            default_camera_config = {"distance": 4.0}
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

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared actions."""
        return self._ctrl_cost_weight * np.sum(np.square(action))

    def step(self, action: Any) -> tuple[np.ndarray, Any, bool, bool, dict[str, Any]]:
        action = self._check_action(action)
        x_before = self.data.qpos[0]
        self.do_simulation(action, self.frame_skip)
        x_after = self.data.qpos[0]
        x_velocity = (x_after - x_before) / self.dt
        forward_reward = self._forward_reward_weight * x_velocity
        ctrl_cost = self.control_cost(action)
        reward = forward_reward - ctrl_cost
        info = {
            "x_position": x_after,
            "x_velocity": x_velocity,
            **_x_reward_info(forward_reward, ctrl_cost),
        }
        return self._get_obs(), reward, False, False, self._add_warnings(info)

    def _get_obs(self) -> np.ndarray:
        position = self.data.qpos.flatten()
        if self._exclude_current_positions_from_observation:
            position = position[1:]
        return np.concatenate((position, self.data.qvel.flatten()))

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

    @property
    def is_healthy(self) -> Any:
        """Whether the robot is upright: height and torso angle (and for Hopper, the state)
        inside their ranges."""
        raise NotImplementedError

    @property
    def healthy_reward(self) -> Any:
        """``healthy_reward`` while healthy, else 0."""
        return self.is_healthy * self._healthy_reward

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared actions."""
        return self._ctrl_cost_weight * np.sum(np.square(action))

    def _get_obs(self) -> np.ndarray:
        position = self.data.qpos.flatten()
        velocity = np.clip(self.data.qvel.flatten(), -10, 10)
        if self._exclude_current_positions_from_observation:
            position = position[1:]
        return np.concatenate((position, velocity))

    def step(self, action: Any) -> tuple[np.ndarray, Any, bool, bool, dict[str, Any]]:
        action = self._check_action(action)
        x_before = self.data.qpos[0]
        self.do_simulation(action, self.frame_skip)
        x_after = self.data.qpos[0]
        x_velocity = (x_after - x_before) / self.dt
        observation = self._get_obs()
        forward_reward = self._forward_reward_weight * x_velocity
        healthy_reward = self.healthy_reward
        ctrl_cost = self.control_cost(action)
        reward = (forward_reward + healthy_reward) - ctrl_cost
        terminated = not self.is_healthy and self._terminate_when_unhealthy
        info = {
            "x_position": x_after,
            "z_distance_from_origin": self.data.qpos[1] - self.init_qpos[1],
            "x_velocity": x_velocity,
            **_x_reward_info(forward_reward, ctrl_cost),
            "reward_survive": healthy_reward,
        }
        return observation, reward, terminated, False, self._add_warnings(info)

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

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "hopper.xml",
        frame_skip: int = 4,
        default_camera_config: dict[str, Any] | None = None,
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
        if default_camera_config is None:
            default_camera_config = {
                "trackbodyid": 2,
                "distance": 3.0,
                "lookat": np.array((0.0, 0.0, 1.15)),
                "elevation": -20.0,
            }
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

    @property
    def is_healthy(self) -> bool:
        """Height, torso angle and every other state component inside their ranges."""
        z, angle = self.data.qpos[1:3]
        state = self.state_vector()[2:]
        low_state, high_state = self._healthy_state_range
        low_z, high_z = self._healthy_z_range
        low_angle, high_angle = self._healthy_angle_range
        return all(
            (
                np.all(np.logical_and(low_state < state, state < high_state)),
                low_z < z < high_z,
                low_angle < angle < high_angle,
            )
        )


class Walker2dEnv(_PlanarWalker):
    """A two-legged planar robot rewarded for walking forward without falling."""

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "walker2d_v5.xml",
        frame_skip: int = 4,
        default_camera_config: dict[str, Any] | None = None,
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
        if default_camera_config is None:
            default_camera_config = {
                "trackbodyid": 2,
                "distance": 4.0,
                "lookat": np.array((0.0, 0.0, 1.15)),
                "elevation": -20.0,
            }
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

    @property
    def is_healthy(self) -> Any:
        """Height and torso angle inside their ranges."""
        z, angle = self.data.qpos[1:3]
        low_z, high_z = self._healthy_z_range
        low_angle, high_angle = self._healthy_angle_range
        return (low_z < z < high_z) and (low_angle < angle < high_angle)


def _xy_info(qpos: np.ndarray) -> dict[str, Any]:
    return {
        "x_position": qpos[0],
        "y_position": qpos[1],
        "distance_from_origin": np.linalg.norm(qpos[0:2], ord=2),
    }


class SwimmerEnv(MujocoEnv):
    """A three-link robot in a viscous fluid, rewarded for swimming forward (+x)."""

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "swimmer.xml",
        frame_skip: int = 4,
        default_camera_config: dict[str, Any] | None = None,
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

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared actions."""
        return self._ctrl_cost_weight * np.sum(np.square(action))

    def step(self, action: Any) -> tuple[np.ndarray, Any, bool, bool, dict[str, Any]]:
        action = self._check_action(action)
        xy_before = self.data.qpos[0:2].copy()
        self.do_simulation(action, self.frame_skip)
        xy_after = self.data.qpos[0:2].copy()
        x_velocity, y_velocity = (xy_after - xy_before) / self.dt
        forward_reward = self._forward_reward_weight * x_velocity
        ctrl_cost = self.control_cost(action)
        reward = forward_reward - ctrl_cost
        info = {
            **_xy_info(xy_after),
            "x_velocity": x_velocity,
            "y_velocity": y_velocity,
            **_x_reward_info(forward_reward, ctrl_cost),
        }
        return self._get_obs(), reward, False, False, self._add_warnings(info)

    def _get_obs(self) -> np.ndarray:
        position = self.data.qpos.flatten()
        if self._exclude_current_positions_from_observation:
            position = position[2:]
        return np.concatenate([position, self.data.qvel.flatten()])

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=False)
        return self._get_obs()

    def _get_reset_info(self) -> dict[str, Any]:
        return _xy_info(self.data.qpos)


class AntEnv(MujocoEnv):
    """A four-legged 3D robot rewarded for moving forward (+x) while its torso stays up."""

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "ant.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = None,
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
        if default_camera_config is None:
            default_camera_config = {"distance": 4.0}
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self._main_body = _check_body(self, main_body)
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

    @property
    def healthy_reward(self) -> Any:
        """``healthy_reward`` while healthy, else 0."""
        return self.is_healthy * self._healthy_reward

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared actions."""
        return self._ctrl_cost_weight * np.sum(np.square(action))

    @property
    def contact_forces(self) -> np.ndarray:
        """The bodies' external forces (``cfrc_ext``), clipped to ``contact_force_range``."""
        low, high = self._contact_force_range
        return np.clip(self.data.cfrc_ext, low, high)

    @property
    def contact_cost(self) -> Any:
        """``contact_cost_weight`` times the sum of squared clipped contact forces."""
        return self._contact_cost_weight * np.sum(np.square(self.contact_forces))

    @property
    def is_healthy(self) -> Any:
        """A finite state with the torso's height inside ``healthy_z_range``."""
        state = self.state_vector()
        low_z, high_z = self._healthy_z_range
        return np.isfinite(state).all() and low_z <= state[2] <= high_z

    def step(self, action: Any) -> tuple[np.ndarray, Any, bool, bool, dict[str, Any]]:
        action = self._check_action(action)
        body = self.data.body(self._main_body)
        xy_before = body.xpos[:2].copy()
        self.do_simulation(action, self.frame_skip)
        xy_after = body.xpos[:2].copy()
        x_velocity, y_velocity = (xy_after - xy_before) / self.dt
        observation = self._get_obs()
        forward_reward = x_velocity * self._forward_reward_weight
        healthy_reward = self.healthy_reward
        ctrl_cost = self.control_cost(action)
        contact_cost = self.contact_cost
        reward = (forward_reward + healthy_reward) - (ctrl_cost + contact_cost)
        terminated = not self.is_healthy and self._terminate_when_unhealthy
        info = {
            **_xy_info(self.data.qpos),
            "x_velocity": x_velocity,
            "y_velocity": y_velocity,
            **_x_reward_info(forward_reward, ctrl_cost),
            "reward_contact": -contact_cost,
            "reward_survive": healthy_reward,
        }
        return observation, reward, terminated, False, self._add_warnings(info)

    def _get_obs(self) -> np.ndarray:
        position = self.data.qpos.flatten()
        if self._exclude_current_positions_from_observation:
            position = position[2:]
        parts = [position, self.data.qvel.flatten()]
        if self._include_cfrc_ext_in_observation:
            parts.append(self.contact_forces[1:].flatten())
        return np.concatenate(parts)

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=True)
        return self._get_obs()

    def _get_reset_info(self) -> dict[str, Any]:
        return _xy_info(self.data.qpos)


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


def mass_center(model: Any, data: Any) -> np.ndarray:
    """The (x, y) of the model's centre of mass."""
    total = np.einsum("b,bj->j", model.body_mass, data.xipos)
    return (total / model.body_mass.sum())[0:2].copy()


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

    def _get_obs(self) -> np.ndarray:
        data = self.data
        position = data.qpos.flatten()
        if self._exclude_current_positions_from_observation:
            position = position[2:]
        parts = [position, data.qvel.flatten()]
        if self._include_cinert_in_observation:
            parts.append(data.cinert[1:].flatten())
        if self._include_cvel_in_observation:
            parts.append(data.cvel[1:].flatten())
        if self._include_qfrc_actuator_in_observation:
            parts.append(data.qfrc_actuator[6:].flatten())
        if self._include_cfrc_ext_in_observation:
            parts.append(data.cfrc_ext[1:].flatten())
        return np.concatenate(parts)

    def _tendon_info(self) -> dict[str, Any]:
        return {
            "tendon_length": self.data.ten_length.copy(),
            "tendon_velocity": self.data.ten_velocity.copy(),
        }

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=False)
        return self._get_obs()


class HumanoidEnv(_Humanoid):
    """A 3D two-legged robot rewarded for walking forward (+x) without falling."""

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "humanoid.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = None,
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
        if default_camera_config is None:
            default_camera_config = {
                "trackbodyid": 1,
                "distance": 4.0,
                "lookat": np.array((0.0, 0.0, 2.0)),
                "elevation": -20.0,
            }
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self._set_observation_space()

    @property
    def healthy_reward(self) -> Any:
        """``healthy_reward`` while healthy, else 0."""
        return self.is_healthy * self._healthy_reward

    def control_cost(self, action: np.ndarray) -> Any:
        """``ctrl_cost_weight`` times the sum of squared controls (``data.ctrl``, float64)."""
        return self._ctrl_cost_weight * np.sum(np.square(self.data.ctrl))

    @property
    def contact_cost(self) -> Any:
        """``contact_cost_weight`` times the sum of squared ``cfrc_ext``, clipped to
        ``contact_cost_range``."""
        cost = self._contact_cost_weight * np.sum(np.square(self.data.cfrc_ext))
        low, high = self._contact_cost_range
        return np.clip(cost, low, high)

    @property
    def is_healthy(self) -> Any:
        """The torso's height inside ``healthy_z_range``."""
        low_z, high_z = self._healthy_z_range
        return low_z < self.data.qpos[2] < high_z

    def step(self, action: Any) -> tuple[np.ndarray, Any, bool, bool, dict[str, Any]]:
        action = self._check_action(action)
        xy_before = mass_center(self.model, self.data)
        self.do_simulation(action, self.frame_skip)
        xy_after = mass_center(self.model, self.data)
        x_velocity, y_velocity = (xy_after - xy_before) / self.dt
        observation = self._get_obs()
        forward_reward = self._forward_reward_weight * x_velocity
        healthy_reward = self.healthy_reward
        ctrl_cost = self.control_cost(action)
        contact_cost = self.contact_cost
        reward = (forward_reward + healthy_reward) - (ctrl_cost + contact_cost)
        terminated = not self.is_healthy and self._terminate_when_unhealthy
        qpos = self.data.qpos
        info = {
            "x_position": qpos[0],
            "y_position": qpos[1],
            **self._tendon_info(),
            "distance_from_origin": np.linalg.norm(qpos[0:2], ord=2),
            "x_velocity": x_velocity,
            "y_velocity": y_velocity,
            "reward_survive": healthy_reward,
            **_x_reward_info(forward_reward, ctrl_cost),
            "reward_contact": -contact_cost,
        }
        return observation, reward, terminated, False, self._add_warnings(info)

    def _get_reset_info(self) -> dict[str, Any]:
        qpos = self.data.qpos
        return {
            "x_position": qpos[0],
            "y_position": qpos[1],
            **self._tendon_info(),
            "distance_from_origin": np.linalg.norm(qpos[0:2], ord=2),
        }


class HumanoidStandupEnv(_Humanoid):
    """The humanoid lying on its back, rewarded for raising its torso (height per timestep)."""

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "humanoidstandup.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = None,
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
        if default_camera_config is None:
            default_camera_config = {
                "trackbodyid": 1,
                "distance": 4.0,
                "lookat": np.array((0.0, 0.0, 0.8925)),
                "elevation": -20.0,
            }
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self._set_observation_space()

    def step(self, action: Any) -> tuple[np.ndarray, Any, bool, bool, dict[str, Any]]:
        action = self._check_action(action)
        self.do_simulation(action, self.frame_skip)
        data = self.data
        height = data.qpos[2]
        uph_cost = (height - 0) / self.model.opt.timestep
        quad_ctrl_cost = self._ctrl_cost_weight * np.square(data.ctrl).sum()
        quad_impact_cost = self._impact_cost_weight * np.square(data.cfrc_ext).sum()
        low, high = self._impact_cost_range
        quad_impact_cost = np.clip(quad_impact_cost, low, high)
        reward = uph_cost - quad_ctrl_cost - quad_impact_cost + 1
        info = {
            **self._get_reset_info(),
            "reward_linup": uph_cost,
            "reward_quadctrl": -quad_ctrl_cost,
            "reward_impact": -quad_impact_cost,
        }
        return self._get_obs(), reward, False, False, self._add_warnings(info)

    def _get_reset_info(self) -> dict[str, Any]:
        qpos = self.data.qpos
        return {
            "x_position": qpos[0],
            "y_position": qpos[1],
            "z_distance_from_origin": qpos[2] - self.init_qpos[2],
            **self._tendon_info(),
        }
