"""Tabular Q-learning on native batches: FrozenLake 4x4 (slippery) and Taxi, solved in seconds.

The first unit of most RL courses, run the palaestra way: ``palaestra.make_vec`` gives a native
batch (every step of all envs is a few numpy operations, row i is the env seeded ``seed + i``),
and the Q table is updated for all rows at once. Each env is then scored by its greedy policy
on 1,000 fresh evaluation episodes (a batch of 1,000 envs, first episode of each row), and its
exact expected return is computed from the env's transition table ``P`` (policy evaluation over
the time limit), beside the best any policy can do (value iteration over the same horizon).
FrozenLake-v1 is solved at Gymnasium's reward threshold, 0.70 (the optimum is 0.74). Taxi-v4's
threshold, 8, lies above its optimum, 7.93 (Gymnasium's "optimum = 8.46" comment predates
v4's start distribution), so Taxi counts as solved when the greedy policy is optimal. It writes
the learning curves (PNG) and a GIF of one greedy episode of each env to
``runs/tabular_q_learning/``.

Run: ``.venv/bin/python examples/tabular_q_learning.py [--out DIR] [--seed S]`` (a few
seconds); ``--quick`` trains on fewer steps and skips the GIFs, for the tests.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import palaestra as gym


@dataclass(frozen=True)
class Settings:
    """Q-learning hyperparameters for one env."""

    env_id: str
    steps: int  # env steps in all (num_envs per batch step)
    quick_steps: int  # with --quick
    num_envs: int = 64
    gamma: float = 0.99  # FrozenLake pays only at the goal: a long horizon matters
    alpha: float = 0.1  # learning rate, decayed linearly to alpha_end
    alpha_end: float = 0.01
    epsilon: float = 1.0  # exploration, decayed linearly to epsilon_end over explore_fraction
    epsilon_end: float = 0.02
    explore_fraction: float = 0.5


SETTINGS = {
    "FrozenLake-v1": Settings("FrozenLake-v1", 1_500_000, 750_000, gamma=0.999),
    "Taxi-v4": Settings("Taxi-v4", 600_000, 600_000, alpha=0.5, alpha_end=0.05),
}


def train(s: Settings, seed: int) -> tuple[np.ndarray, list[float]]:
    """Q-learning on ``make_vec(s.env_id, s.num_envs)``; returns Q and the episode returns."""
    envs = gym.make_vec(s.env_id, num_envs=s.num_envs)
    n_states, n_actions = envs.single_observation_space.n, envs.single_action_space.n
    q = np.zeros((n_states, n_actions))
    rng = np.random.default_rng(seed)
    obs, _ = envs.reset(seed=seed)
    # NEXT_STEP autoreset: a row that ended is reset by the following step, whose transition
    # (last obs -> first obs of the new episode) must not be learned from.
    resetting = np.zeros(s.num_envs, dtype=bool)
    ep_return = np.zeros(s.num_envs)
    returns: list[float] = []
    iterations = s.steps // s.num_envs
    rows = np.arange(s.num_envs)
    for i in range(iterations):
        frac = i / iterations
        epsilon = max(
            s.epsilon_end, s.epsilon - (s.epsilon - s.epsilon_end) * frac / s.explore_fraction
        )
        alpha = s.alpha + (s.alpha_end - s.alpha) * frac
        greedy = q[obs].argmax(axis=1)
        explore = rng.random(s.num_envs) < epsilon
        actions = np.where(explore, rng.integers(0, n_actions, s.num_envs), greedy)
        next_obs, reward, terminated, truncated, _ = envs.step(actions)
        learn = rows[~resetting]
        # Bootstrap through the time limit (truncation), not through the end (termination).
        target = reward + s.gamma * q[next_obs].max(axis=1) * ~terminated
        sa = (obs[learn], actions[learn])
        q[sa] += alpha * (target[learn] - q[sa])
        ep_return[learn] += reward[learn]
        resetting = terminated | truncated
        if resetting.any():
            returns.extend(ep_return[resetting].tolist())
            ep_return[resetting] = 0.0
        obs = next_obs
    envs.close()
    return q, returns


def evaluate(env_id: str, q: np.ndarray, episodes: int = 1000, seed: int = 10_000) -> float:
    """Mean return of the greedy policy over the first episode of ``episodes`` batch rows."""
    envs = gym.make_vec(env_id, num_envs=episodes)
    obs, _ = envs.reset(seed=seed)
    total = np.zeros(episodes)
    finished = np.zeros(episodes, dtype=bool)
    while not finished.all():
        obs, reward, terminated, truncated, _ = envs.step(q[obs].argmax(axis=1))
        total += np.where(finished, 0.0, reward)
        finished |= terminated | truncated
    envs.close()
    return float(total.mean())


def expected_returns(env_id: str, q: np.ndarray) -> tuple[float, float]:
    """``(greedy policy's, best possible)`` expected return over the time limit, exactly, from
    the env's ``P`` and initial-state distribution."""
    env = gym.make(env_id).unwrapped
    horizon = gym.spec(env_id).max_episode_steps
    n_states, n_actions = q.shape
    k = max(len(env.P[s][a]) for s in env.P for a in env.P[s])
    prob, nxt, rew, live = (np.zeros((n_states, n_actions, k)) for _ in range(4))
    for s in env.P:
        for a in env.P[s]:
            for j, (p, s2, r, terminated) in enumerate(env.P[s][a]):
                prob[s, a, j], nxt[s, a, j], rew[s, a, j], live[s, a, j] = p, s2, r, not terminated
    nxt_i = nxt.astype(np.int64)
    greedy = q.argmax(axis=1)
    v_policy, v_best = np.zeros(n_states), np.zeros(n_states)
    for _ in range(horizon):  # values with t steps to go, t = 1 .. horizon
        q_policy = (prob * (rew + live * v_policy[nxt_i])).sum(axis=2)
        v_policy = q_policy[np.arange(n_states), greedy]
        v_best = (prob * (rew + live * v_best[nxt_i])).sum(axis=2).max(axis=1)
    start = env.initial_state_distrib
    return float(start @ v_policy), float(start @ v_best)


def record_episode(env_id: str, q: np.ndarray, path: Path) -> int:
    """Write one greedy episode as a GIF; returns its length."""
    from palaestra.utils.video import save_video

    env = gym.make(env_id, render_mode="rgb_array")
    obs, _ = env.reset(seed=3)
    frames = [env.render()]
    while True:
        obs, _, terminated, truncated, _ = env.step(int(q[obs].argmax()))
        frames.append(env.render())
        if terminated or truncated:
            break
    env.close()
    save_video(frames, path, fps=4)
    return len(frames) - 1


def plot_curves(curves: dict[str, list[float]], path: Path) -> None:
    """One panel per env: the moving average of training episode returns."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(curves), figsize=(5 * len(curves), 3.5))
    for ax, (env_id, returns) in zip(np.atleast_1d(axes), curves.items()):
        r = np.asarray(returns)
        window = max(1, len(r) // 100)
        ax.plot(np.convolve(r, np.ones(window) / window, mode="valid"))
        ax.axhline(
            gym.spec(env_id).reward_threshold, color="gray", ls="--", lw=1, label="threshold"
        )
        ax.set(
            title=f"{env_id} (training, epsilon-greedy)",
            xlabel="episode",
            ylabel=f"return, mean of {window}",
        )
        ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    """Train on each env, evaluate, and write the plot (and GIFs)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=Path("runs/tabular_q_learning"), help="output folder"
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quick", action="store_true", help="fewer steps, no GIFs, for the tests")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    curves = {}
    for env_id, settings in SETTINGS.items():
        if args.quick:
            settings = Settings(**{**settings.__dict__, "steps": settings.quick_steps})
        start = time.perf_counter()
        q, returns = train(settings, args.seed)
        seconds = time.perf_counter() - start
        score = evaluate(env_id, q)
        exact, best = expected_returns(env_id, q)
        threshold = gym.spec(env_id).reward_threshold
        solved = exact >= threshold or (best < threshold and exact >= best - 1e-9)
        print(f"{env_id}: trained on {settings.steps:,} steps ({settings.num_envs} envs) in "
              f"{seconds:.1f} s, {len(returns):,} episodes")  # fmt: skip
        print(f"  greedy policy: mean return {score:.3f} over 1,000 episodes, expected "
              f"{exact:.3f} (optimum {best:.3f}, threshold {threshold:g}): "
              f"{'solved' if solved else 'not solved'}")  # fmt: skip
        curves[env_id] = returns
        if not args.quick:
            gif = args.out / f"{env_id}.gif"
            print(f"  wrote {gif} ({record_episode(env_id, q, gif)} steps)")
    plot_curves(curves, args.out / "learning_curves.png")
    print(f"wrote {args.out / 'learning_curves.png'}")


if __name__ == "__main__":
    main()
