"""DQN's frame buffer (``optimize_memory_usage=True``): exactly the plain buffer's transitions,
each frame stored once."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch

from palaestra import spaces
from palaestra.algos import DQN
from palaestra.algos.common.frame_replay_buffer import FrameReplayBuffer, frame_layout
from palaestra.algos.common.model_io import ModelFileError
from palaestra.algos.common.transition_ring import TransitionRing
from palaestra.core import Env
from palaestra.vec_env import DummyVecEnv, VecFrameStack
from palaestra.wrappers import FrameStackObservation, TimeLimit

from .toys import Toy


class Frames(Env[np.ndarray, int]):
    """Random small images; some all-zero, some repeating the last one (the cases where a
    frame could be confused with padding); terminates with probability ``p_end``."""

    def __init__(self, shape: tuple[int, ...] = (5, 5, 1), p_end: float = 0.1) -> None:
        self.observation_space = spaces.Box(0, 255, shape, np.uint8)
        self.action_space = spaces.Discrete(3)
        self.p_end, self.last = p_end, np.zeros(shape, np.uint8)

    def _frame(self) -> np.ndarray:
        u = self.np_random.random()
        if u < 0.15:
            self.last = np.zeros_like(self.last)
        elif u > 0.3:
            self.last = self.np_random.integers(0, 4, self.last.shape).astype(np.uint8)
        return self.last.copy()

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        return self._frame(), {}

    def step(self, action: int) -> Any:
        done = bool(self.np_random.random() < self.p_end)
        return self._frame(), float(action), done, False, {}


def _vec(n_envs: int, stack: str, p_end: float = 0.1, limit: int = 7) -> Any:
    """Frame-stacked VecEnv: ``"vec"`` (VecFrameStack, zero padding, HWC), ``"wrapper"``
    (FrameStackObservation, first frame repeated, CHW) or ``"none"``."""

    def make() -> Any:
        if stack == "wrapper":
            return TimeLimit(FrameStackObservation(Frames((5, 5), p_end), 4), limit)
        return TimeLimit(Frames((5, 5, 1), p_end), limit)

    venv = DummyVecEnv([make for _ in range(n_envs)])
    venv.seed(0)
    return VecFrameStack(venv, 4) if stack == "vec" else venv


def _drive(venv: Any, buffers: list[Any], steps: int, seed: int = 0) -> int:
    """The DQN loop's bookkeeping: terminal observations as next_obs, timeouts from infos.
    Returns the number of episode ends."""
    rng = np.random.default_rng(seed)
    obs, ends = venv.reset(), 0
    for _ in range(steps):
        actions = rng.integers(0, 3, venv.num_envs)
        new_obs, rewards, dones, infos = venv.step(actions)
        next_obs = new_obs.copy()
        for i in np.flatnonzero(dones):
            next_obs[i] = infos[i]["terminal_observation"]
        timeouts = np.array(
            [d and i.get("TimeLimit.truncated", False) for d, i in zip(dones, infos)]
        )
        for buf in buffers:
            buf.add(obs, next_obs, actions, rewards, dones, timeouts)
        obs, ends = new_obs, ends + int(dones.sum())
    return ends


def _assert_same(frames: FrameReplayBuffer, plain: TransitionRing) -> None:
    assert (frames.size(), frames.pos, frames.full) == (plain.size(), plain.pos, plain.full)
    rows, cols = np.divmod(np.arange(plain.size() * plain.n_envs), plain.n_envs)
    obs, actions, next_obs, rewards, terminated = frames.get(rows, cols)
    np.testing.assert_array_equal(obs, plain.observations[rows, cols])
    np.testing.assert_array_equal(next_obs, plain.next_observations[rows, cols])
    np.testing.assert_array_equal(actions, plain.actions[rows, cols])
    np.testing.assert_array_equal(rewards, plain.rewards[rows, cols])
    np.testing.assert_array_equal(terminated, plain.terminated[rows, cols])


def _pair(venv: Any, size: int) -> tuple[FrameReplayBuffer, TransitionRing]:
    args = (size, venv.observation_space, venv.action_space, venv.num_envs)
    layout = frame_layout(venv.observation_space, venv)
    return FrameReplayBuffer(*args, layout=layout), TransitionRing(*args)


@pytest.mark.parametrize("stack", ["vec", "wrapper", "none"])
@pytest.mark.parametrize("n_envs", [1, 3])
def test_every_cell_equals_the_plain_buffer(stack: str, n_envs: int) -> None:
    venv = _vec(n_envs, stack)
    frames, plain = _pair(venv, 40 * n_envs)
    ends = _drive(venv, [frames, plain], 25)
    _assert_same(frames, plain)  # before the ring wraps
    ends += _drive(venv, [frames, plain], 150, seed=1)
    assert frames.full and ends > 20 and plain.terminated.any()
    assert (plain.terminated == 0).sum() > 0  # time-limit ends stay non-terminal
    _assert_same(frames, plain)
    if stack != "none":  # one new frame per step, one per episode start
        assert frames.stored_frames() <= frames.size() * n_envs * 1.5 + 4 * n_envs


def test_samples_draw_like_the_plain_buffer() -> None:
    venv = _vec(2, "vec")
    frames, plain = _pair(venv, 60)
    _drive(venv, [frames, plain], 80)
    for x, y in zip(
        frames.sample_arrays(8, np.random.default_rng(2)),
        plain.sample_arrays(8, np.random.default_rng(2)),
    ):
        np.testing.assert_array_equal(x, y)


def test_episode_starts_pad_like_the_stacking_wrapper() -> None:
    venv = _vec(1, "vec", p_end=0.0, limit=3)
    frames, plain = _pair(venv, 20)
    _drive(venv, [frames, plain], 6)  # two episodes of 3 steps
    obs, *_ = frames.get(np.array([3]), np.array([0]))  # first step of episode 2
    assert not obs[0, ..., :3].any()  # zeros, nothing from episode 1
    np.testing.assert_array_equal(obs, plain.observations[3:4, 0])
    wrapped = _vec(1, "wrapper", p_end=0.0, limit=3)
    frames, plain = _pair(wrapped, 20)
    _drive(wrapped, [frames, plain], 6)
    obs, *_ = frames.get(np.array([3]), np.array([0]))
    assert (obs[0] == obs[0, -1]).all()  # the first frame repeated
    _assert_same(frames, plain)


def test_short_episodes_grow_the_pool_and_stay_exact() -> None:
    venv = _vec(2, "vec", p_end=1.0)  # every episode is one step: two new frames per step
    frames, plain = _pair(venv, 100)
    before = frames.nbytes()
    _drive(venv, [frames, plain], 120)
    assert frames.nbytes() > before
    _assert_same(frames, plain)


def test_memory_is_one_frame_per_transition() -> None:
    """4x84x84 stacks: within 1.2x the bytes of the unique frames (plain buffer: 8x)."""
    space = spaces.Box(0, 255, (4, 84, 84), np.uint8)
    frame = 84 * 84
    frames = FrameReplayBuffer(2000, space, spaces.Discrete(4))
    plain_bytes = TransitionRing(2000, space, spaces.Discrete(4)).nbytes()
    assert frames.nbytes() <= 1.2 * 2000 * frame
    assert plain_bytes >= 8 * 2000 * frame
    assert frames.n_frames == 4 and frames.frame_shape == (1, 84, 84)


def test_vector_observations_share_obs_and_next_obs() -> None:
    """Not images, not stacked: each observation is one frame, stored once (half the plain)."""
    venv = DummyVecEnv([lambda: TimeLimit(Toy("box"), 5) for _ in range(2)])
    assert frame_layout(venv.observation_space, venv) == (None, 0)
    frames, plain = _pair(venv, 30)
    _drive(venv, [frames, plain], 40)
    _assert_same(frames, plain)
    assert frames.stored_frames() <= frames.size() * 2 + 2 * 2 + 2 * 8


def test_float_frames_compare_bits() -> None:
    space = spaces.Box(-1, 1, (2, 3, 3), np.float32)
    frames = FrameReplayBuffer(10, space, spaces.Discrete(2), layout=(0, 1))
    obs = np.zeros((1, 2, 3, 3), np.float32)
    nxt = obs.copy()
    nxt[0, 1] = -0.0  # equal to 0.0 as a number, not as bits
    frames.add(obs, nxt, np.array([0]), np.array([0.0]), np.array([False]), np.array([False]))
    got = frames.get(np.array([0]), np.array([0]))[2]
    assert np.signbit(got[0, 1]).all() and not np.signbit(got[0, 0]).any()


def test_bad_inputs() -> None:
    with pytest.raises(ValueError, match=r"needs a Box observation space, got Dict\("):
        DQN("MultiInputPolicy", Toy("dict"), optimize_memory_usage=True)
    space = spaces.Box(0, 255, (6, 5, 5), np.uint8)
    with pytest.raises(ValueError, match=r"shape \(6, 5, 5\) into frames of 4 channel"):
        FrameReplayBuffer(10, space, spaces.Discrete(2), layout=(0, 4))
    buf = FrameReplayBuffer(10, space, spaces.Discrete(2))
    with pytest.raises(
        ValueError, match=r"obs must be an array of shape \(1, 6, 5, 5\), got \(6, 5, 5\)"
    ):
        z = np.zeros((6, 5, 5), np.uint8)
        buf.add(z, z, np.array([0]), np.array([0.0]), np.array([False]), np.array([False]))


def _image_venv(n_envs: int = 2) -> Any:
    return VecFrameStack(
        DummyVecEnv([lambda: TimeLimit(Toy("image"), 9) for _ in range(n_envs)]), 4
    )


def test_dqn_saves_and_loads_the_frame_buffer(tmp_path: Any) -> None:
    model = DQN(
        "CnnPolicy",
        _image_venv(),
        optimize_memory_usage=True,
        buffer_size=60,
        learning_starts=20,
        batch_size=4,
        seed=0,
    )
    assert isinstance(model.replay_buffer, FrameReplayBuffer)
    model.learn(50)
    model.save_replay_buffer(tmp_path / "rb")
    other = DQN("CnnPolicy", _image_venv(), optimize_memory_usage=True, buffer_size=60)
    other.load_replay_buffer(tmp_path / "rb")
    a, b = model.replay_buffer, other.replay_buffer
    assert isinstance(b, FrameReplayBuffer)
    assert (b.size(), b.pos, b.full) == (a.size(), a.pos, a.full)
    rows, cols = np.divmod(np.arange(a.size() * 2), 2)
    for x, y in zip(a.get(rows, cols), b.get(rows, cols)):
        np.testing.assert_array_equal(x, y)
    assert b.stored_frames() == a.stored_frames()
    other.learn(20, reset_num_timesteps=False)  # keeps adding after a load
    plain = DQN("CnnPolicy", _image_venv(), buffer_size=60)
    with pytest.raises(ModelFileError, match="holds a frame buffer"):
        plain.load_replay_buffer(tmp_path / "rb")
    plain.save_replay_buffer(tmp_path / "plain")
    with pytest.raises(ModelFileError, match="holds a plain replay buffer"):
        other.load_replay_buffer(tmp_path / "plain")


def test_dqn_frame_buffer_training_matches_the_plain_buffer() -> None:
    """Same seed, same transitions, same minibatches: the same network after training."""
    kwargs = dict(buffer_size=40, learning_starts=16, batch_size=4, train_freq=2, seed=3)
    a = DQN("CnnPolicy", _image_venv(), optimize_memory_usage=True, **kwargs)  # type: ignore[arg-type]
    b = DQN("CnnPolicy", _image_venv(), **kwargs)  # type: ignore[arg-type]
    a.learn(60)
    b.learn(60)
    for (name, x), y in zip(a.q_net.state_dict().items(), b.q_net.state_dict().values()):
        torch.testing.assert_close(x, y, msg=name)
