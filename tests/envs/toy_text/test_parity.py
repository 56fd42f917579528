"""Side by side with the installed Gymnasium: ``P`` tables, specs, and 1200 steps per variant
(observations, rewards with their types, terminated, truncated, infos, ansi text)."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pytest
from tests.envs.toy_text.cases import TOY_TEXT_IDS, VARIANTS, Policy, variant_id

import palaestra

gym = pytest.importorskip("gymnasium")
pytestmark = pytest.mark.filterwarnings("ignore::UserWarning", "ignore::DeprecationWarning")


def assert_same(ours: Any, ref: Any, where: str) -> None:
    """Equal values of equal types (numpy arrays: equal dtype, shape and values)."""
    if isinstance(ref, dict):
        assert isinstance(ours, dict) and ours.keys() == ref.keys(), f"{where}: {ours} != {ref}"
        for key in ref:
            assert_same(ours[key], ref[key], f"{where}[{key!r}]")
    elif isinstance(ref, tuple):
        assert isinstance(ours, tuple) and len(ours) == len(ref), f"{where}: {ours} != {ref}"
        for i, (a, b) in enumerate(zip(ours, ref)):
            assert_same(a, b, f"{where}[{i}]")
    elif isinstance(ref, np.ndarray):
        assert isinstance(ours, np.ndarray) and ours.dtype == ref.dtype, f"{where}: {ours!r}"
        np.testing.assert_array_equal(ours, ref, err_msg=where)
    else:
        # Gymnasium returns Python ints for states, the reward schedule's own types, floats
        # for probabilities: the same types here.
        assert type(ours) is type(ref) and ours == ref, f"{where}: {ours!r} != {ref!r}"


@pytest.mark.parametrize("env_id", TOY_TEXT_IDS)
def test_spec_matches_gymnasium(env_id: str) -> None:
    ours, ref = palaestra.spec(env_id), gym.spec(env_id)
    assert ours.max_episode_steps == ref.max_episode_steps
    assert ours.reward_threshold == ref.reward_threshold
    assert ours.kwargs == ref.kwargs
    assert ours.entry_point.split(":")[1] == ref.entry_point.split(":")[1]  # class name
    env, ref_env = palaestra.make(env_id), gym.make(env_id)
    assert repr(env.observation_space) == repr(ref_env.observation_space)
    assert repr(env.action_space) == repr(ref_env.action_space)
    assert env.unwrapped.metadata == ref_env.unwrapped.metadata
    assert str(env) == str(ref_env)


def test_registered_toy_text_ids_are_gymnasiums() -> None:
    ref = {i for i, s in gym.registry.items() if "toy_text" in str(s.entry_point)}
    ours = {i for i, s in palaestra.registry.items() if "toy_text" in str(s.entry_point)}
    assert ours == ref == set(TOY_TEXT_IDS)


@pytest.mark.parametrize("old", ["Taxi-v3", "CliffWalking-v0", "FrozenLake-v0", "Blackjack-v0"])
def test_old_versions_are_deprecated_as_in_gymnasium(old: str) -> None:
    with pytest.raises(gym.error.DeprecatedEnv) as ref:
        gym.make(old)
    with pytest.raises(palaestra.error.DeprecatedEnv) as ours:
        palaestra.make(old)
    assert str(ours.value) == str(ref.value)


@pytest.mark.parametrize("case", VARIANTS, ids=variant_id)
def test_transition_table_matches_gymnasium(case: tuple[str, dict[str, Any]]) -> None:
    env_id, kwargs = case
    ours, ref = palaestra.make(env_id, **kwargs).unwrapped, gym.make(env_id, **kwargs).unwrapped
    if not hasattr(ref, "P"):
        pytest.skip("Blackjack has no transition table")
    assert ours.P.keys() == ref.P.keys()
    for s in ref.P:
        assert ours.P[s].keys() == ref.P[s].keys()
        for a in ref.P[s]:
            assert len(ours.P[s][a]) == len(ref.P[s][a]), (s, a)
            for got, want in zip(ours.P[s][a], ref.P[s][a]):
                # Gymnasium's CliffWalking keeps numpy ints for states; values must agree and
                # probabilities, rewards and flags keep Gymnasium's Python types.
                assert got == want, (s, a, got, want)
                assert type(got[0]) is type(want[0]) and type(got[2]) is type(want[2])
    np.testing.assert_array_equal(ours.initial_state_distrib, ref.initial_state_distrib)


@pytest.mark.parametrize("case", VARIANTS, ids=variant_id)
def test_episodes_match_gymnasium(case: tuple[str, dict[str, Any]]) -> None:
    env_id, kwargs = case
    ansi = "ansi" in gym.spec(env_id).make().metadata["render_modes"]
    mode = "ansi" if ansi else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ours = palaestra.make(env_id, render_mode=mode, **kwargs)
        ref = gym.make(env_id, render_mode=mode, **kwargs)
    steps = ends = truncations = changes = 0
    for seed, epsilon in ((0, 0.1), (1, 0.3), (7, 1.0), (123, 0.5)):
        policy = Policy(ref, seed, epsilon)
        obs, info = ours.reset(seed=seed)
        ref_obs, ref_info = ref.reset(seed=seed)
        assert_same((obs, info), (ref_obs, ref_info), f"reset seed={seed}")
        for t in range(300):
            action = policy(ref_obs)
            got, want = ours.step(action), ref.step(action)
            where = f"seed={seed} step {t}"
            assert_same(got, want, where)
            if ansi:
                assert ours.render() == ref.render(), where
            if env_id == "Taxi-v4" and not want[2] and not want[3]:
                changes += want[0] % 4 != ref_obs % 4  # only a fickle passenger does this
            ref_obs = want[0]
            steps += 1
            if want[2] or want[3]:
                ends += 1
                truncations += want[3]
                restart = ref.reset()
                assert_same(ours.reset(), restart, f"{where} reset")
                ref_obs = restart[0]
                if ansi:
                    assert ours.render() == ref.render(), where
    assert steps >= 1000 and ends > 0
    if env_id == "Taxi-v4":
        assert truncations > 0  # the random seed's episodes run out of time
        assert (changes > 0) == kwargs.get("fickle_passenger", False)
