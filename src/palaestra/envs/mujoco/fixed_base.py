"""The MuJoCo tasks on a fixed base: InvertedPendulum, InvertedDoublePendulum (balance a pole
on a cart), Reacher (a two-joint arm touches a target) and Pusher (an arm pushes a cylinder
to a goal), v5.

Rewards, terminations, observations and reset draws follow Gymnasium 1.4.0's v5 envs, in the
same order and on the same dtypes, so the same seed and actions give the same bits.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from palaestra.envs.mujoco._base import DEFAULT_CAMERA, MujocoEnv, check_weights

__all__ = ["InvertedDoublePendulumEnv", "InvertedPendulumEnv", "PusherEnv", "ReacherEnv"]


def _squared(x: np.ndarray) -> np.ndarray:
    """``x ** 2`` as Gymnasium's scalar ``x**2`` computes it: C's ``pow``. An array's ``x**2``
    is ``x * x``, which differs from ``pow`` in the last bit now and then; an array exponent
    keeps ``np.power`` on ``pow``."""
    return np.power(x, np.full(x.shape, 2.0))


def body_ids(model: Any, *names: str) -> list[int]:
    """The ids of the model's bodies named ``names`` (their rows in ``data.xpos``)."""
    return [model.body(name).id for name in names]


class InvertedPendulumEnv(MujocoEnv):
    """Push a cart so that the pole hinged on it stays up; +1 a step until it tips past 0.2 rad."""

    default_camera = {"trackbodyid": 0, "distance": 2.04}

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "inverted_pendulum.xml",
        frame_skip: int = 2,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        reset_noise_scale: float = 0.01,
        **kwargs: Any,
    ) -> None:
        (self._reset_noise_scale,) = check_weights(reset_noise_scale=reset_noise_scale)
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self.observation_structure = {"qpos": self.data.qpos.size, "qvel": self.data.qvel.size}
        self.observation_space = self._float_box(4)

    python_infos = {"reward_survive": int}  # Gymnasium's reward is int(not terminated)
    python_reward = int

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        observation = self.rows_obs(rows)
        terminated = ~np.isfinite(observation).all(axis=1) | (np.abs(observation[:, 1]) > 0.2)
        reward = (~terminated).astype(np.int64)
        return observation, reward, terminated, {"reward_survive": reward}

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        return np.concatenate((rows["qpos"], rows["qvel"]), axis=1)

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=False)
        return self._get_obs()


class InvertedDoublePendulumEnv(MujocoEnv):
    """Balance two poles stacked on a cart: a survival bonus minus the tip's distance from its
    upright place and the joints' speeds; ends when the tip drops to y <= 1."""

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "inverted_double_pendulum.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        healthy_reward: float = 10.0,
        reset_noise_scale: float = 0.1,
        **kwargs: Any,
    ) -> None:
        self._healthy_reward, self._reset_noise_scale = check_weights(
            healthy_reward=healthy_reward, reset_noise_scale=reset_noise_scale
        )
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self.observation_space = self._float_box(9)

    row_fields = ("qpos", "qvel", "site_xpos", "qfrc_constraint")
    python_infos = {"reward_survive": float}  # Gymnasium's is a float times an int

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        tip = rows["site_xpos"][:, 0]
        x, y = tip[:, 0], tip[:, 2]
        observation = self.rows_obs(rows)
        terminated = y <= 1
        qvel = rows["qvel"]
        v1, v2 = qvel[:, 1], qvel[:, 2]
        dist_penalty = 0.01 * _squared(x) + _squared(y - 2)
        vel_penalty = 1e-3 * _squared(v1) + 5e-3 * _squared(v2)
        alive_bonus = self._healthy_reward * (~terminated)
        reward = alive_bonus - dist_penalty - vel_penalty
        info = {
            "reward_survive": alive_bonus,
            "distance_penalty": -dist_penalty,
            "velocity_penalty": -vel_penalty,
        }
        return observation, reward, terminated, info

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        qpos = rows["qpos"]
        return np.concatenate(
            (
                qpos[:, :1],
                np.sin(qpos[:, 1:]),
                np.cos(qpos[:, 1:]),
                np.clip(rows["qvel"], -10, 10),
                np.clip(rows["qfrc_constraint"], -10, 10)[:, :1],
            ),
            axis=1,
        )

    def reset_model(self) -> np.ndarray:
        self._noisy_reset(normal_qvel=True)
        return self._get_obs()


class ReacherEnv(MujocoEnv):
    """A two-joint arm rewarded for bringing its fingertip to a random target cheaply."""

    default_camera = {"trackbodyid": 0}

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "reacher.xml",
        frame_skip: int = 2,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        reward_dist_weight: float = 1,
        reward_control_weight: float = 1,
        **kwargs: Any,
    ) -> None:
        self._reward_dist_weight, self._reward_control_weight = check_weights(
            reward_dist_weight=reward_dist_weight, reward_control_weight=reward_control_weight
        )
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self.observation_space = self._float_box(10)
        self._fingertip, self._target = body_ids(self.model, "fingertip", "target")

    row_fields = ("qpos", "qvel", "xpos")

    def _to_target(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        xpos = rows["xpos"]
        return xpos[:, self._fingertip] - xpos[:, self._target]

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        observation = self.rows_obs(rows)
        to_target = self._to_target(rows)
        reward_dist = -np.linalg.norm(to_target, axis=1) * self._reward_dist_weight
        reward_ctrl = -np.square(actions).sum(axis=1) * self._reward_control_weight
        reward = reward_dist + reward_ctrl
        info = {"reward_dist": reward_dist, "reward_ctrl": reward_ctrl}
        return observation, reward, np.zeros(len(reward), bool), info

    def reset_model(self) -> np.ndarray:
        qpos = self.np_random.uniform(low=-0.1, high=0.1, size=self.model.nq) + self.init_qpos
        while True:  # a target inside the disc of radius 0.2
            self.goal = self.np_random.uniform(low=-0.2, high=0.2, size=2)
            if np.linalg.norm(self.goal) < 0.2:
                break
        qpos[-2:] = self.goal
        qvel = self.init_qvel + self.np_random.uniform(low=-0.005, high=0.005, size=self.model.nv)
        qvel[-2:] = 0
        self.set_state(qpos, qvel)
        return self._get_obs()

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        qpos = rows["qpos"]
        theta = qpos[:, :2]
        return np.concatenate(
            (
                np.cos(theta),
                np.sin(theta),
                qpos[:, 2:],
                rows["qvel"][:, :2],
                self._to_target(rows)[:, :2],
            ),
            axis=1,
        )


class PusherEnv(MujocoEnv):
    """A seven-joint arm rewarded for pushing a cylinder onto a goal (and keeping near it)."""

    default_camera = {"trackbodyid": -1, "distance": 4.0}

    def __init__(
        self,
        xml_file: str | os.PathLike[str] = "pusher_v5.xml",
        frame_skip: int = 5,
        default_camera_config: dict[str, Any] | None = DEFAULT_CAMERA,
        reward_near_weight: float = 0.5,
        reward_dist_weight: float = 1,
        reward_control_weight: float = 0.1,
        **kwargs: Any,
    ) -> None:
        self._reward_near_weight, self._reward_dist_weight, self._reward_control_weight = (
            check_weights(
                reward_near_weight=reward_near_weight,
                reward_dist_weight=reward_dist_weight,
                reward_control_weight=reward_control_weight,
            )
        )
        super().__init__(
            xml_file, frame_skip, default_camera_config=default_camera_config, **kwargs
        )
        self.observation_space = self._float_box(23)
        self._tips, self._object, self._goal = body_ids(self.model, "tips_arm", "object", "goal")

    row_fields = ("qpos", "qvel", "xpos")

    def rows_step(
        self, rows: dict[str, np.ndarray], before: Any, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        observation = self.rows_obs(rows)
        xpos = rows["xpos"]
        obj = xpos[:, self._object]
        reward_near = -np.linalg.norm(obj - xpos[:, self._tips], axis=1) * self._reward_near_weight
        reward_dist = -np.linalg.norm(obj - xpos[:, self._goal], axis=1) * self._reward_dist_weight
        reward_ctrl = -np.square(actions).sum(axis=1) * self._reward_control_weight
        reward = reward_dist + reward_ctrl + reward_near
        info = {"reward_dist": reward_dist, "reward_ctrl": reward_ctrl, "reward_near": reward_near}
        return observation, reward, np.zeros(len(reward), bool), info

    def reset_model(self) -> np.ndarray:
        qpos = self.init_qpos.copy()
        self.goal_pos = np.asarray([0, 0])
        while True:  # the cylinder starts more than 0.17 from the goal
            self.cylinder_pos = np.concatenate(
                [
                    self.np_random.uniform(low=-0.3, high=0, size=1),
                    self.np_random.uniform(low=-0.2, high=0.2, size=1),
                ]
            )
            if np.linalg.norm(self.cylinder_pos - self.goal_pos) > 0.17:
                break
        qpos[-4:-2] = self.cylinder_pos
        qpos[-2:] = self.goal_pos
        qvel = self.init_qvel + self.np_random.uniform(low=-0.005, high=0.005, size=self.model.nv)
        qvel[-4:] = 0
        self.set_state(qpos, qvel)
        return self._get_obs()

    def rows_obs(self, rows: dict[str, np.ndarray]) -> np.ndarray:
        xpos = rows["xpos"]
        return np.concatenate(
            (
                rows["qpos"][:, :7],
                rows["qvel"][:, :7],
                xpos[:, self._tips],
                xpos[:, self._object],
                xpos[:, self._goal],
            ),
            axis=1,
        )
