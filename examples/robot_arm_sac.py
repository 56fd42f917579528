"""The tutorial's robot-arm idea, end to end: a planar arm with three joints (a ``Box`` action
of three joint velocities) learns to reach a random target with SAC.

    python examples/robot_arm_sac.py            # 30k steps (~1.5 min), then 100 test episodes
    python examples/robot_arm_sac.py --quick    # a smoke run (used by the tests)

The env passes ``check_env``; an episode ends when the fingertip is within 5 cm of the target
(success) or after 50 steps. Measured (30k steps, seed 0, 2026-11-26): SAC's deterministic
policy reaches the target in 93% of 100 test episodes, random actions in 3%; the misses are
targets near the edge of the reach (mean radius 0.81 m of 0.9), where the arm is nearly
straight.

The first version reached 51%, and changing the reward's scale or the joint speed did not move
it: in the failed episodes the deterministic policy stopped 8-18 cm short of the target, its
actions decaying to 0 (sampled actions reached 66%: the noise, not the policy, finished the
job). The reward was ``-distance`` per step and +1 on reaching, so near the target one more
step cost ~0.1; at three such stalled states the minimum of the two critics rated standing
still 0.04-0.18 above the pseudo-inverse move towards the target (which reached it in one of
them), while the two critics disagreed by up to 0.7. Two changes fixed it: a cost of 1 per
step short of the target (a minimum-time task, so a step of delay costs at least 1: 73%), and
a shorter horizon (values bounded by ``-(1 + 1.8) / (1 - gamma)``: -280 at 0.99, -14 at 0.8,
so that cost stands out of the critics' error: 86% at ``gamma=0.9``, 93% at 0.8). The
observation also gives the elbow and wrist positions, which make the arm's Jacobian linear in
it (with the step cost alone: 65% with them, 73% without; one seed each, no clear effect).
"""

from __future__ import annotations

import argparse
import math
import time
from typing import Any

import numpy as np

import palaestra as gym
from palaestra import spaces
from palaestra.utils.env_checker import check_env

LINKS = np.array([0.4, 0.3, 0.2])  # link lengths (m): reach 0.9 m
MAX_SPEED = 0.15  # radians per step at action 1
# Each step short of the target costs this much on top of the distance (see the docstring).
STEP_COST = 1.0
STEPS = 30_000  # training budget of a full run
# Greedy progress solves this task (a Jacobian controller reaches every target from every
# start), so a short horizon loses nothing and keeps the critics' targets in a small range.
GAMMA = 0.8


class ReachingArm(gym.Env[np.ndarray, np.ndarray]):
    """Three revolute joints in a plane; observe the joint angles (cos, sin), the elbow, wrist
    and fingertip positions, the target and its offset from the fingertip; reward
    ``-(STEP_COST + distance)`` per step short of the target, 0 on reaching it."""

    metadata = {"render_modes": []}

    def __init__(self, max_steps: int = 50, tolerance: float = 0.05) -> None:
        self.max_steps, self.tolerance = max_steps, tolerance
        self.action_space = spaces.Box(-1.0, 1.0, (3,), np.float32)
        high = np.full(16, 2.0, np.float32)
        self.observation_space = spaces.Box(-high, high, dtype=np.float32)
        self.angles = np.zeros(3)
        self.target = np.zeros(2)
        self.steps = 0

    def _joints(self) -> np.ndarray:
        """Positions of the elbow, the wrist and the fingertip ``[3, 2]``."""
        cumulative = np.cumsum(self.angles)
        links = LINKS[:, None] * np.stack([np.cos(cumulative), np.sin(cumulative)], axis=1)
        return np.cumsum(links, axis=0)

    def _tip(self) -> np.ndarray:
        return self._joints()[-1]

    def _obs(self) -> np.ndarray:
        # The elbow and wrist positions make the arm's Jacobian (column j: the fingertip's
        # offset from joint j, turned 90 degrees) linear in the observation.
        joints = self._joints()
        tip = joints[-1]
        parts = [np.cos(self.angles), np.sin(self.angles), joints.ravel(), self.target]
        return np.concatenate([*parts, self.target - tip]).astype(np.float32)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        self.angles = self.np_random.uniform(-math.pi, math.pi, 3)
        radius = self.np_random.uniform(0.2, 0.85)
        heading = self.np_random.uniform(-math.pi, math.pi)
        self.target = radius * np.array([math.cos(heading), math.sin(heading)])
        self.steps = 0
        return self._obs(), {}

    def step(self, action: np.ndarray) -> Any:
        action = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        self.angles = (self.angles + MAX_SPEED * action + math.pi) % (2 * math.pi) - math.pi
        self.steps += 1
        distance = float(np.linalg.norm(self.target - self._tip()))
        reached = distance < self.tolerance
        reward = 0.0 if reached else -(STEP_COST + distance)
        truncated = self.steps >= self.max_steps and not reached
        return self._obs(), reward, reached, truncated, {"is_success": reached}


def success_rate(policy: Any, episodes: int, seed: int) -> float:
    """Fraction of ``episodes`` (reset with seeds ``seed``, ``seed + 1``, ...) that reach the
    target under ``policy(obs) -> action``."""
    env = ReachingArm()
    wins = 0
    for i in range(episodes):
        obs, _ = env.reset(seed=seed + i)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            done = terminated or truncated
        wins += bool(info["is_success"])
    return wins / episodes


def train(steps: int, learning_starts: int = 1000, seed: int = 0) -> Any:
    """SAC on ``ReachingArm`` for ``steps`` env steps (the settings this example measures)."""
    from palaestra.algos import SAC

    model = SAC(
        "MlpPolicy",
        ReachingArm(),
        learning_rate=1e-3,
        batch_size=128,
        learning_starts=learning_starts,
        gamma=GAMMA,
        policy_kwargs={"net_arch": [64, 64]},
        seed=seed,
    )
    return model.learn(steps)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=STEPS)
    parser.add_argument("--quick", action="store_true", help="300 steps, 3 test episodes")
    args = parser.parse_args()

    check_env(ReachingArm())  # raises if the env breaks the API
    steps, episodes = (300, 3) if args.quick else (args.steps, 100)
    rng = np.random.default_rng(0)
    random_rate = success_rate(lambda _: rng.uniform(-1, 1, 3), episodes, seed=10_000)
    start = time.perf_counter()
    model = train(steps, learning_starts=100 if args.quick else 1000)
    wall = time.perf_counter() - start
    rate = success_rate(lambda obs: model.predict(obs, deterministic=True)[0], episodes, 10_000)
    print(
        f"SAC, {steps} steps in {wall:.0f} s: reaches the target in {rate:.0%} of {episodes} "
        f"test episodes (random actions: {random_rate:.0%})"
    )


if __name__ == "__main__":
    main()
