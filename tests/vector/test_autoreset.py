"""Autoreset modes, info stacking, seeding and reset_mask, against gymnasium's SyncVectorEnv.

Modelled on gymnasium's ``tests/vector``: the toy Counter envs end at different steps so
every mode's bookkeeping (reward 0 on NEXT_STEP resets, final_obs/final_info on SAME_STEP, the
DISABLED refusal) is visited, and infos carry every kind of value that stacking handles.
"""

from __future__ import annotations

from functools import partial

import gymnasium
import numpy as np
import pytest

from palaestra import error
from palaestra.vector import AutoresetMode, SyncVectorEnv

from .toys import assert_infos_equal, gym_counter, pal_counter

LENGTHS = (2, 3, 5)
MODES = ["NextStep", "SameStep", "Disabled"]


def _pair(mode: str, **kwargs):
    ours = SyncVectorEnv([partial(pal_counter, n, **kwargs) for n in LENGTHS], autoreset_mode=mode)
    theirs = gymnasium.vector.SyncVectorEnv(
        [partial(gym_counter, n, **kwargs) for n in LENGTHS],
        autoreset_mode=gymnasium.vector.AutoresetMode(mode),
    )
    return ours, theirs


def _assert_same(a, b):
    for x, y in zip(a[:-1], b[:-1]):
        np.testing.assert_array_equal(x, y)
        assert x.dtype == y.dtype
    assert_infos_equal(a[-1], b[-1])


@pytest.mark.parametrize("mode", MODES)
def test_modes_match_gymnasium_step_for_step(mode):
    ours, theirs = _pair(mode)
    rng = np.random.default_rng(0)
    o1, i1 = ours.reset(seed=3)
    o2, i2 = theirs.reset(seed=3)
    np.testing.assert_array_equal(o1, o2)
    assert_infos_equal(i1, i2)
    for _ in range(20):
        actions = rng.integers(0, 3, size=len(LENGTHS))
        a = ours.step(actions)
        b = theirs.step(actions)
        _assert_same(a, b)
        if mode == "Disabled":
            done = a[2] | a[3]
            if done.any():
                opts = {"reset_mask": done.copy()}
                r1 = ours.reset(options=dict(opts))
                r2 = theirs.reset(options=dict(opts))
                np.testing.assert_array_equal(r1[0], r2[0])
                assert_infos_equal(r1[1], r2[1])


def test_next_step_resets_on_the_step_after_the_end():
    envs = SyncVectorEnv([partial(pal_counter, 2)], autoreset_mode=AutoresetMode.NEXT_STEP)
    envs.reset(seed=0)
    envs.step(np.array([2]))
    _, reward, terminated, _, _ = envs.step(np.array([2]))
    assert terminated[0]
    obs, reward, terminated, truncated, infos = envs.step(np.array([2]))
    assert reward[0] == 0.0 and not terminated[0] and not truncated[0]
    assert obs[0, 1] == 0.0  # t == 0: a fresh episode
    assert "reset_start" in infos and "t" not in infos


def test_same_step_reports_final_obs_and_info():
    envs = SyncVectorEnv(
        [partial(pal_counter, 2), partial(pal_counter, 5)], autoreset_mode="SameStep"
    )
    envs.reset(seed=0)
    envs.step(np.array([1, 1]))
    obs, _, terminated, _, infos = envs.step(np.array([1, 1]))
    assert terminated.tolist() == [True, False]
    assert infos["_final_obs"].tolist() == [True, False]
    assert infos["final_obs"].dtype == object and infos["final_obs"][1] is None
    assert infos["final_obs"][0][1] == 2.0 and obs[0, 1] == 0.0
    assert infos["final_info"]["t"][0] == 2 and infos["final_info"]["_t"].tolist() == [True, False]
    # The other env's step info is at top level, the finished env's reset info too.
    assert infos["_t"].tolist() == [False, True]
    assert infos["_reset_start"].tolist() == [True, False]


def test_disabled_refuses_to_step_a_finished_env():
    envs = SyncVectorEnv(
        [partial(pal_counter, 1), partial(pal_counter, 4)], autoreset_mode="Disabled"
    )
    envs.reset(seed=0)
    envs.step(np.array([0, 0]))
    with pytest.raises(error.ResetNeeded, match=r"\[0\].*reset_mask"):
        envs.step(np.array([0, 0]))
    obs, infos = envs.reset(options={"reset_mask": np.array([True, False])})
    assert infos["_reset_start"].tolist() == [True, False]
    assert obs[1, 1] == 1.0  # env 1 kept its state
    envs.step(np.array([0, 0]))


def test_reset_mask_leaves_callers_options_alone_and_passes_the_rest():
    envs = SyncVectorEnv([partial(pal_counter, 3)] * 2)
    envs.reset(seed=0)
    options = {"reset_mask": np.array([False, True]), "offset": 5}
    _, infos = envs.reset(options=options)
    assert "reset_mask" in options
    assert infos["offset"].tolist() == [0, 5] and infos["_offset"].tolist() == [False, True]


@pytest.mark.parametrize(
    ("mask", "exc", "match"),
    [
        ([True, False], TypeError, "must be a numpy array"),
        (np.array([True]), ValueError, r"must have shape `\(2,\)`"),
        (np.array([1, 0]), TypeError, "dtype=np.bool_"),
        (np.array([False, False]), ValueError, "at least one True"),
    ],
)
def test_reset_mask_errors(mask, exc, match):
    envs = SyncVectorEnv([partial(pal_counter, 3)] * 2)
    with pytest.raises(exc, match=match):
        envs.reset(options={"reset_mask": mask})


def test_seeding_is_seed_plus_index_and_lists_work():
    envs = SyncVectorEnv([partial(pal_counter, 3)] * 3)
    envs.reset(seed=10)
    assert envs.np_random_seed == (10, 11, 12)
    singles = [pal_counter(3) for _ in range(3)]
    expected = [s.reset(seed=10 + i)[0] for i, s in enumerate(singles)]
    obs, _ = envs.reset(seed=10)
    np.testing.assert_array_equal(obs, np.stack(expected))
    envs.reset(seed=[4, None, 6])
    assert envs.np_random_seed[0] == 4 and envs.np_random_seed[2] == 6
    with pytest.raises(ValueError, match="length must match num_envs=3"):
        envs.reset(seed=[1, 2])


def test_call_get_attr_set_attr():
    envs = SyncVectorEnv([partial(pal_counter, n) for n in LENGTHS])
    assert envs.get_attr("length") == LENGTHS
    envs.set_attr("length", 9)
    assert envs.get_attr("length") == (9, 9, 9)
    envs.set_attr("length", [1, 2, 3])
    assert envs.call("length") == (1, 2, 3)
    with pytest.raises(ValueError, match="length equal to the number of environments"):
        envs.set_attr("length", [1, 2])


def test_copy_false_returns_the_engine_buffer():
    envs = SyncVectorEnv([partial(pal_counter, 3)] * 2, copy=False)
    obs, _ = envs.reset(seed=0)
    obs2 = envs.step(np.array([1, 1]))[0]
    assert obs is obs2
    copied = SyncVectorEnv([partial(pal_counter, 3)] * 2)
    a, _ = copied.reset(seed=0)
    b = copied.step(np.array([1, 1]))[0]
    assert a is not b and a[0, 1] == 0.0
