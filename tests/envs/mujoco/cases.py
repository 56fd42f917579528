"""The MuJoCo ids and the runs checked against Gymnasium 1.4.0."""

from __future__ import annotations

from typing import Any

from tests.envs.mujoco.trajectories import Run

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

# Constructor options beyond the defaults, two per env: observation switches, weights, ranges,
# frame_skip, a user's own copy of the model file is in test_models (it must compile the same).
OPTIONS: dict[str, list[dict[str, Any]]] = {
    "Ant-v5": [
        {
            "include_cfrc_ext_in_observation": False,
            "exclude_current_positions_from_observation": False,
        },
        {"main_body": "torso", "contact_force_range": (-0.5, 2.0), "healthy_z_range": (0.3, 1.0)},
    ],
    "HalfCheetah-v5": [
        {"exclude_current_positions_from_observation": False, "ctrl_cost_weight": 0.3},
        {"frame_skip": 3, "reset_noise_scale": 0.5, "forward_reward_weight": 2},
    ],
    "Hopper-v5": [
        {"exclude_current_positions_from_observation": False, "terminate_when_unhealthy": False},
        {
            "healthy_angle_range": (-0.5, 0.5),
            "healthy_z_range": (0.5, 5.0),
            "reset_noise_scale": 0.1,
        },
    ],
    "Humanoid-v5": [
        {"include_cinert_in_observation": False, "include_cvel_in_observation": False},
        {
            "include_qfrc_actuator_in_observation": False,
            "include_cfrc_ext_in_observation": False,
            "contact_cost_range": (-1.0, 0.5),
            "terminate_when_unhealthy": False,
        },
    ],
    "HumanoidStandup-v5": [
        {"exclude_current_positions_from_observation": False, "impact_cost_range": (0.0, 1e-3)},
        {
            "include_cinert_in_observation": False,
            "include_cfrc_ext_in_observation": False,
            "ctrl_cost_weight": 0.5,
        },
    ],
    "InvertedDoublePendulum-v5": [{"healthy_reward": 5.0}, {"reset_noise_scale": 0.3}],
    "InvertedPendulum-v5": [{"reset_noise_scale": 0.1}, {"frame_skip": 4}],
    "Pusher-v5": [{"reward_near_weight": 1.0}, {"reward_control_weight": 0.5, "frame_skip": 3}],
    "Reacher-v5": [{"reward_dist_weight": 2.0}, {"reward_control_weight": 0.1}],
    "Swimmer-v5": [
        {"exclude_current_positions_from_observation": False},
        {"ctrl_cost_weight": 0.01, "reset_noise_scale": 0.5},
    ],
    "Walker2d-v5": [
        {"exclude_current_positions_from_observation": False, "terminate_when_unhealthy": False},
        {"healthy_z_range": (0.5, 2.5), "healthy_angle_range": (-2.0, 2.0)},
    ],
}

# Episodes cut at this many steps, so long runs cross resets in the envs that never terminate.
EPISODE_CAP = {"Reacher-v5": None, "Pusher-v5": None}


def short_runs(env_id: str) -> list[Run]:
    """The fast suite's runs: 200 steps of each kind, defaults, resets at least once."""
    return [
        Run(env_id, {}, (3, 11), 200, "uniform", 0, max_episode_steps=EPISODE_CAP.get(env_id, 120)),
        Run(env_id, OPTIONS[env_id][0], (5,), 200, "sample", 1, max_episode_steps=150),
    ]


def long_runs(env_id: str) -> list[Run]:
    """1,200 steps with each kind of action and each option set, several reset seeds."""
    cap = EPISODE_CAP.get(env_id, 400)
    runs = [
        Run(env_id, {}, (0, 1, 2), 1200, "uniform", 10, max_episode_steps=cap),
        Run(env_id, {}, (7, 8), 1200, "sample", 11),
    ]
    for i, options in enumerate(OPTIONS[env_id]):
        runs.append(
            Run(
                env_id,
                options,
                (20 + i, 30 + i),
                1200,
                ("uniform", "sample")[i],
                12 + i,
                max_episode_steps=cap,
            )
        )
    return runs
