"""The Atari training path: CnnPolicy on stacked 84x84 frames (DQN with the frame buffer, PPO),
device choice, save/load. Fast tests use a fake image env; ``slow`` ones the real Breakout."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch

from palaestra import spaces
from palaestra.algos import DQN, PPO
from palaestra.algos.common.base import resolve_device
from palaestra.algos.common.frame_replay_buffer import FrameReplayBuffer
from palaestra.algos.networks import NatureCNN
from palaestra.core import Env
from palaestra.vec_env import DummyVecEnv, VecFrameStack
from palaestra.wrappers import TimeLimit


class FakeAtari(Env[np.ndarray, int]):
    """84x84x1 uint8 frames like ``AtariWrapper``'s: a bright bar whose column follows the
    last action; reward 1 for action 1; games end at random, some by time limit."""

    observation_space = spaces.Box(0, 255, (84, 84, 1), np.uint8)
    action_space = spaces.Discrete(4)

    def _frame(self, column: int) -> np.ndarray:
        frame = np.zeros((84, 84, 1), np.uint8)
        frame[:, 20 * column : 20 * column + 4] = 200
        frame[int(self.np_random.integers(84)), :, 0] = 255
        return frame

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        return self._frame(0), {}

    def step(self, action: int) -> Any:
        done = bool(self.np_random.random() < 0.05)
        return self._frame(int(action)), float(action == 1), done, False, {}


def _fake_env(n_envs: int = 2) -> Any:
    venv = DummyVecEnv([lambda: TimeLimit(FakeAtari(), 30) for _ in range(n_envs)])
    return VecFrameStack(venv, n_stack=4)


def _assert_same_predictions(model: Any, loaded: Any, obs: np.ndarray) -> None:
    a, _ = model.predict(obs, deterministic=True)
    b, _ = loaded.predict(obs, deterministic=True)
    np.testing.assert_array_equal(a, b)
    for x, y in zip(model.policy.state_dict().values(), loaded.policy.state_dict().values()):
        torch.testing.assert_close(x, y, rtol=0, atol=0)


def test_dqn_cnn_with_the_frame_buffer(tmp_path: Any) -> None:
    env = _fake_env()
    model = DQN(
        "CnnPolicy",
        env,
        optimize_memory_usage=True,
        buffer_size=400,
        learning_starts=40,
        batch_size=8,
        train_freq=4,
        target_update_interval=50,
        seed=0,
    )
    assert model.device.type == "cpu"  # "auto": no GPU here
    assert isinstance(model.q_net.features_extractor, NatureCNN)
    assert model.q_net.features_extractor.cnn[0].in_channels == 4  # HWC stack read as CHW
    model.learn(120)
    buf = model.replay_buffer
    assert isinstance(buf, FrameReplayBuffer) and buf.size() == 60
    assert buf.layout == (2, 1) and buf.n_frames == 4
    assert buf.stored_frames() < 2 * 120  # about one frame per transition, not 8
    model.save(tmp_path / "dqn")
    loaded = DQN.load(tmp_path / "dqn", env=env)
    assert loaded.optimize_memory_usage and isinstance(loaded.replay_buffer, FrameReplayBuffer)
    _assert_same_predictions(model, loaded, env.reset())


def test_ppo_cnn_trains_and_round_trips(tmp_path: Any) -> None:
    env = _fake_env()
    model = PPO("CnnPolicy", env, n_steps=16, batch_size=16, n_epochs=2, seed=0)
    assert model.device.type == "cpu"
    model.learn(64)
    obs = env.reset()
    assert obs.shape == (2, 84, 84, 4) and obs.dtype == np.uint8
    model.save(tmp_path / "ppo")
    loaded = PPO.load(tmp_path / "ppo")
    _assert_same_predictions(model, loaded, obs)
    single, _ = loaded.predict(obs[0], deterministic=True)
    assert single.shape == () and 0 <= int(single) < 4


def test_cnn_reads_hwc_stacks_scaled_by_255() -> None:
    model = PPO("CnnPolicy", _fake_env(1), n_steps=8, batch_size=8, seed=0)
    obs = np.random.default_rng(0).integers(0, 256, (3, 84, 84, 4), dtype=np.uint8)
    policy = model.policy
    with torch.no_grad():
        chw = torch.as_tensor(obs).permute(0, 3, 1, 2).float() / 255.0
        expected = policy.value_head(policy.vf_net(policy.features_extractor(chw))).squeeze(1)
        values = policy.predict_values(torch.as_tensor(obs))
    torch.testing.assert_close(values, expected)


def test_auto_device_prefers_cuda_for_cnns(monkeypatch: pytest.MonkeyPatch) -> None:
    assert resolve_device("auto", "CnnPolicy") == torch.device(
        "cuda" if torch.cuda.is_available() else "cpu"
    )
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    assert resolve_device("auto", "CnnPolicy") == torch.device("cuda")
    assert resolve_device("auto", "MultiInputPolicy") == torch.device("cuda")
    assert resolve_device("auto", "MlpPolicy") == torch.device("cpu")
    assert resolve_device("cpu", "CnnPolicy") == torch.device("cpu")
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    assert resolve_device("auto", "CnnPolicy") == torch.device("cpu")


# -- the real game ------------------------------------------------------------------------------
def _breakout(n_envs: int) -> Any:
    pytest.importorskip("ale_py")
    from palaestra.vec_env import make_atari_env

    return VecFrameStack(make_atari_env("BreakoutNoFrameskip-v4", n_envs=n_envs, seed=0), 4)


@pytest.mark.slow
def test_dqn_on_breakout(tmp_path: Any) -> None:
    env = _breakout(2)
    assert env.observation_space.shape == (84, 84, 4)
    model = DQN(
        "CnnPolicy",
        env,
        optimize_memory_usage=True,
        buffer_size=2000,
        learning_starts=200,
        batch_size=16,
        seed=0,
    )
    model.learn(1000)
    buf = model.replay_buffer
    assert isinstance(buf, FrameReplayBuffer)
    assert buf.stored_frames() <= buf.size() * 2 * 1.05 + 6 * 2
    model.save(tmp_path / "dqn")
    model.save_replay_buffer(tmp_path / "rb")
    loaded = DQN.load(tmp_path / "dqn", env=env)
    loaded.load_replay_buffer(tmp_path / "rb")
    _assert_same_predictions(model, loaded, env.reset())
    loaded.learn(200, reset_num_timesteps=False)


@pytest.mark.slow
def test_ppo_on_breakout(tmp_path: Any) -> None:
    env = _breakout(4)
    model = PPO("CnnPolicy", env, n_steps=32, batch_size=64, n_epochs=1, seed=0)
    model.learn(256)
    model.save(tmp_path / "ppo")
    loaded = PPO.load(tmp_path / "ppo", env=env)
    _assert_same_predictions(model, loaded, env.reset())
