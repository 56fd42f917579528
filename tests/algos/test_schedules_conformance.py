"""Schedules return Python floats, as SB3's ``FloatSchedule``/``get_schedule_fn`` (issue 16)."""

from __future__ import annotations

import numpy as np
import pytest
from stable_baselines3.common.utils import get_schedule_fn

from palaestra.algos import PPO
from palaestra.algos.schedules import FloatSchedule, LinearSchedule, as_schedule


@pytest.mark.parametrize("value", [3e-4, lambda p: np.float32(p * 1e-3), lambda p: 1])
def test_as_schedule_returns_python_floats_as_sb3(value):
    ours, theirs = as_schedule(value), get_schedule_fn(value)
    for progress in (1.0, 0.5, 0.0):
        assert type(ours(progress)) is type(theirs(progress)) is float
        assert ours(progress) == theirs(progress)


def test_model_lr_schedule_returns_floats():
    model = PPO("MlpPolicy", "CartPole-v1", learning_rate=lambda p: np.float64(p) * 1e-3, n_steps=8)
    assert type(model.lr_schedule(0.5)) is float and model.lr_schedule(0.5) == 5e-4
    assert isinstance(model.lr_schedule, FloatSchedule)


def test_known_schedules_are_kept_as_they_are():
    linear = LinearSchedule(1.0, 0.0)
    assert as_schedule(linear) is linear
