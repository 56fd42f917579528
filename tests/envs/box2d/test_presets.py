"""The LunarLander presets (issue 15): each builds its algorithm on its env as
``palaestra train`` would, and a ``measured`` block agrees with itself."""

from __future__ import annotations

import pytest

import palaestra
from palaestra import presets

pytest.importorskip("Box2D")
pytest.importorskip("torch")

BOX2D_IDS = ("LunarLander-v3", "LunarLanderContinuous-v3")
CASES = [
    (algo, env_id)
    for algo, envs in presets.available().items()
    for env_id in envs
    if env_id in BOX2D_IDS
]


def test_the_issue_presets_are_shipped() -> None:
    """Issue 15's list: PPO and DQN on LunarLander, SAC and TD3 on LunarLanderContinuous."""
    assert {("ppo", "LunarLander-v3"), ("dqn", "LunarLander-v3")} <= set(CASES)
    assert {("sac", "LunarLanderContinuous-v3"), ("td3", "LunarLanderContinuous-v3")} <= set(CASES)


@pytest.mark.parametrize(("algo", "env_id"), CASES, ids=[f"{a}-{e}" for a, e in CASES])
def test_preset_builds_its_algorithm(algo: str, env_id: str) -> None:
    from palaestra import algos
    from palaestra.vec_env import make_vec_env

    preset = presets.get_preset(algo, env_id)
    hyperparams = presets.resolve(preset["hyperparams"])
    # A small replay buffer: the preset's own size is only memory, not what is checked here.
    if "buffer_size" in hyperparams:
        hyperparams["buffer_size"] = 1000
    venv = make_vec_env(env_id, n_envs=preset["n_envs"], seed=0)
    model = getattr(algos, algo.upper())(preset["policy"], venv, seed=0, **hyperparams)
    assert model.n_envs == preset["n_envs"]
    assert model.gamma == preset["hyperparams"].get("gamma", model.gamma)
    venv.close()


@pytest.mark.parametrize(("algo", "env_id"), CASES, ids=[f"{a}-{e}" for a, e in CASES])
def test_measured_block_is_consistent(algo: str, env_id: str) -> None:
    measured = presets.get_preset(algo, env_id).get("measured")
    assert measured is not None, f"{algo} {env_id}: a shipped preset carries its measurement"
    assert measured["target"] == palaestra.spec(env_id).reward_threshold == 200
    meeting = sum(r >= measured["target"] for r in measured["mean_return"])
    assert measured["seeds_meeting_target"] == meeting
    assert len(measured["mean_return"]) == len(measured["seeds"]) == len(measured["wall_s"])
