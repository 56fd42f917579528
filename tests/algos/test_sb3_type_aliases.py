"""``palaestra.algos.type_aliases`` against SB3's ``type_aliases``: the names palaestra already
had are those objects (one definition), and the new ones have SB3's fields and values."""

from __future__ import annotations

import inspect
import typing

import stable_baselines3.common.type_aliases as sb3

from palaestra.algos import PPO, buffers, schedules, type_aliases
from palaestra.algos.callbacks import BaseCallback
from palaestra.core import Env
from palaestra.vec_env import VecEnv

SAMPLES = [
    "ReplayBufferSamples",
    "DictReplayBufferSamples",
    "RolloutBufferSamples",
    "DictRolloutBufferSamples",
]


def test_the_names_palaestra_had_are_the_same_objects() -> None:
    for name in SAMPLES:
        assert getattr(type_aliases, name) is getattr(buffers, name)
    assert type_aliases.Schedule is schedules.Schedule


def test_named_tuples_have_sb3s_fields_and_defaults() -> None:
    for name in [*SAMPLES, "RolloutReturn", "TrainFreq"]:
        ours, theirs = getattr(type_aliases, name), getattr(sb3, name)
        assert ours._fields == theirs._fields, name
        assert ours._field_defaults == theirs._field_defaults, name


def test_train_frequency_units_are_sb3s_and_equal_palaestras_strings() -> None:
    ours = type_aliases.TrainFrequencyUnit
    assert [(u.name, u.value) for u in ours] == [(u.name, u.value) for u in sb3.TrainFrequencyUnit]
    freq = type_aliases.TrainFreq(4, ours("episode"))
    assert freq == (4, "episode") and freq.unit is ours.EPISODE  # model.train_freq's form


def test_aliases_name_palaestras_classes() -> None:
    assert typing.get_args(type_aliases.GymEnv) == (Env[typing.Any, typing.Any], VecEnv)
    assert BaseCallback in typing.get_args(type_aliases.MaybeCallback)
    assert type(None) in typing.get_args(type_aliases.MaybeCallback)
    step = typing.get_args(type_aliases.GymStepReturn)
    assert step[1:4] == typing.get_args(sb3.GymStepReturn)[1:4] == (float, bool, bool)
    assert step[0] == type_aliases.GymObs
    assert len(typing.get_args(type_aliases.GymObs)) == len(typing.get_args(sb3.GymObs)) == 4
    assert typing.get_args(type_aliases.TensorDict)[1] is typing.get_args(sb3.TensorDict)[1]


def test_policy_predictor_is_sb3s_predict_and_models_have_it() -> None:
    ours = inspect.signature(type_aliases.PolicyPredictor.predict)
    theirs = inspect.signature(sb3.PolicyPredictor.predict)
    assert list(ours.parameters) == list(theirs.parameters)
    assert [p.default for p in ours.parameters.values()] == [
        p.default for p in theirs.parameters.values()
    ]
    model_predict = inspect.signature(PPO.predict)
    assert list(model_predict.parameters) == list(ours.parameters)
