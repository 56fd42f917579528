"""The MuJoCo native batches (all eleven v5 envs): row i is the single env seeded seed + i,
bit for bit, on both vector faces and in every autoreset mode."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

pytest.importorskip("mujoco")

from tests.envs.mujoco.cases import MUJOCO_IDS, OPTIONS

import palaestra as gym
from palaestra import error
from palaestra.envs.mujoco import batch as mujoco_batch
from palaestra.envs.mujoco._base import MujocoWarning
from palaestra.envs.mujoco.batch import AntBatch, HalfCheetahBatch
from palaestra.vec_env import DummyVecEnv, make_vec_env
from palaestra.vector.native import BatchedVectorEnv

MODES = ["NextStep", "SameStep", "Disabled"]
# Arguments that make episodes end within the test's steps (terminations, not only time limits).
ENDING: dict[str, dict[str, Any]] = {
    "Ant-v5": {"healthy_z_range": (0.45, 1.0)},
    "Humanoid-v5": {"healthy_z_range": (1.2, 2.0)},
}


def assert_same(ours: Any, theirs: Any, where: str) -> None:
    """Equal bits (NaN equal to NaN), recursing into dicts and object arrays."""
    if theirs is None:
        assert ours is None, (where, ours)
        return
    if isinstance(theirs, dict):
        assert isinstance(ours, dict) and set(ours) == set(theirs), (where, ours, theirs)
        for key in theirs:
            assert_same(ours[key], theirs[key], f"{where}[{key!r}]")
        return
    if isinstance(theirs, (tuple, list)):
        assert isinstance(ours, (tuple, list)) and len(ours) == len(theirs), (where, ours)
        for k, (x, y) in enumerate(zip(ours, theirs)):
            assert_same(x, y, f"{where}[{k}]")
        return
    a, b = np.asarray(ours), np.asarray(theirs)
    assert a.shape == b.shape, (where, a.shape, b.shape)
    if b.dtype == object:
        for x, y in zip(a.ravel(), b.ravel()):
            assert_same(x, y, where)
        return
    assert a.dtype == b.dtype, (where, a.dtype, b.dtype)
    assert a.tobytes() == b.tobytes(), (where, a, b)


def test_a_step_that_only_resets_rows() -> None:
    """One Ant row that falls: the next step resets it and steps no row at all."""
    ours = gym.make_vec("Ant-v5", 1, healthy_z_range=(0.45, 1.0))
    theirs = gym.make_vec("Ant-v5", 1, vectorization_mode="sync", healthy_z_range=(0.45, 1.0))
    assert_same(ours.reset(seed=2), theirs.reset(seed=2), "reset")
    rng = np.random.default_rng(3)
    ends = 0
    for t in range(300):
        actions = rng.uniform(-1, 1, (1, 8)).astype(np.float32)
        mine, ref = ours.step(actions), theirs.step(actions)
        assert_same(mine, ref, f"step {t}")
        ends += int(ref[2][0])
    assert ends >= 1


def test_make_vec_returns_the_native_batch() -> None:
    envs = gym.make_vec("HalfCheetah-v5", num_envs=3)
    assert isinstance(envs, BatchedVectorEnv)
    assert isinstance(envs.batch, HalfCheetahBatch)
    assert envs.observation_space.shape == (3, 17)
    assert isinstance(gym.make_vec("Ant-v5", num_envs=2).batch, AntBatch)
    envs.close()


@pytest.mark.parametrize("env_id", MUJOCO_IDS)
def test_every_v5_id_has_its_batch(env_id: str) -> None:
    envs = gym.make_vec(env_id, num_envs=2)
    assert isinstance(envs, BatchedVectorEnv)
    name = env_id.removesuffix("-v5")
    assert type(envs.batch) is getattr(mujoco_batch, f"{name}Batch")
    assert type(envs.batch.envs[0]).__name__ == f"{name}Env"
    single = gym.make(env_id)
    assert envs.single_observation_space == single.observation_space
    assert envs.single_action_space == single.action_space
    envs.close()


@pytest.mark.parametrize("env_id", MUJOCO_IDS)
@pytest.mark.parametrize("mode", MODES)
def test_rows_equal_single_envs_in_every_autoreset_mode(env_id: str, mode: str) -> None:
    """Each env, 100 steps across many resets (a time limit of 20 steps, and falls) against a
    SyncVectorEnv of single envs: obs, rewards, terminations, truncations and infos equal bit
    for bit."""
    check_rows(env_id, mode, 1, {"max_episode_steps": 20, **ENDING.get(env_id, {})}, steps=100)


@pytest.mark.parametrize("env_id", ["HalfCheetah-v5", "Ant-v5", "Humanoid-v5"])
@pytest.mark.parametrize("mode", MODES)
def test_rows_equal_single_envs_with_two_threads(env_id: str, mode: str) -> None:
    check_rows(env_id, mode, 2, {"max_episode_steps": 40, **ENDING.get(env_id, {})}, steps=300)


def test_rows_share_one_model_also_after_pickling() -> None:
    """All rows step one MjModel (each its own MjData); a pickled batch keeps that and
    continues bit for bit."""
    import pickle

    batch = HalfCheetahBatch(3)
    models = {id(env.model) for env in batch.envs}
    datas = {id(env.data) for env in batch.envs}
    assert len(models) == 1 and len(datas) == 3
    batch.reset(seed=5)
    actions = np.random.default_rng(0).uniform(-1, 1, (3, 6))
    batch.step(actions)
    copy = pickle.loads(pickle.dumps(batch))
    assert len({id(env.model) for env in copy.envs}) == 1
    for _ in range(3):
        ours = [a.copy() for a in batch.step(actions)]
        theirs = [a.copy() for a in copy.step(actions)]
        assert_same(theirs, ours, "pickled batch")


@pytest.mark.parametrize("env_id", MUJOCO_IDS)
def test_constructor_arguments_reach_every_row(env_id: str) -> None:
    """The parity suite's first option set of each env, passed through make_vec."""
    kwargs = {"max_episode_steps": 30, **OPTIONS[env_id][0]}
    check_rows(env_id, "NextStep", 1, kwargs, steps=60, min_ends=3)


def check_rows(
    env_id: str,
    mode: str,
    num_threads: int,
    kwargs: dict[str, Any],
    steps: int,
    min_ends: int | None = None,
) -> None:
    n = 5
    vector_kwargs = {"autoreset_mode": mode}
    ours = gym.make_vec(env_id, n, vector_kwargs=vector_kwargs, num_threads=num_threads, **kwargs)
    theirs = gym.make_vec(
        env_id, n, vectorization_mode="sync", vector_kwargs=vector_kwargs, **kwargs
    )
    assert isinstance(ours, BatchedVectorEnv)
    assert_same(ours.reset(seed=11), theirs.reset(seed=11), "reset")
    rng = np.random.default_rng(0)
    shape = (n, *ours.single_action_space.shape)
    ends = 0
    for t in range(steps):
        actions = rng.uniform(-1.2, 1.2, shape).astype(np.float32)
        mine, ref = ours.step(actions), theirs.step(actions)
        assert_same(mine, ref, f"step {t}")
        done = ref[2] | ref[3]
        ends += int(done.sum())
        if mode == "Disabled" and done.any():
            assert_same(
                ours.reset(options={"reset_mask": done.copy()}),
                theirs.reset(options={"reset_mask": done.copy()}),
                f"partial reset at {t}",
            )
    # at least the time limit's ends (NextStep spends a step on each reset)
    cap = kwargs["max_episode_steps"]
    assert ends >= (n * (steps // (cap + 1)) if min_ends is None else min_ends)
    ours.close()
    theirs.close()


@pytest.mark.parametrize(
    "env_id", ["HalfCheetah-v5", "Ant-v5", "Hopper-v5", "Humanoid-v5", "InvertedPendulum-v5"]
)
def test_make_vec_env_face_equals_dummy_vec_env(env_id: str) -> None:
    """SB3's face: make_vec_env's native batch against a DummyVecEnv of Monitor-wrapped envs
    (Ant with a narrow healthy_z_range, Hopper and InvertedPendulum end episodes; HalfCheetah
    runs without resets; Humanoid's infos hold arrays)."""
    env_kwargs = ENDING.get(env_id, {})
    ours = make_vec_env(env_id, n_envs=3, seed=5, env_kwargs=env_kwargs)
    theirs = make_vec_env(env_id, n_envs=3, seed=5, vec_env_cls=DummyVecEnv, env_kwargs=env_kwargs)
    assert type(ours).__name__ == "VecMonitor"
    assert_same(ours.reset(), theirs.reset(), "reset")
    rng = np.random.default_rng(1)
    ends = 0
    for t in range(300):
        actions = rng.uniform(-1, 1, (3, *ours.action_space.shape)).astype(np.float32)
        obs, rewards, dones, infos = ours.step(actions)
        ref_obs, ref_rewards, ref_dones, ref_infos = theirs.step(actions)
        assert_same(obs, ref_obs, f"obs {t}")
        assert_same(rewards, ref_rewards, f"rewards {t}")
        assert_same(dones, ref_dones, f"dones {t}")
        ends += int(ref_dones.sum())
        for i in range(3):
            mine = {k: v for k, v in infos[i].items() if k != "episode"}
            ref = {k: v for k, v in ref_infos[i].items() if k != "episode"}
            assert_same(mine, ref, f"infos[{i}] {t}")
            if "episode" in ref_infos[i]:
                # VecMonitor sums float32 returns, Monitor rounds its sum to 6 decimals (SB3's)
                assert infos[i]["episode"]["r"] == pytest.approx(
                    ref_infos[i]["episode"]["r"], abs=1e-4
                )
                assert infos[i]["episode"]["l"] == ref_infos[i]["episode"]["l"]
    assert ends >= (0 if env_id in ("HalfCheetah-v5", "Humanoid-v5") else 5)


def test_bad_actions_name_the_actions_and_the_space() -> None:
    envs = gym.make_vec("HalfCheetah-v5", num_envs=2)
    envs.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=r"expected shape \(2, 6\) .*got \(2, 5\)"):
        envs.step(np.zeros((2, 5), dtype=np.float32))
    bad = np.zeros((2, 6), dtype=np.float32)
    bad[1, 3] = np.nan
    with pytest.raises(error.InvalidAction, match=r"rows \[1\].*nan.*not finite.*Box"):
        envs.step(bad)
    with pytest.raises(error.InvalidAction, match=r"'abc'.*expected real values.*Box"):
        envs.step(np.full((2, 6), "abc"))


def test_step_before_reset_and_bad_arguments() -> None:
    batch = HalfCheetahBatch(2)
    with pytest.raises(error.ResetNeeded, match=r"Rows \[0, 1\] were never reset"):
        batch.step(np.zeros((2, 6)))
    with pytest.raises(ValueError, match="num_envs must be a positive integer, got 0"):
        HalfCheetahBatch(0)
    with pytest.raises(ValueError, match="num_threads must be >= 1, got 0"):
        HalfCheetahBatch(2, num_threads=0)
    with pytest.raises(TypeError, match=r"num_threads must be an int, got 1\.5"):
        HalfCheetahBatch(2, num_threads=1.5)


def test_bad_constructor_arguments_raise_as_the_single_env() -> None:
    with pytest.raises(ValueError, match=r"healthy_z_range must have low <= high, got \(1\.0, 0"):
        gym.make_vec("Hopper-v5", 2, healthy_z_range=(1.0, 0.5))
    with pytest.raises(TypeError, match="unexpected keyword argument 'bogus'"):
        gym.make_vec("Reacher-v5", 2, bogus=1)
    with pytest.raises(ValueError, match="main_body 'nose' is not a body of"):
        gym.make_vec("Ant-v5", 2, main_body="nose")


def test_an_unstable_row_warns_and_flags_only_its_info() -> None:
    batch = HalfCheetahBatch(3)
    batch.reset(seed=0)
    row = batch.envs[1]
    row.set_state(row.init_qpos, np.full(row.model.nv, 1e300))
    with pytest.warns(MujocoWarning, match=r"HalfCheetahEnv \(row 1\): MuJoCo reported mjWARN_BAD"):
        batch.step(np.zeros((3, 6), np.float32))
    infos = batch.last_infos()
    assert infos[1]["mujoco_warnings"] and all(
        w.startswith("mjWARN_BAD") for w in infos[1]["mujoco_warnings"]
    )
    assert "mujoco_warnings" not in infos[0] and "mujoco_warnings" not in infos[2]


def test_a_render_mode_gives_real_envs() -> None:
    envs = gym.make_vec("HalfCheetah-v5", num_envs=2, render_mode="rgb_array")
    assert not isinstance(envs, BatchedVectorEnv)
    envs.close()
