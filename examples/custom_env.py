"""Write your own environment, check it, register it, train an agent on it and evaluate it.

Shows the whole life of a custom env with palaestra's Gymnasium API:

1. ``GridTargetEnv``: an agent on a 5x5 grid walks to a target cell drawn at random each
   episode. Observation ``Box(0, 1, (4,), float32)`` (agent and target positions, scaled);
   actions ``Discrete(4)`` (up, right, down, left); reward +1 on reaching the target, -0.02
   per step otherwise; ``render_mode="rgb_array"`` returns a ``(160, 160, 3) uint8`` picture.
2. ``palaestra.register("GridTarget-v0", ...)`` makes it available to ``palaestra.make`` and
   ``make_vec_env`` with a 50-step time limit.
3. ``check_env`` from ``palaestra.utils.env_checker`` checks it against the API contract.
4. PPO trains on 8 copies; ``evaluate_policy`` compares it with a random policy over 100
   episodes; one greedy episode is saved as a GIF.

Run::

    .venv/bin/python examples/custom_env.py            # seconds: train 30k steps, evaluate
    .venv/bin/python examples/custom_env.py --quick    # a few seconds, for the tests

Outputs go to ``runs/custom_env/`` (``--out`` to change): ``episode.gif``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

import palaestra as gym
from palaestra import spaces
from palaestra.utils.env_checker import check_env

SIZE = 5
CELL = 32  # pixels per grid cell in rendered frames
MOVES = np.array([[0, -1], [1, 0], [0, 1], [-1, 0]])  # up, right, down, left as (dx, dy)


class GridTargetEnv(gym.Env[np.ndarray, np.int64]):
    """Walk to the target cell on a ``size`` x ``size`` grid."""

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 8}

    def __init__(self, size: int = SIZE, render_mode: str | None = None) -> None:
        if size < 2:
            raise ValueError(f"size must be at least 2, got {size}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.size, self.render_mode = size, render_mode
        self.observation_space = spaces.Box(0.0, 1.0, shape=(4,), dtype=np.float32)
        self.action_space = spaces.Discrete(4)
        self.agent = np.zeros(2, dtype=np.int64)
        self.target = np.zeros(2, dtype=np.int64)

    def _obs(self) -> np.ndarray:
        return (np.concatenate([self.agent, self.target]) / (self.size - 1)).astype(np.float32)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)  # seeds self.np_random
        self.agent = self.np_random.integers(0, self.size, size=2)
        self.target = self.agent
        while np.array_equal(self.target, self.agent):
            self.target = self.np_random.integers(0, self.size, size=2)
        return self._obs(), {"distance": int(np.abs(self.agent - self.target).sum())}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if not self.action_space.contains(action):
            raise ValueError(f"action {action!r} is not in {self.action_space}")
        self.agent = np.clip(self.agent + MOVES[int(action)], 0, self.size - 1)
        reached = bool(np.array_equal(self.agent, self.target))
        reward = 1.0 if reached else -0.02
        distance = int(np.abs(self.agent - self.target).sum())
        return self._obs(), reward, reached, False, {"distance": distance}

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        frame = np.full((self.size * CELL, self.size * CELL, 3), 235, dtype=np.uint8)
        frame[::CELL, :] = frame[:, ::CELL] = 180  # grid lines
        tx, ty = self.target * CELL
        frame[ty + 4 : ty + CELL - 3, tx + 4 : tx + CELL - 3] = (60, 170, 75)  # green target
        yy, xx = np.mgrid[0:CELL, 0:CELL]
        disc = (xx - CELL / 2) ** 2 + (yy - CELL / 2) ** 2 <= (CELL * 0.35) ** 2
        ax, ay = self.agent * CELL
        frame[ay : ay + CELL, ax : ax + CELL][disc] = (40, 90, 200)  # blue agent
        return frame


def register() -> None:
    """Make ``GridTarget-v0`` known to ``palaestra.make`` (a 50-step time limit)."""
    if "GridTarget-v0" not in gym.registry:
        gym.register("GridTarget-v0", entry_point=GridTargetEnv, max_episode_steps=50)


def random_returns(episodes: int, seed: int) -> list[float]:
    """Returns of a uniformly random policy (the baseline the agent must beat)."""
    env = gym.make("GridTarget-v0")
    env.action_space.seed(seed)
    out = []
    env.reset(seed=seed)
    for _ in range(episodes):
        total, done = 0.0, False
        while not done:
            _, reward, terminated, truncated, _ = env.step(env.action_space.sample())
            total += float(reward)
            done = terminated or truncated
        out.append(total)
        env.reset()
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=30_000, help="PPO training steps")
    parser.add_argument("--quick", action="store_true", help="tiny run (for the tests)")
    parser.add_argument("--out", type=Path, default=Path("runs/custom_env"))
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    steps, episodes = (2_048, 10) if args.quick else (args.steps, 100)

    import torch

    from palaestra.algos import PPO, evaluate_policy
    from palaestra.utils.video import save_video
    from palaestra.vec_env import make_vec_env

    torch.set_num_threads(1)
    register()
    # check_env raises if the API contract is broken; the unwrapped env gives it the most
    # precise checks, and its spec (from make) lets it try every render mode.
    check_env(gym.make("GridTarget-v0", render_mode="rgb_array").unwrapped)
    print("check_env: GridTargetEnv passes")
    env = gym.make("GridTarget-v0")
    print(f"observation space: {env.observation_space}")
    print(f"action space: {env.action_space}")
    print(f"spec: max_episode_steps={env.spec.max_episode_steps if env.spec else None}")

    venv = make_vec_env("GridTarget-v0", n_envs=8, seed=args.seed)
    hyperparams = dict(n_steps=128, batch_size=256, n_epochs=4, gamma=0.95, ent_coef=0.01)
    model = PPO("MlpPolicy", venv, learning_rate=1e-3, seed=args.seed, **hyperparams)
    start = time.perf_counter()
    model.learn(steps)
    print(f"trained PPO for {steps} steps in {time.perf_counter() - start:.1f} s")

    env.reset(seed=10_000 + args.seed)
    returns, lengths = evaluate_policy(
        model, env, n_eval_episodes=episodes, deterministic=True, return_episode_rewards=True
    )
    reached = float(np.mean([n < 50 for n in lengths]))
    baseline = random_returns(episodes, args.seed)
    print(f"PPO    mean return {np.mean(returns):6.3f}, reached the target in {reached:.0%}")
    print(f"random mean return {np.mean(baseline):6.3f}")

    render_env = gym.make("GridTarget-v0", render_mode="rgb_array")
    obs, _ = render_env.reset(seed=args.seed)
    frames, done = [render_env.render()], False
    while not done:
        action, _ = model.predict(obs, deterministic=True)
        obs, _, terminated, truncated, _ = render_env.step(action)
        frames.append(render_env.render())
        done = terminated or truncated
    args.out.mkdir(parents=True, exist_ok=True)
    gif = save_video(frames, args.out / "episode.gif", fps=4)
    print(f"wrote {gif} ({len(frames)} frames)")


if __name__ == "__main__":
    main()
