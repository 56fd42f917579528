"""Each wrapper against Gymnasium 1.x's on the same toy env, seed and actions.

Observations, rewards, flags and infos must be equal in value *and* type, and the spaces must
have the same reprs.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from tests.wrappers.conftest import GYM, assert_same, pal, rollout


def _with_spec(env: Any, lib: Any, max_steps: int = 30) -> Any:
    env.spec = lib.EnvSpec("Toy-v0", max_episode_steps=max_steps)
    return env


f32 = np.float32

# id -> (toy, wrap(env, lib), rollout kwargs)
CASES: dict[str, tuple[str, Any, dict[str, Any]]] = {
    "TransformObservation": (
        "ToyContinuous",
        lambda e, L: L.W.TransformObservation(
            e, lambda o: o * 2 + 1, L.spaces.Box(-9.0, 11.0, (3,), f32)
        ),
        {},
    ),
    "TransformObservation-keep-space": (
        "ToyContinuous",
        lambda e, L: L.W.TransformObservation(e, np.abs, None),
        {},
    ),
    "TransformAction": (
        "ToyContinuous",
        lambda e, L: L.W.TransformAction(e, lambda a: a * 0.5, L.spaces.Box(-2.0, 2.0, (2,), f32)),
        {},
    ),
    "TransformReward": ("ToyChain", lambda e, L: L.W.TransformReward(e, lambda r: 2 * r + 1), {}),
    "ClipAction": ("ToyContinuous", lambda e, L: L.W.ClipAction(e), {}),
    "RescaleAction-scalar": ("ToyContinuous", lambda e, L: L.W.RescaleAction(e, 0.0, 1.0), {}),
    "RescaleAction-array": (
        "ToyContinuous",
        lambda e, L: L.W.RescaleAction(e, np.array([-3.0, 0.5], f32), np.array([3.0, 0.75], f32)),
        {},
    ),
    "ClipReward": ("ToyContinuous", lambda e, L: L.W.ClipReward(e, -0.5, 0.5), {}),
    "ClipReward-min-only": ("ToyChain", lambda e, L: L.W.ClipReward(e, min_reward=0.0), {}),
    "ClipReward-max-only": ("ToyContinuous", lambda e, L: L.W.ClipReward(e, max_reward=0.1), {}),
    "NormalizeObservation": (
        "ToyContinuous",
        lambda e, L: L.W.NormalizeObservation(e),
        {"steps": 200},
    ),
    "NormalizeObservation-eps": (
        "ToyContinuous",
        lambda e, L: L.W.NormalizeObservation(e, epsilon=0.5),
        {},
    ),
    "NormalizeReward": ("ToyContinuous", lambda e, L: L.W.NormalizeReward(e), {"steps": 200}),
    "NormalizeReward-gamma": (
        "ToyChain",
        lambda e, L: L.W.NormalizeReward(e, gamma=0.5, epsilon=1e-3),
        {"steps": 100},
    ),
    "FlattenObservation-box": ("ToyContinuous", lambda e, L: L.W.FlattenObservation(e), {}),
    "FlattenObservation-discrete": ("ToyChain", lambda e, L: L.W.FlattenObservation(e), {}),
    "FlattenObservation-dict": ("ToyDict", lambda e, L: L.W.FlattenObservation(e), {}),
    "FlattenObservation-tuple": ("ToyTuple", lambda e, L: L.W.FlattenObservation(e), {}),
    "FrameStack-reset": ("ToyContinuous", lambda e, L: L.W.FrameStackObservation(e, 4), {}),
    "FrameStack-zero": (
        "ToyContinuous",
        lambda e, L: L.W.FrameStackObservation(e, 3, padding_type="zero"),
        {},
    ),
    "FrameStack-custom": (
        "ToyContinuous",
        lambda e, L: L.W.FrameStackObservation(
            e, 2, padding_type=np.array([1.0, -1.0, 0.5], dtype=f32)
        ),
        {},
    ),
    "FrameStack-1": ("ToyContinuous", lambda e, L: L.W.FrameStackObservation(e, 1), {}),
    "FrameStack-discrete": ("ToyChain", lambda e, L: L.W.FrameStackObservation(e, 3), {}),
    "FrameStack-dict": (
        "ToyDict",
        lambda e, L: L.W.FrameStackObservation(e, 2, padding_type="zero"),
        {},
    ),
    "DtypeObservation-box": ("ToyContinuous", lambda e, L: L.W.DtypeObservation(e, np.float64), {}),
    "DtypeObservation-discrete": ("ToyChain", lambda e, L: L.W.DtypeObservation(e, np.float32), {}),
    "ReshapeObservation": ("ToyContinuous", lambda e, L: L.W.ReshapeObservation(e, (3, 1)), {}),
    "ReshapeObservation-image": ("ToyImage", lambda e, L: L.W.ReshapeObservation(e, (30, 3)), {}),
    "RescaleObservation": (
        "ToyContinuous",
        lambda e, L: L.W.RescaleObservation(e, f32(-1.0), f32(1.0)),
        {},
    ),
    "RescaleObservation-array": (
        "ToyContinuous",
        lambda e, L: L.W.RescaleObservation(
            e, np.array([0.0, -1.0, 2.0], dtype=f32), np.array([1.0, 1.0, 3.0], dtype=f32)
        ),
        {},
    ),
    "TimeAwareObservation": (
        "ToyContinuous",
        lambda e, L: L.W.TimeAwareObservation(_with_spec(e, L)),
        {},
    ),
    "TimeAwareObservation-normalized": (
        "ToyContinuous",
        lambda e, L: L.W.TimeAwareObservation(_with_spec(e, L), normalize_time=True),
        {},
    ),
    "TimeAwareObservation-unflattened": (
        "ToyContinuous",
        lambda e, L: L.W.TimeAwareObservation(_with_spec(e, L), flatten=False),
        {},
    ),
    "TimeAwareObservation-dict": (
        "ToyDict",
        lambda e, L: L.W.TimeAwareObservation(_with_spec(e, L), flatten=False, dict_time_key="T"),
        {},
    ),
    "TimeAwareObservation-tuple": (
        "ToyTuple",
        lambda e, L: L.W.TimeAwareObservation(_with_spec(e, L)),
        {},
    ),
    "DelayObservation-0": ("ToyContinuous", lambda e, L: L.W.DelayObservation(e, 0), {}),
    "DelayObservation-3": ("ToyContinuous", lambda e, L: L.W.DelayObservation(e, 3), {}),
    "DelayObservation-discrete": ("ToyChain", lambda e, L: L.W.DelayObservation(e, 2), {}),
    "StickyAction": ("ToyChain", lambda e, L: L.W.StickyAction(e, 0.5), {"steps": 120}),
    "StickyAction-duration": (
        "ToyContinuous",
        lambda e, L: L.W.StickyAction(e, 0.3, repeat_action_duration=(1, 4)),
        {"steps": 120},
    ),
    "RepeatAction": ("ToyChain", lambda e, L: L.W.RepeatAction(e, 3), {}),
    "RepeatAction-continuous": ("ToyContinuous", lambda e, L: L.W.RepeatAction(e, 4), {}),
    "FilterObservation-dict": (
        "ToyDict",
        lambda e, L: L.W.FilterObservation(e, ["vel", "count"]),
        {},
    ),
    "FilterObservation-tuple": ("ToyTuple", lambda e, L: L.W.FilterObservation(e, [2, 0]), {}),
    "DiscretizeObservation": ("ToyContinuous", lambda e, L: L.W.DiscretizeObservation(e, 4), {}),
    "DiscretizeObservation-bins-tuple": (
        "ToyContinuous",
        lambda e, L: L.W.DiscretizeObservation(e, (2, 5, 3)),
        {},
    ),
    "DiscretizeObservation-multidiscrete": (
        "ToyContinuous",
        lambda e, L: L.W.DiscretizeObservation(e, (3, 1, 6), multidiscrete=True),
        {},
    ),
    "DiscretizeAction": ("ToyContinuous", lambda e, L: L.W.DiscretizeAction(e, 5), {}),
    "DiscretizeAction-no-table": (  # 300**2 actions: centres computed per step
        "ToyContinuous",
        lambda e, L: L.W.DiscretizeAction(e, 300),
        {},
    ),
    "DiscretizeAction-multidiscrete-no-table": (
        "ToyContinuous",
        lambda e, L: L.W.DiscretizeAction(e, 300, multidiscrete=True),
        {},
    ),
    "DiscretizeAction-multidiscrete": (
        "ToyContinuous",
        lambda e, L: L.W.DiscretizeAction(e, (2, 7), multidiscrete=True),
        {},
    ),
    "MaxAndSkipObservation": ("ToyContinuous", lambda e, L: L.W.MaxAndSkipObservation(e), {}),
    "MaxAndSkipObservation-2": ("ToyImage", lambda e, L: L.W.MaxAndSkipObservation(e, skip=2), {}),
    "GrayscaleObservation": ("ToyImage", lambda e, L: L.W.GrayscaleObservation(e), {}),
    "GrayscaleObservation-keep-dim": (
        "ToyImage",
        lambda e, L: L.W.GrayscaleObservation(e, keep_dim=True),
        {},
    ),
    "Autoreset": ("ToyChain", lambda e, L: L.W.Autoreset(e), {"manual_reset": False, "steps": 100}),
    "Autoreset-continuous": (
        "ToyContinuous",
        lambda e, L: L.W.Autoreset(e),
        {"manual_reset": False, "steps": 100},
    ),
    "stack": (
        "ToyContinuous",
        lambda e, L: L.W.NormalizeReward(
            L.W.FrameStackObservation(L.W.ClipAction(L.W.RescaleAction(e, -2.0, 2.0)), 2)
        ),
        {},
    ),
}


def _scrub_times(records: list[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
    for record in records:
        info = record[-1]
        if "episode" in info:
            assert isinstance(info["episode"]["t"], float) and info["episode"]["t"] >= 0
            info["episode"]["t"] = 0.0
    return records


@pytest.mark.parametrize("case", sorted(CASES))
def test_matches_gymnasium(case: str) -> None:
    toy, wrap, kwargs = CASES[case]
    theirs, expected = rollout(GYM, toy, wrap, **kwargs)
    ours, got = rollout(pal(), toy, wrap, **kwargs)
    assert repr(ours.observation_space) == repr(theirs.observation_space)
    assert repr(ours.action_space) == repr(theirs.action_space)
    assert len(got) == len(expected)
    for i, (g, e) in enumerate(zip(got, expected)):
        assert_same(g, e, f"record {i}")


def test_record_episode_statistics_matches_gymnasium() -> None:
    def wrap(e: Any, L: Any) -> Any:
        return L.W.RecordEpisodeStatistics(e, buffer_length=3, stats_key="ep")

    theirs, expected = rollout(GYM, "ToyContinuous", wrap, steps=150)
    ours, got = rollout(pal(), "ToyContinuous", wrap, steps=150)
    assert sum("ep" in r[-1] for r in got) > 3  # several episodes, so the queues wrap
    assert_same(_scrub_ep(got), _scrub_ep(expected))
    assert list(ours.return_queue) == list(theirs.return_queue)
    assert list(ours.length_queue) == list(theirs.length_queue)
    assert len(ours.time_queue) == len(theirs.time_queue) == 3
    assert ours.episode_count == theirs.episode_count


def _scrub_ep(records: list[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
    for record in records:
        if "ep" in record[-1]:
            t = record[-1]["ep"]["t"]
            assert isinstance(t, float) and 0 <= t < 5
            record[-1]["ep"]["t"] = 0.0
    return records


def test_normalize_freeze_matches_gymnasium() -> None:
    """Freezing the statistics mid-run (evaluation mode) keeps matching Gymnasium."""
    out = []
    for lib in (GYM, pal()):
        env = lib.W.NormalizeReward(lib.W.NormalizeObservation(_toy(lib)))
        env.reset(seed=3)
        rng = np.random.default_rng(0)
        seq = []
        for i in range(80):
            if i == 40:
                env.update_running_mean = False
                env.env.update_running_mean = False
                assert env.update_running_mean is False
            obs, r, term, trunc, _ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
            seq.append((obs, r))
            if term or trunc:
                env.reset()
        out.append((seq, env.env.obs_rms.mean.copy(), env.return_rms.var))
    (theirs, t_mean, t_var), (ours, o_mean, o_var) = out
    assert_same(ours, theirs)
    assert_same(o_mean, t_mean)
    assert_same(o_var, t_var)


def _toy(lib: Any) -> Any:
    from tests.wrappers.conftest import make_toy

    return make_toy(lib, "ToyContinuous")


def test_discretize_reverts_match_gymnasium() -> None:
    envs = []
    for lib in (GYM, pal()):
        toy = _toy(lib)
        envs.append(
            (
                lib.W.DiscretizeObservation(toy, (3, 4, 2)),
                lib.W.DiscretizeObservation(toy, 3, multidiscrete=True),
                lib.W.DiscretizeAction(toy, (4, 3)),
                lib.W.DiscretizeAction(toy, 5, multidiscrete=True),
            )
        )
    (g_obs, g_mobs, g_act, g_mact), (p_obs, p_mobs, p_act, p_mact) = envs
    for i in range(24):
        assert_same(p_obs.revert_observation(i), g_obs.revert_observation(i))
    for idx in ([0, 0, 0], [2, 1, 0], [1, 2, 2]):
        assert_same(p_mobs.revert_observation(idx), g_mobs.revert_observation(idx))
    rng = np.random.default_rng(1)
    for _ in range(20):
        a = rng.uniform(-1.2, 1.2, 2).astype(np.float32)
        assert int(p_act.revert_action(a)) == int(g_act.revert_action(a))
        assert_same(p_mact.revert_action(a), g_mact.revert_action(a))
