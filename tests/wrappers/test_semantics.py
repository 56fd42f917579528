# ruff: noqa: E501  (one case per line reads best in these tables)
"""Behaviour that parity alone does not pin down: Autoreset, padding, aliasing, specs, errors."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from tests.wrappers.conftest import WRAPPER_MODULES, make_toy, pal

import palaestra
from palaestra.core import ActionWrapper, ObservationWrapper, RewardWrapper, Wrapper
from palaestra.envs.env_spec import EnvSpec
from palaestra.spaces import Box
from palaestra.wrappers.common import TimeLimit

W = pal().W


def cont(**kwargs: Any) -> Any:
    return make_toy(pal(), "ToyContinuous", **kwargs)


def chain(**kwargs: Any) -> Any:
    return make_toy(pal(), "ToyChain", **kwargs)


class Recorder(Wrapper):
    """Remembers the actions that reached the inner env."""

    def __init__(self, env: Any) -> None:
        super().__init__(env)
        self.actions: list[Any] = []

    def step(self, action: Any) -> Any:
        self.actions.append(action)
        return self.env.step(action)


def test_autoreset_resets_on_the_step_after_the_end() -> None:
    env = W.Autoreset(cont(max_steps=3))
    env.reset(seed=0)
    for _ in range(2):
        *_, terminated, truncated, _ = env.step(np.zeros(2, np.float32))
        assert not (terminated or truncated)
    *_, truncated, info = env.step(np.zeros(2, np.float32))
    assert truncated and info == {"t": 3}
    # the action is ignored (the toy would fail on None), the reset result comes back
    obs, reward, terminated, truncated, info = env.step(None)
    assert (reward, terminated, truncated, info) == (0.0, False, False, {"t": 0})
    assert obs in env.observation_space
    assert env.step(np.zeros(2, np.float32))[-1] == {"t": 1}


def test_autoreset_flag_cleared_by_manual_reset() -> None:
    env = W.Autoreset(cont(max_steps=1))
    env.reset(seed=0)
    assert env.step(np.zeros(2, np.float32))[3]
    env.reset()
    assert env.step(np.zeros(2, np.float32))[-1] == {"t": 1}  # a real step, not a reset


def test_delay_pads_with_the_space_zero_and_fresh_arrays() -> None:
    inner = cont()
    env = W.TransformObservation(inner, lambda o: o + 10, Box(5.0, 15.0, (3,), np.float32))
    env = W.DelayObservation(env, 2)
    first, _ = env.reset(seed=0)
    np.testing.assert_array_equal(first, np.full(3, 5.0, np.float32))  # low > 0, so low
    first[:] = -1
    second = env.step(np.zeros(2, np.float32))[0]
    np.testing.assert_array_equal(second, np.full(3, 5.0, np.float32))
    third = env.step(np.zeros(2, np.float32))[0]
    assert np.all(third > 8)  # the reset observation, two steps late


def test_frame_stack_padding_and_order() -> None:
    def obs_of(env: Any, seed: int = 0) -> tuple[Any, Any, Any]:
        o0, _ = env.reset(seed=seed)
        o1 = env.step(np.zeros(2, np.float32))[0]
        return o0, o1, env

    raw0, _ = cont().reset(seed=0)
    (o0, o1, _) = obs_of(W.FrameStackObservation(cont(), 3, padding_type="zero"))
    np.testing.assert_array_equal(o0, np.stack([np.zeros(3), np.zeros(3), raw0]).astype(np.float32))
    np.testing.assert_array_equal(o1[:2], o0[1:])
    (o0, _, _) = obs_of(W.FrameStackObservation(cont(), 3))
    np.testing.assert_array_equal(o0, np.stack([raw0] * 3))
    pad = np.array([1.0, -1.0, 0.5], np.float32)
    (o0, o1, env) = obs_of(W.FrameStackObservation(cont(), 3, padding_type=pad))
    np.testing.assert_array_equal(o0, np.stack([pad, pad, raw0]))
    assert env.observation_space == Box(-5.0, 5.0, (3, 3), np.float32)


def test_frame_stack_returns_unaliased_arrays() -> None:
    env = W.FrameStackObservation(cont(), 2)
    obs, _ = env.reset(seed=0)
    kept = obs.copy()
    later = [env.step(np.ones(2, np.float32))[0] for _ in range(3)]
    np.testing.assert_array_equal(obs, kept)  # later steps did not write into it
    later[0][:] = 99
    assert not np.any(later[1] == 99)


def test_time_aware_finds_time_limit_in_the_stack() -> None:
    env = W.TimeAwareObservation(W.ClipReward(TimeLimit(cont(), 7), 0, 1), normalize_time=True)
    assert env.max_timesteps == 7
    obs, _ = env.reset(seed=0)
    assert obs[-1] == 0.0 and obs.shape == (4,)
    for t in range(1, 4):
        obs = env.step(np.zeros(2, np.float32))[0]
        assert obs[-1] == np.float32(t / 7)
    env = W.TimeAwareObservation(TimeLimit(cont(), 7), flatten=False)
    assert env.reset(seed=0)[0]["time"].tolist() == [0]


def test_repeat_action_stops_at_episode_end() -> None:
    rec = Recorder(cont(max_steps=5))
    env = W.RepeatAction(rec, 3)
    env.reset(seed=0)
    a = np.zeros(2, np.float32)
    _, reward, _, _, info = env.step(a)
    assert len(rec.actions) == 3 and info == {"t": 3} and isinstance(reward, float)
    *_, truncated, info = env.step(a)
    assert truncated and len(rec.actions) == 5 and info == {"t": 5}


def test_sticky_action_never_sticks_at_p0_and_not_after_reset() -> None:
    rec = Recorder(chain(max_steps=1000))
    env = W.StickyAction(rec, 0.0)
    env.reset(seed=0)
    for a in [0, 2, 1, 0, 2]:
        env.step(a)
    assert rec.actions == [0, 2, 1, 0, 2]
    rec.actions.clear()
    env = W.StickyAction(rec, 0.999, repeat_action_duration=2)
    env.reset(seed=0)
    for a in [2, 0, 0, 1, 1]:
        env.step(a)
    # the first action after reset is the agent's; then every action is the stuck one
    assert rec.actions == [2, 2, 2, 2, 2]


def test_clip_and_rescale_reach_the_inner_bounds() -> None:
    rec = Recorder(cont())
    env = W.ClipAction(rec)
    env.reset(seed=0)
    env.step(np.array([5.0, -7.0], np.float32))
    np.testing.assert_array_equal(rec.actions[-1], [1.0, -1.0])
    env = W.RescaleAction(rec, np.float32(0), np.float32(4))
    env.reset(seed=0)
    env.step(np.array([0.0, 4.0], np.float32))
    np.testing.assert_allclose(rec.actions[-1], [-1.0, 1.0])
    env.step(np.array([2.0, 1.0], np.float32))
    np.testing.assert_allclose(rec.actions[-1], [0.0, -0.5])


def test_max_and_skip_takes_the_max_of_the_last_two() -> None:
    rec = Recorder(cont())
    env = W.MaxAndSkipObservation(rec, skip=3)
    ref = cont()
    env.reset(seed=4)
    ref.reset(seed=4)
    a = np.array([0.5, -0.5], np.float32)
    frames = [ref.step(a)[0] for _ in range(3)]
    obs, *_ = env.step(a)
    np.testing.assert_array_equal(obs, np.maximum(frames[1], frames[2]))
    assert len(rec.actions) == 3


def test_normalize_observation_space_and_dtype() -> None:
    env = W.NormalizeObservation(cont())
    assert env.observation_space == Box(-np.inf, np.inf, (3,), np.float32)
    obs, _ = env.reset(seed=0)
    assert obs.dtype == np.float32
    env.update_running_mean = False
    count = env.obs_rms.count
    env.step(np.zeros(2, np.float32))
    assert env.obs_rms.count == count


def test_record_episode_statistics_queues() -> None:
    env = W.RecordEpisodeStatistics(chain(max_steps=4), buffer_length=2)
    env.reset(seed=0)
    episodes = 0
    while episodes < 3:
        *_, terminated, truncated, info = env.step(1)
        if terminated or truncated:
            episodes += 1
            ep = info["episode"]
            assert set(ep) == {"r", "l", "t"} and 1 <= ep["l"] <= 4 and ep["t"] >= 0
            env.reset()
    assert len(env.return_queue) == len(env.length_queue) == len(env.time_queue) == 2
    assert env.episode_count == 3


def _spec_env() -> Any:
    env = cont()
    env.spec = EnvSpec("Toy-v0", max_episode_steps=30)
    return env


@pytest.mark.parametrize(
    ("build", "name", "kwargs"),
    [
        (lambda e: W.ClipAction(e), "ClipAction", {}),
        (lambda e: W.RescaleAction(e, 0.0, 1.0), "RescaleAction", {"min_action": 0.0, "max_action": 1.0}),
        (lambda e: W.FrameStackObservation(e, 4), "FrameStackObservation", {"stack_size": 4, "padding_type": "reset"}),
        (lambda e: W.NormalizeReward(e, gamma=0.9), "NormalizeReward", {"gamma": 0.9, "epsilon": 1e-8}),
        (lambda e: W.RecordEpisodeStatistics(e), "RecordEpisodeStatistics", {"buffer_length": 100, "stats_key": "episode"}),
        (lambda e: W.TimeAwareObservation(e), "TimeAwareObservation", {"flatten": True, "normalize_time": False, "dict_time_key": "time"}),
        (lambda e: W.DiscretizeObservation(e, 3), "DiscretizeObservation", {"bins": 3, "multidiscrete": False}),
        (lambda e: W.Monitor(e), "Monitor", {"filename": None, "allow_early_resets": True, "reset_keywords": (), "info_keywords": (), "override_existing": True}),
    ],
)  # fmt: skip
def test_spec_records_the_wrapper(build: Any, name: str, kwargs: dict[str, Any]) -> None:
    env = build(_spec_env())
    last = env.spec.additional_wrappers[-1]
    assert last.name == name
    assert last.kwargs == kwargs
    assert last.entry_point == f"{type(env).__module__}:{name}"


def test_wrappers_have_the_right_base_and_no_getattr() -> None:
    template_base = {
        "TransformObservation": ObservationWrapper,
        "FilterObservation": ObservationWrapper,
        "FlattenObservation": ObservationWrapper,
        "DtypeObservation": ObservationWrapper,
        "DelayObservation": ObservationWrapper,
        "NormalizeObservation": ObservationWrapper,
        "TransformAction": ActionWrapper,
        "ClipAction": ActionWrapper,
        "RescaleAction": ActionWrapper,
        "DiscretizeAction": ActionWrapper,
        "StickyAction": ActionWrapper,
        "TransformReward": RewardWrapper,
        "ClipReward": RewardWrapper,
    }
    for name in WRAPPER_MODULES:
        cls = getattr(W, name)
        assert issubclass(cls, template_base.get(name, Wrapper)), name
        assert "__getattr__" not in {k for c in cls.__mro__ for k in vars(c)}, name


def test_lazy_table_agrees_with_the_modules() -> None:
    table = palaestra.wrappers._LAZY
    for name, module in WRAPPER_MODULES.items():
        if name in table:  # once the lead has added the entry
            assert table[name] == module
            assert getattr(palaestra.wrappers, name) is getattr(W, name)


def test_frame_stack_names_a_wrong_observation_shape() -> None:
    inner = cont()
    env = W.FrameStackObservation(
        W.TransformObservation(inner, lambda o: o[:2], None),
        3,  # claims (3,), returns (2,)
    )
    with pytest.raises(ValueError, match=r"observations of shape \(2,\), expected \(3,\)"):
        env.reset(seed=0)
