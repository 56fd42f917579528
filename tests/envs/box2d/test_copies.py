"""Box2D envs pickle and deep-copy (issue 26): the copy replays the calls so far and continues
the same trajectory, bit for bit, where Gymnasium's copies are fresh, never-reset envs."""

from __future__ import annotations

import copy
import pickle
from typing import Any

import numpy as np
import pytest
from tests.envs.box2d.cases import BOX2D_IDS, id_params

import palaestra
from palaestra.envs.box2d import _common

pytest.importorskip("Box2D")


def _run(env: Any, actions: list[Any]) -> list[tuple[bytes, float, bool]]:
    out = []
    for action in actions:
        obs, reward, terminated, truncated, _ = env.step(action)
        out.append((np.asarray(obs).tobytes(), float(reward), bool(terminated)))
        if terminated or truncated:
            break
    return out


def _actions(env: Any, n: int, seed: int) -> list[Any]:
    env.action_space.seed(seed)
    return [env.action_space.sample() for _ in range(n)]


@pytest.mark.parametrize("env_id", id_params(BOX2D_IDS))
def test_copies_continue_the_trajectory(env_id: str) -> None:
    env = palaestra.make(env_id)
    env.reset(seed=3)
    _run(env, _actions(env, 15, 0))
    clones = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    later = _actions(env, 15, 1)
    want = _run(env, later)
    for clone in clones:
        assert clone.unwrapped is not env.unwrapped
        assert _run(clone, later) == want
        assert clone.unwrapped.np_random.bit_generator.state == (
            env.unwrapped.np_random.bit_generator.state
        )


def test_a_fresh_env_copies_and_then_runs_as_its_original() -> None:
    env = palaestra.make("LunarLander-v3")
    clone = pickle.loads(pickle.dumps(env))
    assert clone.reset(seed=5)[0].tobytes() == env.reset(seed=5)[0].tobytes()
    actions = [0, 2, 2, 1, 3] * 4
    assert _run(clone, actions) == _run(env, actions)


def test_a_copy_made_in_a_later_episode_of_one_world_envs_continues_it() -> None:
    # BipedalWalker keeps one Box2D world across episodes: the copy replays every call.
    env = palaestra.make("BipedalWalker-v3")
    env.reset(seed=0)
    _run(env, _actions(env, 30, 0))
    env.reset(options=None)  # a second episode in the same world, not reseeded
    _run(env, _actions(env, 10, 1))
    clone = copy.deepcopy(env)
    later = _actions(env, 20, 2)
    assert _run(clone, later) == _run(env, later)


def test_draws_made_between_steps_by_a_wrapper_are_replayed() -> None:
    # StickyAction draws from the env's np_random before each step; LunarLander draws too.
    env = palaestra.wrappers.StickyAction(
        palaestra.make("LunarLander-v3"), repeat_action_probability=0.5
    )
    env.reset(seed=1)
    _run(env, [2, 1, 3, 0, 2, 2, 1] * 3)
    clone = pickle.loads(pickle.dumps(env))
    later = [3, 2, 0, 1] * 5
    assert _run(clone, later) == _run(env, later)


def test_a_generator_handed_out_and_drawn_from_later_is_replayed() -> None:
    # Steps skip recording the generator's state while only the env holds it; reading
    # np_random hands it out, and the caller may draw from its reference at any time after.
    env = palaestra.make("LunarLander-v3")
    env.reset(seed=4)
    _run(env, [2, 2, 1])
    assert [start for kind, start, _ in env.unwrapped._calls if kind == "step"] == [None] * 3
    rng = env.np_random
    for action in [3, 2, 0, 1, 2]:
        rng.random(int(rng.integers(1, 4)))  # draws the env does not make
        env.step(action)
    assert all(start is not None for _, start, _ in env.unwrapped._calls[4:])
    clone = copy.deepcopy(env)
    rng.random(3)
    later = [2, 3, 1, 0] * 3
    want = _run(env, later)
    assert _run(clone, later) != want  # the copy's generator did not see the last draws
    clone = copy.deepcopy(env)
    assert _run(clone, later) == _run(env, later)


def test_a_generator_assigned_from_outside_is_recorded_and_a_seeded_reset_is_private() -> None:
    env = palaestra.make("BipedalWalker-v3")
    env.reset(seed=0)
    env.unwrapped.np_random = np.random.default_rng(7)
    env.step(np.zeros(4, dtype=np.float32))
    assert env.unwrapped._calls[-1][1] == np.random.default_rng(7).bit_generator.state
    env.reset(seed=1)  # a fresh generator that no one else holds
    env.step(np.zeros(4, dtype=np.float32))
    assert env.unwrapped._calls[-1][1] is None


def test_copies_get_their_own_generator_and_keep_it_private() -> None:
    env = palaestra.make("LunarLander-v3").unwrapped
    env.reset(seed=2)
    _run(env, [2, 1, 3])
    for clone in (copy.copy(env), copy.deepcopy(env), pickle.loads(pickle.dumps(env))):
        assert clone._rng is not env._rng
        assert clone._rng.bit_generator.state == env._rng.bit_generator.state
        clone.step(2)
        assert clone._calls[-1][1] is None  # private: only the copy holds it
        assert env._rng.bit_generator.state != clone._rng.bit_generator.state


def test_past_the_limit_the_env_keeps_its_world_and_a_copy_warns(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The cap bounds the history, never the env's physics: the env keeps its one world as
    Gymnasium's does; a copy made later replays the calls since the cut in a fresh world."""
    monkeypatch.setattr(_common, "MAX_REPLAYED_CALLS", 12)
    env = palaestra.make("BipedalWalker-v3")
    reference = palaestra.make("BipedalWalker-v3")  # never copied, no cut in its physics
    for walker in (env, reference):
        walker.reset(seed=0)
    first = _actions(env, 20, 0)
    assert _run(env, first) == _run(reference, first)
    world = env.unwrapped.world
    env.reset()  # 21 calls recorded: the history restarts here, the world stays
    reference.reset()
    assert env.unwrapped.world is world
    assert [kind for kind, *_ in env.unwrapped._calls] == ["reset"]
    second = _actions(env, 5, 1)
    assert _run(env, second) == _run(reference, second)
    with pytest.warns(UserWarning, match=r"^BipedalWalker has run more than 12 calls in one world"):
        clone = copy.deepcopy(env)
    assert len(clone.unwrapped._calls) == 6
    later = _actions(env, 10, 2)
    assert _run(env, later) == _run(reference, later)  # the original's physics never changed
    assert len(_run(clone, later)) == len(later)  # the copy runs on, approximately


def test_lunar_lander_keeps_only_the_current_episode() -> None:
    env = palaestra.make("LunarLander-v3")
    env.reset(seed=0)
    _run(env, [0] * 5)
    env.reset(seed=1)
    _run(env, [2] * 3)
    assert [kind for kind, *_ in env.unwrapped._calls] == ["reset", "step", "step", "step"]


def test_an_invalid_action_is_not_recorded() -> None:
    env = palaestra.make("LunarLander-v3")
    env.reset(seed=0)
    with pytest.raises(palaestra.error.InvalidAction):
        env.step(7)
    env.step(1)
    clone = copy.deepcopy(env)
    assert _run(clone, [2, 2, 3]) == _run(env, [2, 2, 3])


def test_constructor_arguments_and_spec_come_along() -> None:
    env = palaestra.make("LunarLander-v3", continuous=True, enable_wind=True, gravity=-5.0)
    env.reset(seed=2)
    clone = pickle.loads(pickle.dumps(env))
    inner = clone.unwrapped
    assert (inner.continuous, inner.enable_wind, inner.gravity) == (True, True, -5.0)
    assert clone.spec == env.spec
    actions = _actions(env, 10, 0)
    assert _run(clone, actions) == _run(env, actions)


def test_gymnasium_copies_are_fresh_envs_not_the_same_trajectory() -> None:
    # Why this is a documented difference: Gymnasium's EzPickle rebuilds from the constructor
    # arguments, so its copy has no lander until it is reset (its step asserts one).
    gymnasium = pytest.importorskip("gymnasium")
    env = gymnasium.make("LunarLander-v3")
    env.reset(seed=0)
    clone = pickle.loads(pickle.dumps(env))
    with pytest.raises(AssertionError):
        clone.step(0)


def test_the_gymnasium_named_subclasses_copy_as_themselves() -> None:
    from palaestra.envs.box2d import BipedalWalkerHardcore, LunarLanderContinuous

    for env in (LunarLanderContinuous(), BipedalWalkerHardcore()):
        env.reset(seed=0)
        clone = pickle.loads(pickle.dumps(env))
        assert type(clone) is type(env)
        actions = _actions(env, 5, 0)
        assert _run(clone, actions) == _run(env, actions)
