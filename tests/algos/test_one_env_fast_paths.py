"""The shortcuts DQN's one-env loop takes (issue 28, goal 5, fourth pass) give what the general
code gives, bit for bit: ReLU against cached zeros, the float32 input passed through, the one-env
engine step, the one-row observation copy and the replay ring's ``terminated`` without
time-outs."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import palaestra
from palaestra import spaces
from palaestra.algos.common.transition_ring import TransitionRing
from palaestra.algos.learners import mlp
from palaestra.algos.learners.learner import _flat_input
from palaestra.core import Env
from palaestra.spaces.batched_samples import concatenate_array
from palaestra.vec_env import DummyVecEnv
from palaestra.vector.engine import LoopEngine

SPECIALS = np.array(
    [0.0, -0.0, 1.0, -1.0, np.inf, -np.inf, np.nan, -np.nan, 1e-45, -1e-45, 3.4e38, -3.4e38],
    dtype=np.float32,
)


def _bits(x: np.ndarray) -> list[int]:
    return np.ascontiguousarray(x).view(np.uint32).ravel().tolist()


@pytest.mark.parametrize("shape", [(1, 120), (128, 64), (3, 7)])
def test_relu_against_zeros_equals_the_scalar_maximum(shape: tuple[int, int]) -> None:
    rng = np.random.default_rng(0)
    raw = rng.integers(0, 2**32, size=shape, dtype=np.uint64).astype(np.uint32)
    h = raw.view(np.float32).copy()  # every kind of float32: NaN payloads, subnormals, -0.0
    h.ravel()[: SPECIALS.size] = SPECIALS[: h.size]
    expected = np.maximum(h, 0.0)
    out = mlp._np_activate(h, ("relu", 0.0))
    assert out is h  # in place, as before
    assert _bits(out) == _bits(expected)
    zeros = mlp._zeros(shape)
    assert not zeros.flags.writeable and not zeros.any()


def test_float32_batches_pass_through_and_others_are_converted_as_before() -> None:
    x = np.arange(6, dtype=np.float32).reshape(2, 3)
    assert _flat_input(x) is x
    wide = np.arange(12, dtype=np.float32).reshape(2, 2, 3)
    assert _flat_input(wide).shape == (2, 6)
    doubles = np.arange(6, dtype=np.float64).reshape(2, 3)
    converted = _flat_input(doubles)
    assert converted.dtype == np.float32 and converted.tolist() == doubles.tolist()
    with pytest.raises(ValueError, match="cannot reshape array of size 0"):
        _flat_input(np.zeros((0, 3), np.float32))  # an empty batch is refused, as before


class Drifting(Env[np.ndarray, Any]):
    """Observations in ``obs_dtype`` (float64 into a float32 space tests the cast), episodes
    of random length, an info key per step."""

    def __init__(self, obs_dtype: Any = np.float32, action_space: Any = None) -> None:
        self.observation_space = spaces.Box(-1e3, 1e3, (3,), np.float32)
        self.action_space = action_space if action_space is not None else spaces.Discrete(3)
        self.obs_dtype = obs_dtype
        self.t = 0

    def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[Any, dict]:
        super().reset(seed=seed)
        self.t = 0
        return self.np_random.normal(size=3).astype(self.obs_dtype), {"reset": True}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        self.t += 1
        obs = (self.np_random.normal(size=3) + np.sum(action)).astype(self.obs_dtype)
        reward = float(self.np_random.normal())
        terminated = bool(self.np_random.random() < 0.1)
        truncated = self.t >= 7
        return obs, reward, terminated, truncated, {"t": self.t, "action": action}


def _same(a: Any, b: Any) -> None:
    if isinstance(a, np.ndarray):
        assert type(b) is np.ndarray and a.dtype == b.dtype and a.shape == b.shape
        assert _bits(a.astype(np.float32)) == _bits(b.astype(np.float32))
    elif isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            _same(a[key], b[key])
    elif isinstance(a, list):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            _same(x, y)
    else:
        assert type(a) is type(b) and a == b


@pytest.mark.parametrize("obs_dtype", [np.float32, np.float64])
@pytest.mark.parametrize("kind", ["discrete", "box"])
def test_one_env_step_equals_the_general_loop(obs_dtype: Any, kind: str) -> None:
    """ndarray actions take the one-row path; the same actions as a list go through the loop
    (``iterate``): every step's observations, rewards, dones and infos are the same."""
    space = spaces.Discrete(3) if kind == "discrete" else spaces.Box(-1.0, 1.0, (2,), np.float32)
    fast, slow = (DummyVecEnv([lambda: Drifting(obs_dtype, space)]) for _ in range(2))
    for env in (fast, slow):
        env.seed(3)
        env.action_space.seed(4)
    _same(fast.reset(), slow.reset())
    for _ in range(60):
        action = np.array([fast.action_space.sample()])
        step_fast = fast.step(action)
        step_slow = slow.step(list(action))
        for a, b in zip(step_fast, step_slow):
            _same(a, b)
        _same(fast.reset_infos, slow.reset_infos)


def test_one_env_engine_refuses_what_the_loop_refuses() -> None:
    engine = LoopEngine([lambda: Drifting()], "same", "test")
    engine.reset(None, [0], None)
    engine._sent = (np.array([1, 2]), None)  # past check_actions_batch: the loop's own check
    with pytest.raises(palaestra.error.InvalidAction, match="Got more than 1 actions"):
        engine.step_recv()


def test_one_row_observation_copy_casts_like_copyto() -> None:
    space = spaces.Box(-1.0, 1.0, (2,), np.float32)
    out = np.zeros((1, 2), np.float32)
    assert concatenate_array(space, [np.array([0.5, -2.0], np.float32)], out) is out
    assert out.tolist() == [[0.5, -2.0]]
    with np.errstate(over="ignore"):  # float64: same_kind cast, 1e300 overflows to inf
        concatenate_array(space, [np.array([0.1, 1e300])], out)
    assert _bits(out) == _bits(np.array([[0.1, np.inf]], np.float32))
    with pytest.raises(TypeError, match="same_kind"):
        concatenate_array(space, [np.array([1 + 2j, 0j])], out)


@pytest.mark.parametrize("handle", [True, False])
def test_ring_terminated_without_timeouts_is_the_general_formula(handle: bool) -> None:
    ring = TransitionRing(16, spaces.Box(-1, 1, (2,)), spaces.Discrete(2), 2, "cpu", handle)
    obs = np.zeros((2, 2), np.float32)
    cases = [
        (np.array([True, False]), np.array([False, False])),
        (np.array([True, True]), np.array([True, False])),
        (np.array([0.5, 0.0]), np.array([False, False])),  # non-bool dones: the general path
        ([True, False], [False, False]),
        (np.array([False, True]), np.array([False, True])),
    ]
    for dones, timeouts in cases:
        row = ring.pos
        ring.add(obs, obs, np.array([0, 1]), np.zeros(2, np.float32), dones, timeouts)
        if handle:
            expected = np.logical_and(dones, np.logical_not(timeouts))
        else:
            expected = dones
        got = np.zeros(2, np.float32)
        got[:] = expected
        assert ring.terminated[row].tolist() == got.tolist()


def test_numpy_ops_clip_equals_np_clip_for_the_huber_vjp() -> None:
    """DQN's loss VJP clips with ``numpy_ops.clip``: np.clip's values, every kind of float32."""
    from palaestra.algos.learners.xp import numpy_ops

    rng = np.random.default_rng(1)
    x = rng.integers(0, 2**32, size=100_000, dtype=np.uint64).astype(np.uint32).view(np.float32)
    x[: SPECIALS.size] = SPECIALS
    with np.errstate(invalid="ignore"):
        assert _bits(numpy_ops.clip(x, -1.0, 1.0)) == _bits(np.clip(x, -1.0, 1.0))
