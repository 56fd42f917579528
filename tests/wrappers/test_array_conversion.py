"""``ArrayConversion``/``NumpyToTorch`` (single and vector): the types Gymnasium's wrappers
return (its docstring example: tensors, a float reward, bool flags) and the same numbers as
the unwrapped env. Gymnasium's own wrappers need ``array_api_compat`` (not installed), so
the reference values come from the numpy env itself, which equals Gymnasium's CartPole."""

from __future__ import annotations

from collections import namedtuple
from typing import Any

import numpy as np
import pytest

import palaestra as gym
from palaestra.vector import SyncVectorEnv
from palaestra.wrappers import ArrayConversion, NumpyToTorch
from palaestra.wrappers import vector as vector_wrappers
from palaestra.wrappers.array_conversion import array_conversion

torch = pytest.importorskip("torch")


def test_single_env_types_and_values() -> None:
    env = NumpyToTorch(gym.make("CartPole-v1"))
    reference = gym.make("CartPole-v1")
    obs, _ = env.reset(seed=4)
    want, _ = reference.reset(seed=4)
    assert isinstance(obs, torch.Tensor) and obs.dtype == torch.float32
    np.testing.assert_array_equal(obs.numpy(), want)
    for action in [1, 0, 1, 1]:
        obs, reward, terminated, truncated, _info = env.step(torch.tensor(action))
        want, want_reward, *_ = reference.step(action)
        assert isinstance(obs, torch.Tensor) and np.array_equal(obs.numpy(), want)
        assert type(reward) is float and reward == want_reward
        assert type(terminated) is bool and type(truncated) is bool
    assert env.device is None and env.spec is not None


class _Spy(gym.Env[Any, Any]):
    """Records the actions and reset options it receives; answers with numpy values."""

    observation_space = gym.spaces.Box(-1, 1, (2,))
    action_space = gym.spaces.Box(-1, 1, (2,))
    render_mode = "rgb_array"

    def __init__(self) -> None:
        self.seen: list[Any] = []

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        self.seen.append(options)
        return np.zeros(2, np.float32), {"extra": np.ones(3), "name": "spy", "n": 2}

    def step(self, action: Any) -> Any:
        self.seen.append(action)
        return np.ones(2, np.float32), np.float64(0.5), np.bool_(True), False, {"k": 1.5}

    def render(self) -> np.ndarray:
        return np.zeros((2, 2, 3), np.uint8)


def test_actions_reach_the_env_as_numpy_and_infos_come_back_converted() -> None:
    spy = _Spy()
    env = ArrayConversion(spy, env_xp=np, target_xp=torch)
    _obs, info = env.reset(options={"scale": torch.tensor([2.0])})
    assert isinstance(spy.seen[0]["scale"], np.ndarray)
    assert isinstance(info["extra"], torch.Tensor) and info["name"] == "spy"
    assert isinstance(info["n"], torch.Tensor) and int(info["n"]) == 2
    _, reward, terminated, _, info = env.step(torch.tensor([0.1, -0.2]))
    assert isinstance(spy.seen[1], np.ndarray) and spy.seen[1].dtype == np.float32
    assert reward == 0.5 and terminated is True and isinstance(info["k"], torch.Tensor)
    assert isinstance(env.render(), torch.Tensor)


def test_array_conversion_of_nested_values() -> None:
    Pair = namedtuple("Pair", "a b")
    array = np.arange(3.0)
    value = {"x": (array, [1, 2.5]), "p": Pair(np.int64(3), None), "s": "text"}
    out = array_conversion(value, torch)
    assert isinstance(out["x"], tuple) and isinstance(out["x"][1], list)
    assert isinstance(out["p"], Pair) and out["p"].b is None and out["s"] == "text"
    out["x"][0][0] = 7.0  # numpy -> torch on the CPU shares memory (Gymnasium's DLPack too)
    assert array[0] == 7.0
    back = array_conversion(out, np)
    assert isinstance(back["x"][0], np.ndarray) and back["x"][0][0] == 7.0
    with pytest.raises(TypeError, match="No known conversion"):
        array_conversion(object(), torch)


def test_vector_wrapper_converts_batches() -> None:
    envs = vector_wrappers.NumpyToTorch(SyncVectorEnv([lambda: gym.make("CartPole-v1")] * 2))
    reference = SyncVectorEnv([lambda: gym.make("CartPole-v1")] * 2)
    obs, _ = envs.reset(seed=[1, 2])
    want, _ = reference.reset(seed=[1, 2])
    assert isinstance(obs, torch.Tensor) and np.array_equal(obs.numpy(), want)
    for _ in range(3):
        obs, rewards, terminated, truncated, _infos = envs.step(torch.tensor([0, 1]))
        want, want_rewards, want_term, want_trunc, _ = reference.step(np.array([0, 1]))
        assert np.array_equal(obs.numpy(), want)
        for got, ref in [(rewards, want_rewards), (terminated, want_term), (truncated, want_trunc)]:
            assert isinstance(got, torch.Tensor) and np.array_equal(got.numpy(), ref)
    assert vector_wrappers.ArrayConversion is not None


def test_bad_modules() -> None:
    with pytest.raises(ValueError, match="target_xp must be an array module"):
        ArrayConversion(gym.make("CartPole-v1"), env_xp=np, target_xp="torch")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="env_xp must be an array module"):
        vector_wrappers.ArrayConversion(
            SyncVectorEnv([lambda: gym.make("CartPole-v1")]), env_xp=42, target_xp=torch
        )
