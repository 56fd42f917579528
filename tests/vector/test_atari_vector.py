"""The native vector Atari (``make_vec("ALE/...")``) against ale-py's own ``AtariVectorEnv``.

Both run the same ``ALEVectorInterface``; equal seeds and actions must give equal observations,
rewards, flags and infos in every autoreset mode, through autoresets (short frame limits force
them) and lost lives. Longer and wider runs are marked slow.
"""

from __future__ import annotations

import gc
import os
import time
from typing import Any

import numpy as np
import pytest

import palaestra as gym
from palaestra import error
from palaestra.envs.atari.ale_engine import ALEVectorEngine
from palaestra.envs.atari.vector import AtariVectorEnv
from palaestra.utils.stacked_infos import StackedInfos
from palaestra.vector import AutoresetMode

ale_py = pytest.importorskip("ale_py")
ale_vector_env = pytest.importorskip("ale_py.vector_env")

INFO_KEYS = ("env_id", "lives", "frame_number", "episode_frame_number")
V5 = {"repeat_action_probability": 0.25}  # what the ALE/<Game>-v5 spec adds


def _pair(n: int, mode: str, **settings: Any) -> tuple[Any, Any]:
    ours = gym.make_vec("ALE/Breakout-v5", num_envs=n, autoreset_mode=mode, **settings)
    ref = ale_vector_env.AtariVectorEnv("breakout", n, autoreset_mode=mode, **V5, **settings)
    return ours, ref


def _assert_infos(ours: dict[str, Any], ref: dict[str, Any], where: Any) -> None:
    for key in INFO_KEYS:
        np.testing.assert_array_equal(ours[key], ref[key], err_msg=f"{key} at {where}")
        assert ours[key].dtype == ref[key].dtype, (key, where)
        assert ours[f"_{key}"].all(), (key, where)


def _run_parity(n: int, mode: str, steps: int, seed: int = 7, **settings: Any) -> dict[str, int]:
    """Step both with the same random actions; count episode ends and lost lives."""
    ours, ref = _pair(n, mode, **settings)
    obs, info = ours.reset(seed=seed)
    ref_obs, ref_info = ref.reset(seed=seed)
    np.testing.assert_array_equal(obs, ref_obs)
    _assert_infos(info, ref_info, "reset")
    rng = np.random.default_rng(seed)
    counts = {"ends": 0, "lives_lost": 0}
    lives = info["lives"].copy()
    for t in range(steps):
        actions = rng.integers(0, 4, n)
        obs, rewards, terminated, truncated, info = ours.step(actions)
        r_obs, r_rewards, r_terminated, r_truncated, r_info = ref.step(actions)
        np.testing.assert_array_equal(obs, r_obs, err_msg=f"obs at step {t}")
        np.testing.assert_array_equal(rewards, r_rewards, err_msg=f"rewards at step {t}")
        np.testing.assert_array_equal(terminated, r_terminated, err_msg=f"terminated at {t}")
        np.testing.assert_array_equal(truncated, r_truncated, err_msg=f"truncated at {t}")
        assert rewards.dtype == np.float64 and terminated.dtype == truncated.dtype == np.bool_
        _assert_infos(info, r_info, t)
        done = terminated | truncated
        if mode == "SameStep" and done.any():
            assert info["_final_obs"].tolist() == done.tolist()
            # ale-py's final_obs is meaningful only for rows it reset (a lost life under
            # life_loss_info leaves a stale frame there): ours is that row's obs, which goes on.
            lost_only = done & (info["lives"] > 0) & (info["lives"] < lives)
            for i in np.flatnonzero(done):
                expected = obs[i] if lost_only[i] else r_info["final_obs"][i]
                np.testing.assert_array_equal(info["final_obs"][i], expected)
                assert set(info["final_info"]) >= set(INFO_KEYS)
        counts["ends"] += int(done.sum())
        counts["lives_lost"] += int(((info["lives"] < lives) & (info["lives"] > 0)).sum())
        lives = info["lives"].copy()
    ours.close()
    return counts


def test_parity_with_ale_py_through_autoresets() -> None:
    counts = _run_parity(2, "NextStep", 250, max_num_frames_per_episode=300)
    assert counts["ends"] >= 2  # every row truncated at least once


def test_parity_with_life_loss_info_same_step() -> None:
    # A lost life reports terminated=True and the game goes on: no reset, reward kept.
    counts = _run_parity(3, "SameStep", 250, seed=1, life_loss_info=True)
    assert counts["lives_lost"] >= 2


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_parity_with_life_loss_info(mode: str) -> None:
    counts = _run_parity(2, mode, 600, seed=1, life_loss_info=True)
    assert counts["lives_lost"] >= 4


@pytest.mark.slow
@pytest.mark.parametrize("n", [2, 4])
@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
@pytest.mark.parametrize(
    "settings",
    [
        {},
        {"max_num_frames_per_episode": 1000},
        {"episodic_life": True},
        {"life_loss_info": True, "max_num_frames_per_episode": 1500},
        {"grayscale": False, "stack_num": 2, "img_height": 100, "img_width": 80},
        {"frameskip": 2, "maxpool": False, "noop_max": 0, "use_fire_reset": False},
        {"reward_clipping": False, "full_action_space": True},
    ],
)
def test_parity_with_ale_py_long(n: int, mode: str, settings: dict[str, Any]) -> None:
    _run_parity(n, mode, 1200, seed=n, **settings)


def test_make_vec_gives_the_native_vector_env() -> None:
    envs = gym.make_vec("ALE/Breakout-v5", num_envs=2)
    assert isinstance(envs, AtariVectorEnv)
    assert isinstance(envs.engine, ALEVectorEngine)
    assert repr(envs) == "AtariVectorEnv(ALE/Breakout-v5, num_envs=2)"
    assert envs.single_observation_space == gym.spaces.Box(0, 255, (4, 84, 84), np.uint8)
    assert envs.observation_space.shape == (2, 4, 84, 84)
    assert str(envs.single_action_space) == "Discrete(4)"
    assert str(envs.action_space) == "MultiDiscrete([4 4])"
    assert envs.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    assert envs.engine.settings.repeat_action_probability == 0.25  # the v5 spec's
    same = gym.make_vec("ALE/Pong-v5", 1, "vector_entry_point")
    assert isinstance(same, AtariVectorEnv) and str(same.single_action_space) == "Discrete(6)"
    assert same.call("get_action_meanings")[0][:2] == ["NOOP", "FIRE"]
    for env in (envs, same):
        env.close()


def test_reset_mask_and_row_seeds() -> None:
    ours, ref = _pair(2, "NextStep")
    ours.reset(seed=0)
    ref.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(5):
        actions = rng.integers(0, 4, 2)
        ours.step(actions)
        ref.step(actions)
    mask = np.array([False, True])
    obs, info = ours.reset(seed=[None, 11], options={"reset_mask": mask})
    r_obs, r_info = ref.reset(seed=np.array([11]), options={"reset_mask": mask})
    np.testing.assert_array_equal(obs, r_obs)  # row 0 keeps its current observation
    assert info["_lives"].tolist() == mask.tolist()
    np.testing.assert_array_equal(
        info["episode_frame_number"][mask], r_info["episode_frame_number"][mask]
    )
    assert info["episode_frame_number"][0] == 0  # rows not reset carry no info
    actions = rng.integers(0, 4, 2)
    np.testing.assert_array_equal(ours.step(actions)[0], ref.step(actions)[0])
    # An int seed with a mask seeds row i with seed + i, as in every palaestra vector env.
    a, _ = ours.reset(seed=20, options={"reset_mask": mask})
    b, _ = ours.reset(seed=[None, 21], options={"reset_mask": mask})
    np.testing.assert_array_equal(a[1], b[1])
    ours.close()


def test_seeding() -> None:
    envs = gym.make_vec("ALE/Breakout-v5", num_envs=2)
    # Seeds 0 and 1 draw different no-op counts; [1, 0] swaps the rows of seed=0.
    first = envs.reset(seed=0)[1]["episode_frame_number"].tolist()
    assert first[0] != first[1]
    assert envs.reset(seed=[1, 0])[1]["episode_frame_number"].tolist() == first[::-1]
    with pytest.raises(error.Error, match=r"Seed must be an int in \[0, 2147483647\].*2147483648"):
        envs.reset(seed=2**31)
    with pytest.raises(error.Error, match=r"Seed must be an int in \[0, 2147483647\].*: -1"):
        envs.reset(seed=[0, -1])
    with pytest.raises(
        error.Error, match="Seed must be a python integer, actual type: <class 'float'>"
    ):
        envs.reset(seed=[0, 1.5])
    with pytest.raises(ValueError, match="length must match num_envs=2 but got length=3"):
        envs.reset(seed=[0, 1, 2])
    envs.close()


def test_disabled_mode_needs_a_masked_reset() -> None:
    envs = gym.make_vec(
        "ALE/Breakout-v5", num_envs=2, autoreset_mode="Disabled", max_num_frames_per_episode=40
    )
    envs.reset(seed=0)
    truncated = np.zeros(2, dtype=bool)
    while not truncated.any():
        _, _, _, truncated, _ = envs.step(np.zeros(2, dtype=np.int64))
    with pytest.raises(error.ResetNeeded, match=r"Sub-environments \[0, 1\] have finished"):
        envs.step(np.zeros(2, dtype=np.int64))
    _, info = envs.reset(options={"reset_mask": truncated})
    assert info["_lives"].tolist() == truncated.tolist()
    _, _, _, truncated, _ = envs.step(np.zeros(2, dtype=np.int64))
    assert not truncated.any()
    envs.close()


def test_same_step_infos_keep_their_dtypes() -> None:
    envs = gym.make_vec(
        "ALE/Breakout-v5", num_envs=2, autoreset_mode="SameStep", max_num_frames_per_episode=40
    )
    envs.reset(seed=0)
    seen = set()
    for _ in range(12):
        _, _, _, truncated, info = envs.step(np.ones(2, dtype=np.int64))
        seen.add(bool(truncated.any()))
        assert info["lives"].dtype == np.int32 and info["_lives"].all()
    assert seen == {True, False}
    envs.close()


def _thread_count() -> int:
    return len(os.listdir("/proc/self/task"))


def _threads_settle_to(expected: int, seconds: float = 5.0) -> int:
    """The thread count once it reaches ``expected`` or ``seconds`` pass.

    A joined thread's /proc entry can outlive the join by a few milliseconds (1 run in ~30
    showed one extra task right after ``close()``, gone 50 ms later), so the count is polled.
    """
    deadline = time.monotonic() + seconds
    while (count := _thread_count()) != expected and time.monotonic() < deadline:
        time.sleep(0.01)
    return count


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="needs Linux /proc")
def test_close_stops_the_threads_and_is_idempotent() -> None:
    gc.collect()
    before = _thread_count()
    envs = gym.make_vec("ALE/Breakout-v5", num_envs=2, num_threads=2)
    envs.reset()
    envs.step(np.zeros(2, dtype=np.int64))
    assert _thread_count() > before
    envs.close()
    envs.close()
    assert _threads_settle_to(before) == before
    with pytest.raises(error.ClosedEnvironmentError, match="after a call to `close\\(\\)`"):
        envs.step(np.zeros(2, dtype=np.int64))
    with pytest.raises(error.ClosedEnvironmentError):
        envs.reset()
    with gym.make_vec("ALE/Breakout-v5", num_envs=1) as envs:
        envs.reset()
    assert envs.closed and _threads_settle_to(before) == before


@pytest.fixture(scope="module")
def breakout() -> Any:
    envs = gym.make_vec("ALE/Breakout-v5", num_envs=2)
    envs.reset(seed=0)
    yield envs
    envs.close()


@pytest.mark.parametrize(
    ("actions", "message"),
    [
        (np.array([0, 1, 2]), r"Expected a batch of 2 actions \(shape \(2,\)\).*got shape \(3,\)"),
        (np.array([[0, 1]]), r"got shape \(1, 2\)"),
        (3, r"got shape \(\)"),
        (np.array([0.0, 1.0]), "Expected integer actions .* got dtype float64"),
        (np.array([True, False]), "got dtype bool"),
        (np.array([0, 4]), r"Actions \[4\] of sub-environments \[1\] are not in Discrete\(4\)"),
        ([-1, 2], r"Actions \[-1\] of sub-environments \[0\] .*'NOOP', 'FIRE'"),
    ],
)
def test_bad_actions(breakout: Any, actions: Any, message: str) -> None:
    # ALE itself hangs its worker thread for good on an out-of-range action.
    with pytest.raises(error.InvalidAction, match=message):
        breakout.step(actions)
    assert breakout.step([0, 1])[0].shape == (2, 4, 84, 84)  # still usable


def test_bad_arguments() -> None:
    with pytest.raises(
        TypeError, match=r"unexpected keyword arguments \['obs_type'\].*'frameskip'"
    ):
        gym.make_vec("ALE/Breakout-v5", num_envs=2, obs_type="rgb")
    with pytest.raises(error.Error, match="Invalid frameskip 0: expected a positive int"):
        AtariVectorEnv("breakout", 2, frameskip=0)
    with pytest.raises(ValueError, match="Invalid stack_num 0: expected an int >= 1"):
        AtariVectorEnv("breakout", 2, stack_num=0)
    with pytest.raises(ValueError, match=r"Invalid repeat_action_probability 1.5: .*\[0, 1\]"):
        AtariVectorEnv("breakout", 2, repeat_action_probability=1.5)
    with pytest.raises(ValueError, match=r"batch_size=1 is not supported.*use batch_size=0"):
        AtariVectorEnv("breakout", 2, batch_size=1)
    with pytest.raises(ValueError, match="num_envs must be an int >= 1, got 0"):
        AtariVectorEnv("breakout", 0)
    with pytest.raises(error.Error, match=r"Unknown Atari game 'Breakout'.*'breakout'"):
        AtariVectorEnv("Breakout", 2)
    with pytest.raises(ValueError, match="'Sometimes' is not a valid AutoresetMode"):
        AtariVectorEnv("breakout", 2, autoreset_mode="Sometimes")


def test_protocol_errors() -> None:
    envs = AtariVectorEnv("breakout", 2)
    with pytest.raises(error.ResetNeeded, match="Cannot call `step` before calling `reset`"):
        envs.step(np.zeros(2, dtype=np.int64))
    with pytest.raises(error.ResetNeeded, match=r"first reset .* must reset every sub-environment"):
        envs.reset(options={"reset_mask": np.array([True, False])})
    with pytest.raises(
        ValueError, match="takes no reset options but 'reset_mask', got \\{'x': 1\\}"
    ):
        envs.reset(options={"x": 1})
    envs.reset(seed=0)
    with pytest.raises(AttributeError, match="no sub-env objects, so no 'ale'"):
        envs.get_attr("ale")
    with pytest.raises(AttributeError, match="Cannot set 'x'"):
        envs.set_attr("x", 1)
    assert envs.get_attr("render_mode") == (None, None)
    envs.close()


def test_continuous_actions_match_ale_py() -> None:
    ours, ref = _pair(2, "NextStep", continuous=True)
    assert ours.single_action_space == gym.spaces.Box(
        np.array([0.0, -np.pi, 0.0], np.float32), np.array([1.0, np.pi, 1.0], np.float32)
    )
    np.testing.assert_array_equal(ours.reset(seed=2)[0], ref.reset(seed=2)[0])
    rng = np.random.default_rng(2)
    for t in range(60):
        actions = rng.uniform([0, -np.pi, 0], [1, np.pi, 1], (2, 3)).astype(np.float32)
        a, b = ours.step(actions), ref.step(actions)
        np.testing.assert_array_equal(a[0], b[0], err_msg=str(t))
        np.testing.assert_array_equal(a[1], b[1])
    with pytest.raises(
        error.InvalidAction, match=r"3 finite floats.*Box\(\[ 0\..*got float32 \(2, 3\)"
    ):
        ours.step(np.full((2, 3), np.nan, np.float32))
    with pytest.raises(error.InvalidAction, match=r"shape \(2, 3\).*got int64 \(2,\)"):
        ours.step(np.array([1, 2]))
    ours.close()


def test_stacked_infos_rows() -> None:
    infos = StackedInfos({"lives": np.array([5, 4, 3], np.int32)}, 3, np.array([True, False, True]))
    assert len(infos) == 3 and infos[1] == {} and infos[-1] == {"lives": 3}
    assert [dict(i) for i in infos[:2]] == [{"lives": 5}, {}]
    stacked = infos.stacked()
    assert stacked["lives"].tolist() == [5, 0, 3] and stacked["_lives"].tolist() == [1, 0, 1]
    with pytest.raises(IndexError, match="row 3 out of range for 3 rows"):
        infos[3]


def test_fallback_without_the_vector_interface(monkeypatch: pytest.MonkeyPatch) -> None:
    """Old ale-py: worker processes run the single env with the matching wrappers."""
    import palaestra.envs.atari.vector as atari_vector
    from palaestra.vector.process_engine import ProcessEngine

    monkeypatch.setattr(atari_vector, "vector_interface_available", lambda: False)
    with pytest.raises(error.Error, match=r"\['maxpool', 'life_loss_info'\] need ale-py's"):
        AtariVectorEnv("breakout", 2, maxpool=False, life_loss_info=True)
    envs = AtariVectorEnv("breakout", 2, autoreset_mode="SameStep", max_num_frames_per_episode=80)
    try:
        assert isinstance(envs.engine, ProcessEngine)
        native = gym.make_vec("ALE/Breakout-v5", num_envs=2)
        assert envs.observation_space == native.observation_space
        assert envs.action_space == native.action_space
        native.close()
        obs, _ = envs.reset(seed=0)
        assert obs.shape == (2, 4, 84, 84) and obs[:, :3].max() == 0  # zero-padded stack
        truncated = np.zeros(2, dtype=bool)
        for _ in range(25):
            obs, rewards, _, truncated, info = envs.step(np.ones(2, dtype=np.int64))
            assert set(np.unique(rewards)) <= {-1.0, 0.0, 1.0}
            if truncated.any():
                break
        assert truncated.any() and info["final_obs"][0].shape == (4, 84, 84)
    finally:
        envs.close()
    assert all(not p.is_alive() for p in envs.engine.processes)
