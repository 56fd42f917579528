"""``palaestra.utils.performance``: Gymnasium's benchmarks give rates for palaestra envs."""

from __future__ import annotations

import pytest

import palaestra as gym
from palaestra.utils import performance


def test_rates_are_positive_and_short() -> None:
    env = gym.make("CartPole-v1", render_mode="rgb_array")
    assert performance.benchmark_step(env, target_duration=0.05, seed=0) > 100
    assert performance.benchmark_render(env, target_duration=0.05) > 1
    assert performance.benchmark_init(lambda: gym.make("CartPole-v1"), 0.05, seed=1) > 1
    for mode in ("sync", "vector_entry_point"):
        venv = gym.make_vec("CartPole-v1", 4, vectorization_mode=mode)
        assert performance.benchmark_vector_step(venv, target_duration=0.05, seed=0) > 100


def test_counts_what_gymnasium_counts(monkeypatch: pytest.MonkeyPatch) -> None:
    # a clock that advances 1 s per reading: with target 2.5 s the body runs exactly 3 times
    ticks = iter(range(100))
    monkeypatch.setattr(performance.time, "perf_counter", lambda: float(next(ticks)))
    env = gym.make("CartPole-v1")
    assert performance.benchmark_step(env, target_duration=2.5, seed=0) == 1.0
    venv = gym.make_vec("CartPole-v1", 4, vectorization_mode="sync")
    ticks = iter(range(100))
    assert performance.benchmark_vector_step(venv, target_duration=2.5, seed=0) == 4.0


def test_bad_durations() -> None:
    env = gym.make("CartPole-v1")
    with pytest.raises(ValueError, match="target_duration must be >= 0 seconds, got -1"):
        performance.benchmark_step(env, target_duration=-1)
    with pytest.raises(TypeError, match="target_duration must be a number of seconds"):
        performance.benchmark_render(env, target_duration="5")  # type: ignore[arg-type]
