"""Same seeds and actions: palaestra's Atari envs equal ale-py's (via ``gymnasium.make``).

Every byte of every observation, every reward, flag and info (``seeds`` included) must agree,
across seeded and unseeded resets, with sticky actions at their default 0.25. The default
suite runs a few hundred steps per case; the ``slow`` cases run longer and cover more games.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from tests.envs.atari.reference import assert_same, gymnasium_make, rollout

import palaestra

pytest.importorskip("ale_py")

# Seeded reset first, an unseeded reset at step 100, a reseed at step 200.
SEEDS: dict[int, int | None] = {0: 3, 100: None, 200: 7}


def random_actions(n_actions: int, steps: int, seed: int = 1) -> list[int]:
    return [int(a) for a in np.random.default_rng(seed).integers(0, n_actions, steps)]


def check_parity(
    env_id: str, steps: int = 300, seeds: dict | None = None, **kwargs: Any
) -> list[tuple]:
    """Roll both libraries out on the same actions, assert equality, return ours."""
    ours = palaestra.make(env_id, **kwargs)
    ref = gymnasium_make(env_id, **kwargs)
    actions = random_actions(int(ours.action_space.n), steps)
    seeds = SEEDS if seeds is None else seeds
    transitions = rollout(ours, actions, seeds)
    assert_same(transitions, rollout(ref, actions, seeds))
    return transitions


def count(transitions: list[tuple], index: int) -> int:
    """How many steps had a true flag / non-zero reward at ``index`` (2 reward, 3 terminated)."""
    return sum(1 for t in transitions if t[0] == "step" and t[index])


@pytest.mark.parametrize("game", ["Breakout", "Pong", "SpaceInvaders"])
def test_rgb_frames_rewards_and_infos_match(game: str) -> None:
    transitions = check_parity(f"ALE/{game}-v5")
    assert count(transitions, 2) > 0  # some reward was scored


def test_game_over_and_the_reset_after_it_match() -> None:
    # Random Breakout loses its 5 lives at step 132 from seed 4.
    transitions = check_parity("ALE/Breakout-v5", steps=160, seeds={0: 4})
    assert count(transitions, 3) == 1


@pytest.mark.parametrize("obs_type", ["grayscale", "ram"])
def test_other_observation_types_match(obs_type: str) -> None:
    check_parity("ALE/Breakout-v5", steps=150, seeds={0: 5, 75: None}, obs_type=obs_type)


@pytest.mark.slow
@pytest.mark.parametrize("obs_type", ["rgb", "grayscale", "ram"])
@pytest.mark.parametrize("game", ["Breakout", "Pong", "SpaceInvaders", "MsPacman", "Seaquest"])
def test_long_runs_match(game: str, obs_type: str) -> None:
    seeds = {0: 11, 700: None, 1400: 12}
    transitions = check_parity(f"ALE/{game}-v5", steps=2000, seeds=seeds, obs_type=obs_type)
    assert count(transitions, 3) > 0 or game == "Pong"  # Pong's 21 points outlast 700 steps


def test_episode_ends_and_frame_limit_truncation_match() -> None:
    # 40 frames per episode: truncated on step 10, then reset; Pong never ends that fast.
    check_parity("ALE/Pong-v5", steps=60, max_num_frames_per_episode=40)


def test_stochastic_frameskip_full_action_space_mode_and_difficulty_match() -> None:
    kwargs = dict(frameskip=(2, 5), full_action_space=True, mode=4, difficulty=1)
    check_parity("ALE/Breakout-v5", steps=120, seeds={0: 2, 60: 9}, **kwargs)


def test_noframeskip_v4_matches() -> None:
    check_parity("BreakoutNoFrameskip-v4", steps=200, seeds={0: 4})


def test_sound_observations_match() -> None:
    check_parity("ALE/Pong-v5", steps=40, seeds={0: 1}, sound_obs=True)


def test_continuous_actions_match() -> None:
    ours = palaestra.make("ALE/Breakout-v5", continuous=True)
    ref = gymnasium_make("ALE/Breakout-v5", continuous=True)
    assert repr(ours.action_space) == repr(ref.action_space)
    ours.action_space.seed(0)
    actions = [ours.action_space.sample() for _ in range(150)]
    assert_same(rollout(ours, actions, {0: 6}), rollout(ref, actions, {0: 6}))


def test_spaces_metadata_and_action_meanings_match() -> None:
    for kwargs in [{"obs_type": "grayscale"}, {"obs_type": "ram", "full_action_space": True}]:
        ours, ref = palaestra.make("ALE/Pong-v5", **kwargs), gymnasium_make("ALE/Pong-v5", **kwargs)
        assert repr(ours.observation_space) == repr(ref.observation_space)
        assert repr(ours.action_space) == repr(ref.action_space)
        assert ours.unwrapped.metadata == ref.unwrapped.metadata
        assert ours.unwrapped.get_action_meanings() == ref.unwrapped.get_action_meanings()
        assert ours.unwrapped.get_keys_to_action() == ref.unwrapped.get_keys_to_action()
    meanings = palaestra.make("ALE/Breakout-v5").unwrapped.get_action_meanings()
    assert meanings == ["NOOP", "FIRE", "RIGHT", "LEFT"]


def test_np_random_is_derived_from_the_seed_as_in_ale_py() -> None:
    ours, ref = palaestra.make("ALE/Pong-v5"), gymnasium_make("ALE/Pong-v5")
    ours.reset(seed=42)
    ref.reset(seed=42)
    assert ours.unwrapped.np_random_seed == ref.unwrapped.np_random_seed == 42
    draw = ours.unwrapped.np_random.integers(0, 2**31, 5)
    np.testing.assert_array_equal(draw, ref.unwrapped.np_random.integers(0, 2**31, 5))


def test_clone_restore_round_trip_and_states_equal_ale_pys() -> None:
    ours, ref = palaestra.make("ALE/Breakout-v5"), gymnasium_make("ALE/Breakout-v5")
    actions = random_actions(4, 120, seed=3)
    for env in (ours, ref):
        env.reset(seed=8)
        for a in actions[:60]:
            env.step(a)
    for include_rng in (False, True):
        state = ours.unwrapped.clone_state(include_rng=include_rng)
        ref_state = ref.unwrapped.clone_state(include_rng=include_rng)
        assert state.serialize() == ref_state.serialize()
    # Replaying from a state with its RNG gives the same frames, sticky actions included.
    state = ours.unwrapped.clone_state(include_rng=True)
    first = [ours.step(a)[0] for a in actions[60:]]
    ours.unwrapped.restore_state(state)
    again = [ours.step(a)[0] for a in actions[60:]]
    assert all(np.array_equal(a, b) for a, b in zip(first, again))
    assert not np.array_equal(first[0], first[-1])  # the game moved: the check means something


def test_deepcopy_keeps_the_trajectory() -> None:
    """A copy continues exactly where the original is: emulator, sticky-action RNG, frameskip."""
    import copy

    env = palaestra.make("ALE/Breakout-v5", frameskip=(2, 5))
    env.reset(seed=1)
    for a in random_actions(4, 40, seed=5):
        env.step(a)
    clone = copy.deepcopy(env)
    assert clone.unwrapped.np_random_seed == 1 and clone.spec == env.spec
    actions = random_actions(4, 100, seed=6)
    assert_same(
        [("step", *clone.step(a)) for a in actions], [("step", *env.step(a)) for a in actions]
    )
