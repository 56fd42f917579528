"""An id Gymnasium has and palaestra does not names the ``gymnasium:`` bridge (issue 16, 12)."""

from __future__ import annotations

import pytest

import palaestra as gym
from palaestra import error


@pytest.mark.parametrize(
    ("env_id", "bridged"),
    [
        # (Taxi, FrozenLake, LunarLander and the MuJoCo envs are palaestra's own now: the
        # Shimmy compatibility ids stand in.)
        ("GymV26Environment-v0", "gymnasium:GymV26Environment-v0"),
        ("GymV21Environment", "gymnasium:GymV21Environment-v0"),
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


def test_the_hint_names_the_dependencies_to_install():
    with pytest.raises(error.NameNotFound, match=r"with gymnasium and that env's own dependencies"):
        gym.make("GymV26Environment-v0")


def test_mujoco_ids_are_native_and_get_no_bridge_hint():
    from palaestra.envs.lookup import GYMNASIUM_ONLY

    for name in ("Ant", "HalfCheetah", "Hopper", "Reacher"):
        assert name not in GYMNASIUM_ONLY
        spec = gym.spec(f"{name}-v5")
        assert spec.entry_point.startswith("palaestra.envs.mujoco."), spec.entry_point


def test_the_bridge_table_lists_no_native_env():
    from palaestra.envs.lookup import GYMNASIUM_ONLY

    native = {spec.name for spec in gym.registry.values() if spec.namespace is None}
    assert not native & set(GYMNASIUM_ONLY)
