"""SB3's remaining public policy names at their palaestra paths: the classes the algorithms
build, and SAC's log-std bounds with SB3's values."""

from __future__ import annotations

import pytest

from palaestra.algos import SAC, TD3
from palaestra.algos.common import policies
from palaestra.algos.sac import policies as sac_policies
from palaestra.algos.td3 import policies as td3_policies

sb3_sac_policies = pytest.importorskip("stable_baselines3.sac.policies")


def test_sac_log_std_bounds_are_sb3s() -> None:
    assert (sac_policies.LOG_STD_MIN, sac_policies.LOG_STD_MAX) == (
        sb3_sac_policies.LOG_STD_MIN,
        sb3_sac_policies.LOG_STD_MAX,
    )


def test_actor_and_critic_names_are_the_classes_the_algorithms_build() -> None:
    sac = SAC("MlpPolicy", "Pendulum-v1", learning_starts=10, seed=0)
    td3 = TD3("MlpPolicy", "Pendulum-v1", learning_starts=10, seed=0)
    assert type(sac.actor) is sac_policies.Actor
    assert type(td3.actor) is td3_policies.Actor
    assert type(sac.critic) is policies.ContinuousCritic is type(td3.critic)


def test_base_model_is_the_base_of_every_policy() -> None:
    sac = SAC("MlpPolicy", "Pendulum-v1", learning_starts=10, seed=0)
    assert isinstance(sac.policy, policies.BaseModel)
    assert isinstance(sac.actor, policies.BaseModel)
    assert issubclass(policies.ActorCriticPolicy, policies.BaseModel)
