"""An id Gymnasium has and palaestra does not names the ``gymnasium:`` bridge (issue 16, 12)."""

from __future__ import annotations

import pytest

import palaestra as gym
from palaestra import error


@pytest.mark.parametrize(
    ("env_id", "bridged"),
    [
        # (Taxi, FrozenLake and LunarLander are palaestra's own now: MuJoCo ids stand in.)
        ("HalfCheetah-v5", "gymnasium:HalfCheetah-v5"),
        ("Reacher-v5", "gymnasium:Reacher-v5"),
        ("Hopper", "gymnasium:Hopper-v5"),
    ],
)
def test_gymnasium_only_id_names_the_bridge(env_id, bridged):
    with pytest.raises(error.NameNotFound, match=f'make\\("{bridged}"\\)'):
        gym.make(env_id)


def test_the_suggested_bridge_id_makes_the_env():
    pytest.importorskip("gymnasium")
    env = gym.make("gymnasium:Taxi-v4")
    obs, _ = env.reset(seed=0)
    assert obs in env.observation_space


def test_other_unknown_names_keep_gymnasiums_message():
    with pytest.raises(
        error.NameNotFound,
        match=r"^Environment `Cartpole` doesn't exist\. Did you mean: `CartPole`\?$",
    ):
        gym.make("Cartpole-v1")


def test_the_hint_names_the_mujoco_install():
    with pytest.raises(error.NameNotFound, match=r'pip install "gymnasium\[mujoco\]"'):
        gym.make("Ant-v5")


def test_the_bridge_table_lists_no_native_env():
    from palaestra.envs.lookup import GYMNASIUM_ONLY

    native = {spec.name for spec in gym.registry.values() if spec.namespace is None}
    assert not native & set(GYMNASIUM_ONLY)
