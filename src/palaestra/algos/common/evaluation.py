"""``evaluate_policy``: SB3's evaluation loop, for a single env or an SB3-style ``VecEnv``."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from palaestra.core import Env, Wrapper
from palaestra.wrappers.monitor import Monitor

__all__ = ["evaluate_policy"]

EvalCallbackFn = Callable[[dict[str, Any], dict[str, Any]], Any]


def _has_monitor(env: Any) -> bool:
    while isinstance(env, Wrapper):
        if isinstance(env, Monitor):
            return True
        env = env.env
    return False


def _vec_monitored(venv: Any) -> bool:
    """A ``VecMonitor`` layer, or ``Monitor``-wrapped sub-envs (SB3's two checks)."""
    from palaestra.vec_env import VecMonitor  # lazy: import-time — cloudpickle

    layer = venv
    while layer is not None:
        if isinstance(layer, VecMonitor):
            return True
        layer = getattr(layer, "venv", None)
    return bool(venv.env_is_wrapped(Monitor)[0]) if hasattr(venv, "env_is_wrapped") else False


def evaluate_policy(
    model: Any,
    env: Any,
    n_eval_episodes: int = 10,
    deterministic: bool = True,
    render: bool = False,
    callback: EvalCallbackFn | None = None,
    reward_threshold: float | None = None,
    return_episode_rewards: bool = False,
    warn: bool = True,
) -> tuple[float, float] | tuple[list[float], list[int]]:
    """Run ``n_eval_episodes`` episodes; return ``(mean, std)`` of the returns, or the lists
    of returns and lengths with ``return_episode_rewards=True``.

    With a ``Monitor`` in the env stack the Monitor's episode statistics are used (so reward
    wrappers or episodic-life wrappers do not distort them), as SB3 does. ``callback`` gets
    ``(locals_, globals_)`` where ``locals_`` holds ``model, env, i, reward, done, info,
    observations, episode_counts, current_rewards, current_lengths``. An env without a
    ``Monitor`` (or ``VecMonitor``) gets SB3's warning unless ``warn=False``.
    ``reward_threshold`` raises ``AssertionError`` when the mean return is at or below it
    (SB3's behaviour).
    """
    if n_eval_episodes <= 0:
        raise ValueError(f"n_eval_episodes must be positive, got {n_eval_episodes}")
    single = isinstance(env, Env)
    if not single and not (hasattr(env, "step_async") and hasattr(env, "num_envs")):
        raise TypeError(f"evaluate_policy needs an Env or a VecEnv, got {type(env).__name__}")
    monitored = _has_monitor(env) if single else _vec_monitored(env)
    if not monitored and warn:  # SB3 warns for a single env too (it wraps it in a VecEnv)
        warnings.warn(
            "Evaluation environment is not wrapped with a ``Monitor`` wrapper. This may result in "
            "reporting modified episode lengths and rewards, if other wrappers happen to modify "
            "these. Consider wrapping environment first with ``Monitor`` wrapper.",
            UserWarning,
            stacklevel=2,
        )
    run = _evaluate_single if single else _evaluate_vec
    rewards, lengths = run(model, env, n_eval_episodes, deterministic, render, callback, monitored)
    mean_reward, std_reward = float(np.mean(rewards)), float(np.std(rewards))
    if reward_threshold is not None:
        assert mean_reward > reward_threshold, (
            f"Mean reward below threshold: {mean_reward:.2f} < {reward_threshold:.2f}"
        )
    if return_episode_rewards:
        return rewards, lengths
    return mean_reward, std_reward


def _evaluate_single(
    model: Any,
    env: Env[Any, Any],
    n: int,
    deterministic: bool,
    render: bool,
    callback: EvalCallbackFn | None,
    monitored: bool,
) -> tuple[list[float], list[int]]:
    rewards: list[float] = []
    lengths: list[int] = []
    obs, _ = env.reset()
    ep_reward, ep_len, state = 0.0, 0, None
    while len(rewards) < n:
        action, state = model.predict(
            obs, state=state, episode_start=np.array([ep_len == 0]), deterministic=deterministic
        )
        new_obs, reward, terminated, truncated, info = env.step(action)
        ep_reward += float(reward)
        ep_len += 1
        done = terminated or truncated
        if callback is not None:
            callback(
                {
                    "model": model,  # SB3 passes its locals(), which user callbacks read
                    "env": env,
                    "i": 0,
                    "reward": reward,
                    "done": done,
                    "info": info,
                    "observations": obs,
                    "new_observations": new_obs,
                    "episode_counts": [len(rewards)],
                    "current_rewards": [ep_reward],
                    "current_lengths": [ep_len],
                },
                {},
            )
        obs = new_obs
        if render:
            env.render()
        if done:
            if not monitored:
                rewards.append(ep_reward)
                lengths.append(ep_len)
            elif "episode" in info:
                rewards.append(float(info["episode"]["r"]))
                lengths.append(int(info["episode"]["l"]))
            obs, _ = env.reset()
            ep_reward, ep_len, state = 0.0, 0, None
    return rewards, lengths


def _evaluate_vec(
    model: Any,
    env: Any,
    n: int,
    deterministic: bool,
    render: bool,
    callback: EvalCallbackFn | None,
    monitored: bool,
) -> tuple[list[float], list[int]]:
    n_envs = env.num_envs
    # Spread the episodes over the envs evenly so no env's short episodes dominate (SB3).
    targets = np.array([(n + i) // n_envs for i in range(n_envs)], dtype=int)
    counts = np.zeros(n_envs, dtype=int)
    current_rewards = np.zeros(n_envs)
    current_lengths = np.zeros(n_envs, dtype=int)
    rewards: list[float] = []
    lengths: list[int] = []
    observations = env.reset()
    states, episode_starts = None, np.ones((n_envs,), dtype=bool)
    while (counts < targets).any():
        actions, states = model.predict(
            observations, state=states, episode_start=episode_starts, deterministic=deterministic
        )
        new_obs, step_rewards, dones, infos = env.step(actions)
        current_rewards += step_rewards
        current_lengths += 1
        for i in range(n_envs):
            if counts[i] >= targets[i]:
                continue
            episode_starts[i] = dones[i]
            if callback is not None:
                callback(
                    {
                        "model": model,
                        "env": env,
                        "i": i,
                        "reward": step_rewards[i],
                        "done": dones[i],
                        "info": infos[i],
                        # SB3 2.x: the observations acted on, and those the step returned
                        "observations": observations,
                        "new_observations": new_obs,
                        "episode_counts": counts,
                        "current_rewards": current_rewards,
                        "current_lengths": current_lengths,
                    },
                    {},
                )
            if dones[i]:
                if not monitored:
                    rewards.append(float(current_rewards[i]))
                    lengths.append(int(current_lengths[i]))
                    counts[i] += 1
                elif "episode" in infos[i]:
                    rewards.append(float(infos[i]["episode"]["r"]))
                    lengths.append(int(infos[i]["episode"]["l"]))
                    counts[i] += 1
                current_rewards[i], current_lengths[i] = 0.0, 0
        observations = new_obs
        if render:
            env.render()
    return rewards, lengths
