"""The batched engines agree exactly, row by row, with single envs seeded ``seed + i``."""

from __future__ import annotations

import numpy as np
import pytest
from tests.envs.cases import CLASSES, batch_actions

from palaestra import error

N = 8


def _single_action(action: np.ndarray) -> object:
    return int(action) if action.ndim == 0 else action


@pytest.mark.parametrize("env_id", list(CLASSES))
def test_rows_equal_single_envs(env_id: str) -> None:
    single_cls, batch_cls = CLASSES[env_id]
    singles = [single_cls() for _ in range(N)]
    batch = batch_cls(N)
    obs = batch.reset(seed=42)
    assert obs.shape == (N, *batch.single_observation_space.shape)
    assert obs.dtype == np.float32
    ref = np.stack([env.reset(seed=42 + i)[0] for i, env in enumerate(singles)])
    assert obs.tobytes() == ref.tobytes()
    rng = np.random.default_rng(3)
    resets = 0
    for t in range(400):
        actions = batch_actions(env_id, rng, obs)
        obs, reward, terminated = batch.step(actions)
        results = [env.step(_single_action(a)) for env, a in zip(singles, actions)]
        where = f"{env_id} step {t}"
        assert obs.tobytes() == np.stack([r[0] for r in results]).tobytes(), where
        assert reward.dtype == np.float64 and terminated.dtype == np.bool_
        np.testing.assert_array_equal(reward, [r[1] for r in results], err_msg=where)
        np.testing.assert_array_equal(terminated, [r[2] for r in results], err_msg=where)
        done = terminated | (rng.random(N) < 0.01)  # plus a few "truncations"
        if done.any():
            resets += int(done.sum())
            obs = batch.reset(mask=done)  # rows keep their own generators
            for i in np.flatnonzero(done):
                singles[i].reset()
            ref = np.stack([env.state for env in singles]).astype(np.float64)
            np.testing.assert_array_equal(batch.state, ref, err_msg=where)
    assert resets > 0


def test_seed_list_and_partial_reseed() -> None:
    single_cls, batch_cls = CLASSES["CartPole-v1"]
    batch = batch_cls(3)
    batch.reset(seed=[5, None, 9])
    assert batch.seeds[0] == 5 and batch.seeds[2] == 9
    mask = np.array([False, True, False])
    before = batch.state.copy()
    obs = batch.reset(seed=100, mask=mask)  # row 1 gets seed 100 + 1
    np.testing.assert_array_equal(batch.state[[0, 2]], before[[0, 2]])
    assert obs[1].tobytes() == single_cls().reset(seed=101)[0].tobytes()


def test_state_is_a_writable_rows_by_components_view() -> None:
    _, batch_cls = CLASSES["MountainCar-v0"]
    batch = batch_cls(4)
    batch.reset(seed=0)
    assert batch.state.shape == (4, 2) and batch.state.dtype == np.float64
    batch.state[2] = (0.55, 0.01)  # next to the flag, moving right
    _, _, terminated = batch.step(np.full(4, 2))
    assert terminated.tolist() == [False, False, True, False]


def test_spaces_and_repr() -> None:
    _, batch_cls = CLASSES["Pendulum-v1"]
    batch = batch_cls(5)
    assert batch.num_envs == 5
    assert batch.observation_space.shape == (5, 3)
    assert batch.single_action_space.shape == (1,)
    assert repr(batch) == "PendulumBatch(num_envs=5)"


def test_step_before_reset_and_bad_sizes() -> None:
    _, batch_cls = CLASSES["CartPole-v1"]
    with pytest.raises(ValueError, match="num_envs"):
        batch_cls(0)
    batch = batch_cls(3)
    with pytest.raises(error.ResetNeeded):
        batch.step(np.zeros(3, dtype=np.int64))
    with pytest.raises(ValueError, match="3 seeds"):
        batch.reset(seed=[1, 2])


@pytest.mark.parametrize(
    "actions, match",
    [
        (np.array([0, 1, 2]), r"rows \[2\]"),  # out of range, named by row
        (np.array([0, -1, 1]), r"rows \[1\]"),
        (np.array([0, 1]), "shape"),
        (np.array([0.0, 1.0, 1.0]), "dtype"),
        ([[0], [1], [1]], "shape"),
    ],
)
def test_discrete_batch_action_validation(actions: object, match: str) -> None:
    _, batch_cls = CLASSES["CartPole-v1"]
    batch = batch_cls(3)
    batch.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=match):
        batch.step(actions)


@pytest.mark.parametrize(
    "actions, match",
    [
        (np.array([[0.0], [np.nan], [0.0]]), r"rows \[1\].*not finite"),
        (np.array([[0.0], [0.0], [np.inf]]), r"rows \[2\]"),
        (np.zeros(3), "shape"),
        (np.zeros((3, 2)), "shape"),
        ([["a"], ["b"], ["c"]], "not numeric"),
    ],
)
def test_box_batch_action_validation(actions: object, match: str) -> None:
    _, batch_cls = CLASSES["MountainCarContinuous-v0"]
    batch = batch_cls(3)
    batch.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=match):
        batch.step(actions)


def test_batch_reset_options_checked_once() -> None:
    _, batch_cls = CLASSES["MountainCar-v0"]
    batch = batch_cls(2)
    with pytest.raises(ValueError, match="Lower bound"):
        batch.reset(seed=0, options={"low": 0.1, "high": -0.1})
    obs = batch.reset(seed=0, options={"low": -0.3, "high": -0.2})
    assert ((obs[:, 0] >= -0.3) & (obs[:, 0] <= -0.2)).all()


@pytest.mark.parametrize("env_id", list(CLASSES))
def test_many_resets_draw_like_single_envs(env_id: str) -> None:
    """Pre-drawn uniforms (refilled every few resets) give each row its single env's draws."""
    single_cls, batch_cls = CLASSES[env_id]
    singles = [single_cls() for _ in range(3)]
    batch = batch_cls(3)
    batch.reset(seed=7)
    for i, env in enumerate(singles):
        env.reset(seed=7 + i)
    rng = np.random.default_rng(0)
    per = batch._draws.per  # resets a row's pre-drawn uniforms hold
    for k in range(4 * per):  # past two buffer refills for every env, before and after a reseed
        mask = rng.random(3) < 0.7
        seed = 1000 + k if k in (per // 2, 2 * per) else None  # reseeding drops buffered draws
        obs = batch.reset(seed=seed, mask=mask)
        for i in np.flatnonzero(mask):
            ref, _ = singles[i].reset(seed=None if seed is None else seed + int(i))
            assert obs[i].tobytes() == ref.tobytes(), (k, i)


def test_bad_mask() -> None:
    _, batch_cls = CLASSES["CartPole-v1"]
    batch = batch_cls(3)
    with pytest.raises(ValueError, match="mask"):
        batch.reset(mask=np.array([1, 0, 1]))
    with pytest.raises(ValueError, match="mask"):
        batch.reset(mask=np.ones(4, dtype=bool))


@pytest.mark.filterwarnings("ignore::UserWarning")  # rows stepped past termination
@pytest.mark.parametrize("env_id", list(CLASSES))
def test_step_with_reset_mask_equals_step_then_reset(env_id: str) -> None:
    """The autoreset fast path: masked rows step, then are re-sampled; one obs pass for all."""
    single_cls, batch_cls = CLASSES[env_id]
    singles = [single_cls() for _ in range(N)]
    batch = batch_cls(N)
    obs = batch.reset(seed=9)
    for i, env in enumerate(singles):
        env.reset(seed=9 + i)
    rng = np.random.default_rng(4)
    mask = np.zeros(N, dtype=bool)
    resets = 0
    for t in range(300):
        actions = batch_actions(env_id, rng, obs)
        obs, reward, terminated = batch.step(actions, reset_mask=mask)
        results = [env.step(_single_action(a)) for env, a in zip(singles, actions)]
        ref_obs = [r[0] for r in results]
        for i in np.flatnonzero(mask):
            ref_obs[i] = singles[i].reset()[0]  # the step above is discarded, as in the batch
        assert obs.tobytes() == np.stack(ref_obs).tobytes(), t
        np.testing.assert_array_equal(reward, [r[1] for r in results], err_msg=str(t))
        np.testing.assert_array_equal(terminated, [r[2] for r in results], err_msg=str(t))
        resets += int(mask.sum())
        mask = terminated | (rng.random(N) < 0.02)
    assert resets > 0


def test_step_rejects_a_bad_reset_mask() -> None:
    _, batch_cls = CLASSES["CartPole-v1"]
    batch = batch_cls(3)
    batch.reset(seed=0)
    with pytest.raises(ValueError, match="reset_mask"):
        batch.step(np.zeros(3, dtype=np.int64), reset_mask=np.array([1, 0, 1]))


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("env_id", list(CLASSES))
def test_step_with_reset_mask_equals_reset_with_mask_on_many_rows(env_id: str) -> None:
    """Thousands of resets: fresh-row observations that differ from the stepped-row formula
    (Acrobot's float32 trig differs in ~0.1% of values) must still come out as reset() gives."""
    _, batch_cls = CLASSES[env_id]
    fused, twin = batch_cls(256), batch_cls(256)
    obs = fused.reset(seed=1)
    twin.reset(seed=1)
    rng = np.random.default_rng(6)
    mask = np.zeros(256, dtype=bool)
    for t in range(20):
        actions = batch_actions(env_id, rng, obs)
        obs, reward, terminated = fused.step(actions, reset_mask=mask)
        ref_obs, ref_reward, ref_terminated = twin.step(actions)
        np.testing.assert_array_equal(reward, ref_reward)
        np.testing.assert_array_equal(terminated, ref_terminated)
        if mask.any():
            ref_obs = twin.reset(mask=mask)
        assert obs.tobytes() == ref_obs.tobytes(), t
        mask = rng.random(256) < 0.8


# Per replayed env: an action draw, states to write (``-0.0`` for ``0.0`` too, whose sin
# differs; angles several periods out) and new constants that take other products.
_REPLAYED = {
    "Acrobot-v1": (
        lambda rng: rng.integers(0, 3, 4),
        [[0.3, 0.0, 1.0, -2.0], [0.3, -0.0, 1.0, -2.0], [3.0, -3.1, 12.5, 28.0]],
        {"LINK_MASS_2": 1.5, "LINK_LENGTH_1": 1.25},  # m2 != 1: the product the default skips
    ),
    "Pendulum-v1": (
        lambda rng: rng.uniform(-2.5, 2.5, (4, 1)).astype(np.float32),
        [[0.0, 1.0], [-0.0, -1.0], [20.5, 7.9]],
        {"m": 1.5, "l": 0.75, "max_speed": 6.0},
    ),
}


@pytest.mark.parametrize("chunk", [None, 3])
@pytest.mark.parametrize("env_id", list(_REPLAYED))
def test_replayed_batch_follows_state_writes_params_and_copies(
    env_id: str, chunk: int | None
) -> None:
    """A state written from outside, new params and a pickled copy: the replayed batch
    (recorded ``step_state``, trig kept from the last observation) still steps exactly as
    single envs in that state, in one replay or in chunks of 3 and 1 rows."""
    import dataclasses
    import pickle

    draw, written, changes = _REPLAYED[env_id]
    single_cls, batch_cls = CLASSES[env_id]
    batch = batch_cls(4)
    if chunk is not None:
        batch.chunk = chunk
    batch.reset(seed=3)
    singles = [single_cls() for _ in range(4)]
    for i, env in enumerate(singles):
        env.reset(seed=3 + i)
    rng = np.random.default_rng(8)

    def step_both(b: object, envs: list, t: int) -> None:
        actions = draw(rng)
        obs, reward, terminated = b.step(actions)  # type: ignore[attr-defined]
        results = [env.step(_single_action(a)) for env, a in zip(envs, actions)]
        assert obs.tobytes() == np.stack([r[0] for r in results]).tobytes(), t
        np.testing.assert_array_equal(reward, [r[1] for r in results])
        np.testing.assert_array_equal(terminated, [r[2] for r in results])

    for t in range(3):
        step_both(batch, singles, t)
    batch.state[:3] = written
    for env, row in zip(singles, written):
        env.state = np.array(row)
    for t in range(3, 6):
        step_both(batch, singles, t)
    batch.params = dataclasses.replace(batch.params, **changes)
    for env in singles:
        for name, value in changes.items():
            setattr(env, name, value)
    for t in range(6, 9):
        step_both(batch, singles, t)
    copied = pickle.loads(pickle.dumps(batch))
    twins = [pickle.loads(pickle.dumps(env)) for env in singles]
    for t in range(9, 12):
        step_both(copied, twins, t)
