"""Run palaestra's and ale-py's Atari envs side by side on the same seeds and actions."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest


def gymnasium_make(env_id: str, **kwargs: Any) -> Any:
    """``gymnasium.make`` with ale-py's ids registered; skips when either is missing."""
    gymnasium = pytest.importorskip("gymnasium")
    ale_py = pytest.importorskip("ale_py")
    gymnasium.register_envs(ale_py)
    return gymnasium.make(env_id, **kwargs)


def rollout(env: Any, actions: list[Any], seeds: dict[int, int | None]) -> list[tuple]:
    """Reset with ``seeds[0]``, step ``actions``; reset again at each episode end and at
    every step index in ``seeds`` (``None``: unseeded). Returns every transition."""
    obs, info = env.reset(seed=seeds[0])
    out: list[tuple] = [("reset", obs, info)]
    for t, action in enumerate(actions, 1):
        obs, reward, terminated, truncated, info = env.step(action)
        out.append(("step", obs, reward, terminated, truncated, info))
        if terminated or truncated or t in seeds:
            obs, info = env.reset(seed=seeds.get(t))
            out.append(("reset", obs, info))
    return out


def assert_same(ours: list[tuple], ref: list[tuple]) -> None:
    """Transition by transition: equal observations (every byte), rewards, flags and infos."""
    assert len(ours) == len(ref)
    for t, (a, b) in enumerate(zip(ours, ref)):
        assert a[0] == b[0], t
        obs_a, obs_b = a[1], b[1]
        if isinstance(obs_b, dict):
            assert obs_a.keys() == obs_b.keys()
            for key in obs_b:
                np.testing.assert_array_equal(obs_a[key], obs_b[key], err_msg=f"{t} {key}")
        else:
            assert obs_a.dtype == obs_b.dtype and obs_a.shape == obs_b.shape, t
            np.testing.assert_array_equal(obs_a, obs_b, err_msg=f"transition {t}")
        rest_a, rest_b = a[2:], b[2:]
        assert [type(v) for v in rest_a] == [type(v) for v in rest_b], t
        assert rest_a == rest_b, (t, rest_a, rest_b)
