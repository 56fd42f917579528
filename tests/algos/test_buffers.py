"""Replay and rollout buffers: layout, time-limit bootstrapping, sampling, persistence."""

from typing import Any

import numpy as np
import pytest

from palaestra import spaces
from palaestra.algos.common.rollout_store import RolloutStore
from palaestra.algos.common.transition_ring import TransitionRing

OBS = spaces.Box(-10, 10, (2,))


def _fill(buf: TransitionRing, steps: int) -> None:
    for t in range(steps):
        obs = np.full((buf.n_envs, 2), t, dtype=np.float32)
        buf.add(
            obs,
            obs + 1,
            np.arange(buf.n_envs),
            np.full(buf.n_envs, float(t)),
            np.array([t % 3 == 2] * buf.n_envs),
            np.array([t % 6 == 5] * buf.n_envs),
        )


def test_timeouts_are_not_terminal() -> None:
    buf = TransitionRing(100, OBS, spaces.Discrete(3), n_envs=2)
    _fill(buf, 6)
    # steps 2 and 5 are done; step 5 is a truncation, so only step 2 is terminal
    assert buf.terminated[:6, 0].tolist() == [0, 0, 1, 0, 0, 0]
    no_handle = TransitionRing(100, OBS, spaces.Discrete(3), handle_timeout_termination=False)
    _fill(no_handle, 6)
    assert no_handle.terminated[:6, 0].tolist() == [0, 0, 1, 0, 0, 1]


def test_ring_wraps_and_sample_shapes() -> None:
    buf = TransitionRing(8, OBS, spaces.Discrete(3), n_envs=2)  # 4 rows of 2 envs, as SB3
    assert buf.buffer_size == 4
    _fill(buf, 6)
    assert buf.full and buf.pos == 2 and buf.size() == 4
    obs, actions, next_obs, rewards, terminated = buf.sample_arrays(16, np.random.default_rng(0))
    assert obs.shape == (16, 2) and actions.shape == (16,)
    assert rewards.dtype == np.float32 and terminated.shape == (16,)
    # rows 0-1 were overwritten by steps 4-5: no step 0 or 1 transitions remain
    assert set(rewards.tolist()) <= {2.0, 3.0, 4.0, 5.0}
    np.testing.assert_array_equal(next_obs, obs + 1)


def test_dict_observations_and_state_roundtrip() -> None:
    space = spaces.Dict({"img": spaces.Box(0, 255, (3, 4, 4), np.uint8), "v": spaces.Discrete(5)})
    buf = TransitionRing(10, space, spaces.Discrete(2))
    for t in range(3):
        obs = {"img": np.full((1, 3, 4, 4), t, np.uint8), "v": np.array([t])}
        buf.add(obs, obs, np.array([1]), np.array([1.0]), np.array([False]), np.array([False]))
    obs = buf.sample_arrays(4, np.random.default_rng(1))[0]
    assert obs["img"].dtype == np.uint8 and obs["img"].shape == (4, 3, 4, 4)
    meta, arrays = buf.state()
    other = TransitionRing(10, space, spaces.Discrete(2))
    other.load_state(meta, arrays)
    assert other.pos == 3 and not other.full
    np.testing.assert_array_equal(other.observations["v"][:3, 0], [0, 1, 2])
    with pytest.raises(ValueError, match="n_envs"):
        TransitionRing(10, space, spaces.Discrete(2), n_envs=2).load_state(meta, arrays)


def test_rollout_buffer_minibatches_cover_everything_once() -> None:
    buf = RolloutStore(4, OBS, spaces.Box(-1, 1, (2,)), n_envs=3, gamma=0.9, gae_lambda=0.8)
    for t in range(4):
        buf.add(
            np.full((3, 2), t),
            np.zeros((3, 2)),
            np.ones(3),
            np.zeros(3),
            np.arange(3) + 10 * t,
            np.zeros(3),
        )
    assert buf.full
    buf.compute_returns_and_advantage(np.zeros(3), np.ones(3))
    seen = []
    for mb in buf.minibatch_arrays(5, np.random.default_rng(0)):
        assert mb["observations"].shape[1:] == (2,) and mb["actions"].dtype == np.float32
        seen += mb["old_values"].tolist()
    assert sorted(seen) == sorted(float(10 * t + e) for t in range(4) for e in range(3))


def _dqn_with_buffer(tmp_path):  # type: ignore[no-untyped-def]
    from palaestra.algos import DQN

    model = DQN("MlpPolicy", "CartPole-v1", buffer_size=500, learning_starts=50, seed=0)
    model.learn(120)
    model.save_replay_buffer(tmp_path / "rb.zip")
    return model


def test_replay_buffer_file_larger_than_the_buffer_is_refused_before_reading(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import tracemalloc

    from palaestra.algos import ModelFileError
    from palaestra.algos.common.model_io import read_archive, write_archive

    model = _dqn_with_buffer(tmp_path)
    meta, arrays = read_archive(tmp_path / "rb.zip", "replay_buffer")
    arrays["rewards"] = np.zeros((4_000_000, 1), dtype=np.float32)  # 16 MB: far past 500 rows
    write_archive(tmp_path / "big.zip", "replay_buffer", meta, arrays)
    tracemalloc.start()
    with pytest.raises(ModelFileError, match="limit"):
        model.load_replay_buffer(tmp_path / "big.zip")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 4_000_000  # refused from the declared sizes, not after reading


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda m, a: a.__setitem__("actions", a["actions"] + 7), "actions outside Discrete"),
        (lambda m, a: a["rewards"].__setitem__(0, np.nan), "NaN or infinite"),
        (lambda m, a: m.__setitem__("pos", "3"), "position '3'"),
        (lambda m, a: m.__setitem__("full", 1), "full 1 are malformed"),
    ],
)
def test_replay_buffer_contents_are_checked(tmp_path, change, message) -> None:  # type: ignore[no-untyped-def]
    from palaestra.algos import ModelFileError
    from palaestra.algos.common.model_io import read_archive, write_archive

    model = _dqn_with_buffer(tmp_path)
    meta, arrays = read_archive(tmp_path / "rb.zip", "replay_buffer")
    change(meta, arrays)
    write_archive(tmp_path / "bad.zip", "replay_buffer", meta, arrays)
    with pytest.raises(ModelFileError, match=message):
        model.load_replay_buffer(tmp_path / "bad.zip")


@pytest.mark.parametrize("dict_obs", [False, True])
def test_one_env_sample_is_get_of_column_zero(dict_obs: bool) -> None:
    """One env: the column draw (which takes nothing from the stream) is skipped and the
    column read directly; the same transitions and the same generator state as ``get``."""
    space: Any = spaces.Box(-5, 5, (3,), np.float32)
    if dict_obs:
        space = spaces.Dict({"x": space, "k": spaces.Discrete(4)})
    buf = TransitionRing(50, space, spaces.Box(-1, 1, (2,), np.float32))
    rng = np.random.default_rng(0)
    for _ in range(70):  # wraps
        obs, next_obs = space.sample(), space.sample()
        if dict_obs:
            obs = {k: np.asarray(v)[None] for k, v in obs.items()}
            next_obs = {k: np.asarray(v)[None] for k, v in next_obs.items()}
        else:
            obs, next_obs = obs[None], next_obs[None]
        buf.add(
            obs,
            next_obs,
            rng.uniform(-1, 1, (1, 2)),
            rng.normal(size=1),
            rng.random(1) < 0.2,
            np.array([False]),
        )
    fast_rng, ref_rng = np.random.default_rng(5), np.random.default_rng(5)
    got = buf.sample_arrays(32, fast_rng)
    rows = ref_rng.integers(0, buf.size(), size=32)
    cols = ref_rng.integers(0, 1, size=32)
    expected = buf.get(rows, cols)
    assert fast_rng.bit_generator.state == ref_rng.bit_generator.state
    assert len(got) == len(expected) == 5
    for g, e in zip(got, expected):
        if dict_obs and isinstance(e, dict):
            assert g.keys() == e.keys()
            for key in e:
                np.testing.assert_array_equal(g[key], e[key])
                assert g[key].dtype == e[key].dtype and g[key].shape == e[key].shape
        else:
            np.testing.assert_array_equal(g, e)
            assert g.dtype == e.dtype and g.shape == e.shape
