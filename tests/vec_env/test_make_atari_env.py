"""``make_atari_env``: SB3's helper (Monitor, then AtariWrapper, around each env).

The parity test runs SB3's own ``make_atari_env`` on ale-py. SB3's ``WarpFrame`` needs OpenCV,
which is not installed here: SB3's module gets a fake ``cv2`` whose ``cvtColor`` is OpenCV's
fixed-point formula and whose ``resize`` is palaestra's ``resize_area`` (pinned to OpenCV's
bytes by tests/wrappers/test_resize.py), so the comparison covers everything but OpenCV itself.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import pytest
from tests.wrappers.atari_helpers import fake_cv2

import palaestra
from palaestra.vec_env import DummyVecEnv, SubprocVecEnv, make_atari_env
from palaestra.vec_env.env_util import _atari_engine
from palaestra.wrappers import AtariWrapper, Monitor

pytest.importorskip("ale_py")

ENV_ID = "BreakoutNoFrameskip-v4"


def _steps(venv: Any, steps: int, seed: int = 0) -> list[tuple]:
    out: list[tuple] = [("reset", venv.reset())]
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        out.append(("step", *venv.step(rng.integers(0, 4, venv.num_envs))))
    return out


def _assert_same(a: list[tuple], b: list[tuple], reward_dtype: bool = True) -> int:
    """Equal observations, rewards, dones and infos; returns the number of finished games."""
    games = 0
    for t, (x, y) in enumerate(zip(a, b, strict=True)):
        np.testing.assert_array_equal(x[1], y[1], err_msg=f"obs {t}")
        assert x[1].dtype == y[1].dtype
        if x[0] == "reset":
            continue
        np.testing.assert_array_equal(x[2], y[2], err_msg=f"rewards {t}")
        np.testing.assert_array_equal(x[3], y[3], err_msg=f"dones {t}")
        assert x[3].dtype == y[3].dtype
        assert x[2].dtype == y[2].dtype or not reward_dtype
        for ours, ref in zip(x[4], y[4], strict=True):
            assert sorted(ours) == sorted(ref), t
            for key, value in ref.items():
                if key == "terminal_observation":
                    np.testing.assert_array_equal(ours[key], value)
                elif key == "episode":  # the wall-clock "t" differs
                    assert (ours[key]["r"], ours[key]["l"]) == (value["r"], value["l"]), t
                    games += 1
                else:
                    assert ours[key] == value, (t, key)
    return games


def test_parity_with_sb3(monkeypatch: pytest.MonkeyPatch) -> None:
    gymnasium = pytest.importorskip("gymnasium")
    sb3_atari = pytest.importorskip("stable_baselines3.common.atari_wrappers")
    import ale_py
    from stable_baselines3.common.env_util import make_atari_env as sb3_make_atari_env

    gymnasium.register_envs(ale_py)
    monkeypatch.setattr(sb3_atari, "cv2", fake_cv2())
    kwargs: dict[str, Any] = {"n_envs": 2, "seed": 3}
    ours = make_atari_env(ENV_ID, **kwargs)
    ref = sb3_make_atari_env(ENV_ID, **kwargs)
    assert ours.observation_space == palaestra.spaces.Box(0, 255, (84, 84, 1), np.uint8)
    assert ours.observation_space.shape == ref.observation_space.shape
    assert _assert_same(_steps(ours, 500), _steps(ref, 500)) >= 1  # a game ended


def test_each_env_is_monitor_then_atari_wrapper() -> None:
    venv = make_atari_env(ENV_ID, n_envs=2, seed=0)
    assert isinstance(venv, DummyVecEnv)
    for env in venv.envs:
        assert isinstance(env, AtariWrapper)
        inner = env
        while not isinstance(inner, Monitor):
            inner = inner.env
        assert inner.env.unwrapped.spec.id == ENV_ID
    assert venv.reset().shape == (2, 84, 84, 1)


def test_wrapper_and_env_kwargs_reach_their_targets(tmp_path: Any) -> None:
    venv = make_atari_env(
        "ALE/Pong-v5",
        n_envs=1,
        seed=1,
        start_index=4,
        monitor_dir=str(tmp_path),
        wrapper_kwargs={"screen_size": 64, "terminal_on_life_loss": False, "noop_max": 0},
        env_kwargs={"frameskip": 1, "repeat_action_probability": 0.0},
    )
    assert venv.reset().shape == (1, 64, 64, 1)
    env = venv.envs[0]
    assert env.unwrapped.frameskip == 1
    names = []
    while not isinstance(env, Monitor):
        names.append(type(env).__name__)
        env = env.env
    assert "EpisodicLifeEnv" not in names and "NoopResetEnv" not in names
    venv.close()
    assert os.listdir(tmp_path) == ["4.monitor.csv"]


def test_callable_env_id() -> None:
    venv = make_atari_env(lambda: palaestra.make(ENV_ID), n_envs=1, seed=0)
    assert venv.reset().shape == (1, 84, 84, 1)


def test_no_batched_atari_engine_yet() -> None:
    assert _atari_engine(ENV_ID, 4, {}, {}, None) is None


def test_subproc_gives_the_same_steps() -> None:
    kwargs: dict[str, Any] = {"n_envs": 2, "seed": 5}
    sub = make_atari_env(ENV_ID, vec_env_cls=SubprocVecEnv, **kwargs)
    try:
        assert isinstance(sub, SubprocVecEnv)
        # SB3's SubprocVecEnv stacks float64 rewards, its DummyVecEnv float32: so do ours
        dummy = make_atari_env(ENV_ID, **kwargs)
        _assert_same(_steps(sub, 60), _steps(dummy, 60), reward_dtype=False)
    finally:
        sub.close()
