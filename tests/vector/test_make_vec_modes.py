"""make_vec picks the native batch by default, and falls back to sync for Gymnasium-style args."""

import numpy as np
import pytest

import palaestra as gym
from palaestra.vector import AutoresetMode, SyncVectorEnv
from palaestra.vector.native import BatchedVectorEnv
from palaestra.wrappers import ClipReward


def test_default_is_the_native_batch() -> None:
    assert isinstance(gym.make_vec("MountainCar-v0", 4), BatchedVectorEnv)


def test_native_batch_takes_its_own_vector_kwargs() -> None:
    envs = gym.make_vec("CartPole-v1", 2, vector_kwargs={"autoreset_mode": "SameStep"})
    assert isinstance(envs, BatchedVectorEnv)
    assert envs.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP


@pytest.mark.parametrize(
    "kwargs",
    [
        {"wrappers": [lambda env: ClipReward(env, -0.5, 0.5)]},
        {"vector_kwargs": {"copy": False, "observation_mode": "same"}},
    ],
)
def test_gymnasium_style_arguments_fall_back_to_sync(kwargs: dict) -> None:
    envs = gym.make_vec("MountainCar-v0", 3, **kwargs)
    assert isinstance(envs, SyncVectorEnv)
    envs.reset(seed=0)
    _, rewards, *_ = envs.step(np.zeros(3, dtype=np.int64))
    expected = -0.5 if "wrappers" in kwargs else -1.0
    assert rewards.tolist() == [expected] * 3


def test_explicit_vector_entry_point_still_refuses_wrappers() -> None:
    with pytest.raises(gym.error.Error, match="wrappers argument"):
        gym.make_vec(
            "MountainCar-v0", 2, vectorization_mode="vector_entry_point", wrappers=[ClipReward]
        )


NATIVE_IDS = {
    "CartPole-v1": "CartPoleBatch",
    "MountainCar-v0": "MountainCarBatch",
    "MountainCarContinuous-v0": "ContinuousMountainCarBatch",
    "Pendulum-v1": "PendulumBatch",
    "Acrobot-v1": "AcrobotBatch",
    "Blackjack-v1": "BlackjackBatch",
    "FrozenLake-v1": "FrozenLakeBatch",
    "CliffWalking-v1": "CliffWalkingBatch",
    "Taxi-v4": "TaxiBatch",
}


@pytest.mark.parametrize("env_id", sorted(NATIVE_IDS))
def test_the_registry_entry_names_the_native_batch(env_id: str) -> None:
    # The batch is named where the id is registered; palaestra.vector keeps no table of them.
    spec = gym.spec(env_id)
    assert spec.vector_entry_point.endswith(":" + NATIVE_IDS[env_id])
    batch_cls, env_cls = gym.envs.registration.native_batch(spec)
    assert batch_cls.__name__ == NATIVE_IDS[env_id]
    assert f"{env_cls.__module__}:{env_cls.__name__}" == spec.entry_point
    envs = gym.make_vec(env_id, 2)
    assert isinstance(envs, BatchedVectorEnv) and type(envs.batch) is batch_cls
    assert envs.spec.vector_entry_point == spec.vector_entry_point


def test_an_entry_point_that_is_no_native_batch() -> None:
    spec = gym.spec("CartPole-v1")
    for entry in (None, "palaestra.vector.native:BatchedVectorEnv", "no_such_module:X"):
        other = gym.envs.registration.EnvSpec("Other-v0", spec.entry_point)
        other.vector_entry_point = entry
        assert gym.envs.registration.native_batch(other) is None
