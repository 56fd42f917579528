"""Wrapper stacks on the real classic-control envs, made by both libraries, step for step."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
import pytest
from tests.wrappers.conftest import GYM, assert_same, pal, sample_action

import palaestra

STACKS: dict[str, tuple[str, Any]] = {
    "CartPole-time-aware-normalized": (
        "CartPole-v1",
        lambda e, L: L.W.NormalizeObservation(L.W.TimeAwareObservation(e, normalize_time=True)),
    ),
    "CartPole-frame-stack-stats": (
        "CartPole-v1",
        lambda e, L: L.W.RecordEpisodeStatistics(L.W.FrameStackObservation(e, 4)),
    ),
    "Pendulum-rescale-clip-normalize-reward": (
        "Pendulum-v1",
        lambda e, L: L.W.NormalizeReward(
            L.W.ClipAction(L.W.RescaleAction(e, np.float32(0), np.float32(1)))
        ),
    ),
    "MountainCar-discretize-sticky": (
        "MountainCar-v0",
        lambda e, L: L.W.StickyAction(L.W.DiscretizeObservation(e, (6, 5)), 0.25),
    ),
    "MountainCarContinuous-discretize-action": (
        "MountainCarContinuous-v0",
        lambda e, L: L.W.DiscretizeAction(L.W.RepeatAction(e, 2), 7),
    ),
    "Acrobot-delay-max-skip": (
        "Acrobot-v1",
        lambda e, L: L.W.MaxAndSkipObservation(L.W.DelayObservation(e, 1), skip=2),
    ),
}


def _run(lib: Any, make: Any, env_id: str, wrap: Any) -> list[Any]:
    env = wrap(make(env_id), lib)
    rng = np.random.default_rng(3)
    records: list[Any] = [env.reset(seed=11)]
    for _ in range(250):
        obs, reward, terminated, truncated, info = env.step(sample_action(env.action_space, rng))
        if "episode" in info:
            info["episode"]["t"] = 0.0
        records.append((obs, reward, terminated, truncated, info))
        if terminated or truncated:
            records.append(env.reset())
    return [repr(env.observation_space), repr(env.action_space), *records]


@pytest.mark.parametrize("stack", sorted(STACKS))
def test_stack_matches_gymnasium(stack: str) -> None:
    env_id, wrap = STACKS[stack]
    assert_same(_run(pal(), palaestra.make, env_id, wrap), _run(GYM, gymnasium.make, env_id, wrap))


def test_time_aware_reads_max_episode_steps_from_the_spec() -> None:
    env = pal().W.TimeAwareObservation(palaestra.make("CartPole-v1", max_episode_steps=17))
    assert env.max_timesteps == 17
    assert env.spec is not None and env.spec.additional_wrappers[-1].name == "TimeAwareObservation"


def test_make_rebuilds_a_wrapped_env_from_its_spec() -> None:
    W = pal().W
    env = W.NormalizeReward(
        W.FrameStackObservation(
            W.ClipAction(
                W.RescaleAction(palaestra.make("Pendulum-v1"), np.float32(0), np.float32(1))
            ),
            3,
            padding_type="zero",
        ),
        gamma=0.9,
    )
    rebuilt = palaestra.make(env.spec)
    assert str(rebuilt) == str(env)
    names = [w.name for w in rebuilt.spec.additional_wrappers]
    assert names == ["RescaleAction", "ClipAction", "FrameStackObservation", "NormalizeReward"]
    runs = []
    for e in (env, rebuilt):
        rng = np.random.default_rng(0)
        runs.append(
            [e.reset(seed=2)] + [e.step(sample_action(e.action_space, rng)) for _ in range(20)]
        )
    assert_same(runs[1], runs[0])
