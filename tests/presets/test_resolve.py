"""presets.resolve: the JSON forms of schedules and action noise become the objects the
algorithms take, and a malformed one is a PresetError naming it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from palaestra import presets
from palaestra.algos import TD3, NormalActionNoise, OrnsteinUhlenbeckActionNoise
from palaestra.algos.common.hyperparams import check_run_hyperparams
from palaestra.algos.schedules import LinearSchedule

OU = {"type": "OrnsteinUhlenbeckActionNoise", "mean": [0.0], "sigma": [0.5]}


def test_ou_noise_takes_sb3_defaults_and_starts_at_zero() -> None:
    noise = presets.resolve({"action_noise": OU, "learning_rate": "lin_0.001"})
    assert noise["learning_rate"] == LinearSchedule(0.001, 0.0)
    ou = noise["action_noise"]
    assert isinstance(ou, OrnsteinUhlenbeckActionNoise)
    assert (ou._theta, ou._dt) == (0.15, 0.01)  # SB3's constructor defaults
    np.testing.assert_array_equal(ou.noise_prev, [0.0])
    # First draw from zero: only the diffusion term, sigma * sqrt(dt) * z.
    z = np.random.default_rng(3).normal(size=1)
    np.testing.assert_allclose(ou(np.random.default_rng(3)), 0.5 * math.sqrt(0.01) * z, rtol=1e-6)


def test_normal_noise_and_explicit_ou_settings() -> None:
    normal = presets.resolve(
        {"action_noise": {"type": "NormalActionNoise", "mean": [0.0, 0.1], "sigma": [0.2, 0.3]}}
    )["action_noise"]
    assert isinstance(normal, NormalActionNoise) and normal.shape == (2,)
    np.testing.assert_array_equal(normal._sigma, [0.2, 0.3])
    ou = presets.resolve({"action_noise": {**OU, "theta": 0.3, "dt": 0.05}})["action_noise"]
    assert (ou._theta, ou._dt) == (0.3, 0.05)


def test_objects_and_none_pass_through() -> None:
    noise = NormalActionNoise(np.zeros(1), np.ones(1))
    assert presets.resolve({"action_noise": noise})["action_noise"] is noise
    assert presets.resolve({"action_noise": None})["action_noise"] is None


@pytest.mark.parametrize(
    ("value", "why"),
    [
        ({"type": "ornstein", "mean": [0.0], "sigma": [0.5]}, "unknown action_noise type"),
        ({"type": "NormalActionNoise", "sigma": [0.5]}, "missing key 'mean'"),
        ({**OU, "sigma": [0.5, 1.0]}, r"mean \(1,\) and sigma \(2,\) do not match"),
        (0.5, "must be a saved noise mapping"),
    ],
)
def test_malformed_noise_is_a_preset_error(value: object, why: str) -> None:
    message = rf"action_noise=.* is not an action noise.*{why}"
    with pytest.raises(presets.PresetError, match=message):
        presets.resolve({"action_noise": value})


def test_a_preset_noise_reaches_the_model_and_passes_the_run_folder_check() -> None:
    hyper = {"action_noise": OU, "learning_starts": 10}
    # `palaestra eval/record/train --resume` re-read config.json's unresolved hyperparams.
    check_run_hyperparams("td3", hyper, {"action_noise", "learning_starts"}, "config.json")
    model = TD3("MlpPolicy", "MountainCarContinuous-v0", seed=0, **presets.resolve(hyper))
    assert isinstance(model.action_noise, OrnsteinUhlenbeckActionNoise)
    with pytest.raises(ValueError, match=r"action_noise of shape \(2,\) does not fit"):
        TD3(
            "MlpPolicy",
            "MountainCarContinuous-v0",
            **presets.resolve({"action_noise": {**OU, "mean": [0.0, 0.0], "sigma": [0.5, 0.5]}}),
        )


def _presets_with_noise() -> list[tuple[str, str, str]]:
    return [
        (algo, env_id, name)
        for algo, envs in presets.available().items()
        for env_id, names in envs.items()
        for name in names
        if "action_noise" in presets.get_preset(algo, env_id, name)["hyperparams"]
    ]


@pytest.mark.parametrize(("algo", "env_id", "name"), _presets_with_noise())
def test_shipped_noise_presets_build(algo: str, env_id: str, name: str) -> None:
    from palaestra.runs.settings import algo_class

    preset = presets.get_preset(algo, env_id, name)
    model = algo_class(algo)("MlpPolicy", env_id, **presets.resolve(preset["hyperparams"]))
    assert model.action_noise is not None
    assert model.action_noise.shape == model.action_space.shape


def test_presets_are_for_the_declared_algorithms() -> None:
    """Every registered algorithm ships presets, and every preset names a registered one: a new
    algorithm's registration line and its presets come together."""
    from palaestra.runs.algorithms import ALGOS

    assert sorted(presets.available()) == sorted(ALGOS)


@pytest.mark.parametrize(
    ("algo", "env_id", "name"),
    [
        (algo, env_id, name)
        for algo, envs in presets.available().items()
        for env_id, names in envs.items()
        for name in names
    ],
)
def test_shipped_presets_pass_their_algorithms_rules(algo: str, env_id: str, name: str) -> None:
    """A preset's hyperparams are ones its algorithm's declared rules accept (what a run folder
    written from it must pass on ``eval`` and ``train --resume``)."""
    from palaestra.runs.algorithms import hyperparameter_names

    hyperparams = presets.get_preset(algo, env_id, name)["hyperparams"]
    check_run_hyperparams(algo, hyperparams, set(hyperparameter_names(algo)), f"{algo}/{env_id}")
