"""The batched engines' fast paths agree with the single envs where the parity runs do not reach.

``test_batched.py`` covers the default CartPole; these cover the other CartPole variants (the
generic semi-implicit path, Sutton-Barto rewards), many buffer refills per row, and the
one-reduction bounds check of discrete actions on unusual integer dtypes.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from tests.envs.cases import CLASSES

from palaestra import error

N = 6


def _run_cartpole(batch: object, singles: list, steps: int = 300) -> None:
    obs = batch.reset(seed=11)  # type: ignore[attr-defined]
    ref = np.stack([env.reset(seed=11 + i)[0] for i, env in enumerate(singles)])
    assert obs.tobytes() == ref.tobytes()
    rng = np.random.default_rng(5)
    for t in range(steps):
        actions = rng.integers(0, 2, N)
        obs, reward, terminated = batch.step(actions)  # type: ignore[attr-defined]
        results = [env.step(int(a)) for env, a in zip(singles, actions)]
        assert obs.tobytes() == np.stack([r[0] for r in results]).tobytes(), t
        np.testing.assert_array_equal(reward, [r[1] for r in results], err_msg=str(t))
        np.testing.assert_array_equal(terminated, [r[2] for r in results], err_msg=str(t))
        done = terminated & (rng.random(N) < 0.7)  # some rows step on past termination
        if done.any():
            obs = batch.reset(mask=done)  # type: ignore[attr-defined]
            for i in np.flatnonzero(done):
                singles[i].reset()


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("sutton_barto", [False, True])
def test_cartpole_rewards_after_termination_match(sutton_barto: bool) -> None:
    single_cls, batch_cls = CLASSES["CartPole-v1"]
    batch = batch_cls(N, sutton_barto_reward=sutton_barto)
    _run_cartpole(batch, [single_cls(sutton_barto_reward=sutton_barto) for _ in range(N)])


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_cartpole_semi_implicit_rows_match() -> None:
    single_cls, batch_cls = CLASSES["CartPole-v1"]
    batch = batch_cls(N)
    batch.params = type(batch.params)(kinematics_integrator="semi-implicit euler")
    singles = [single_cls() for _ in range(N)]
    for env in singles:
        env.kinematics_integrator = "semi-implicit euler"
    _run_cartpole(batch, singles)


@pytest.mark.parametrize("env_id", ["CartPole-v1", "MountainCar-v0"])
def test_hundreds_of_resets_draw_like_single_envs(env_id: str) -> None:
    """Several refills of every row's pre-drawn uniforms (``_draws.per`` resets each)."""
    single_cls, batch_cls = CLASSES[env_id]
    singles = [single_cls() for _ in range(2)]
    batch = batch_cls(2)
    batch.reset(seed=3)
    for i, env in enumerate(singles):
        env.reset(seed=3 + i)
    all_rows = np.ones(2, dtype=bool)
    for k in range(3 * batch._draws.per + 2):
        obs = batch.reset(mask=all_rows)
        ref = np.stack([env.reset()[0] for env in singles])
        assert obs.tobytes() == ref.tobytes(), k


@pytest.mark.parametrize("dtype", ["<i8", ">i8", "i1", "<i4", ">i4", "u2", ">u8"])
def test_discrete_batch_check_on_integer_dtypes(dtype: str) -> None:
    _, batch_cls = CLASSES["CartPole-v1"]
    batch = batch_cls(3)
    batch.reset(seed=0)
    batch.step(np.array([0, 1, 1], dtype=dtype))
    with pytest.raises(error.InvalidAction, match=r"rows \[1\]"):
        batch.step(np.array([0, 2, 1], dtype=dtype))
    if np.dtype(dtype).kind == "i":
        with pytest.raises(error.InvalidAction, match=r"rows \[2\]"):
            batch.step(np.array([0, 1, -1], dtype=dtype))


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("sutton_barto", [False, True])
def test_params_replaced_between_steps_reach_the_array_step(sutton_barto: bool) -> None:
    """The array step runs on a cached copy of ``params`` (0-d array constants): replacing
    ``params`` after steps have run must rebuild it. (A long tau also brings poles stepped
    past termination back within bounds, the case below.)"""
    single_cls, batch_cls = CLASSES["CartPole-v1"]
    batch = batch_cls(N, sutton_barto_reward=sutton_barto)
    singles = [single_cls(sutton_barto_reward=sutton_barto) for _ in range(N)]
    _run_cartpole(batch, singles, steps=20)
    batch.params = dataclasses.replace(batch.params, gravity=3.5, tau=0.05)
    for env in singles:
        env.gravity, env.tau = 3.5, 0.05
    _run_cartpole(batch, singles, steps=50)


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("sutton_barto", [False, True])
def test_reward_of_a_pole_back_within_bounds_after_termination(sutton_barto: bool) -> None:
    """Gymnasium pays a non-terminating step as usual even after an unreset termination."""
    single_cls, batch_cls = CLASSES["CartPole-v1"]
    batch, single = batch_cls(1, sutton_barto_reward=sutton_barto), single_cls(sutton_barto)
    batch.reset(seed=0)
    single.reset(seed=0)
    rewards = []
    for state in ([2.39, 1.0, 0.0, 0.0], [2.41, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]):
        batch.state[0] = state  # terminates, stays out, then is put back in bounds
        single.state = state
        _, reward, terminated = batch.step(np.array([1]))
        _, ref_reward, ref_terminated, _, _ = single.step(1)
        assert (reward[0], terminated[0]) == (ref_reward, ref_terminated)
        rewards.append(ref_reward)
    assert rewards == ([-1.0, -1.0, 0.0] if sutton_barto else [1.0, 0.0, 1.0])


def _cartpole_trace(batch_cls: type, rows: int, integrator: str, states: np.ndarray) -> list:
    """Observations, rewards, terminations and states of ``rows`` CartPoles over 500 steps
    from ``states`` (re-set every 50 steps), resetting rows that ended."""
    batch = batch_cls(rows, sutton_barto_reward=integrator != "euler")
    batch.params = type(batch.params)(kinematics_integrator=integrator)
    batch.reset(seed=3)
    rng = np.random.default_rng(9)
    trace = []
    with np.errstate(all="ignore"):  # the NaN and inf rows
        for t in range(500):
            if t % 50 == 0:
                batch.state[...] = states[t // 50]
            obs, reward, terminated = batch.step(rng.integers(0, 2, rows))
            trace.append((obs.tobytes(), reward.tobytes(), terminated.tobytes()))
            trace.append(batch.state.tobytes())
            done = terminated & (rng.random(rows) < 0.5)
            if done.any():
                batch.reset(mask=done)
    return trace


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("rows", [1, 8, 16])
@pytest.mark.parametrize("integrator", ["euler", "semi-implicit euler"])
def test_cartpole_row_by_row_step_equals_the_array_step(
    monkeypatch: pytest.MonkeyPatch, rows: int, integrator: str
) -> None:
    """Up to ``SCALAR_ROWS`` rows step on Python floats; the array step gives the same bits,
    also for states far outside the episode's range, infinities and NaN."""
    from palaestra.envs.classic_control import cartpole

    assert rows <= cartpole.SCALAR_ROWS
    rng = np.random.default_rng(1)
    states = rng.normal(0.0, 1.0, (10, rows, 4)) * rng.choice([1e-3, 1.0, 1e3], (10, rows, 4))
    states[9, 0] = [np.nan, np.inf, -np.inf, 0.5]
    _, batch_cls = CLASSES["CartPole-v1"]
    row_by_row = _cartpole_trace(batch_cls, rows, integrator, states)
    monkeypatch.setattr(cartpole, "SCALAR_ROWS", 0)  # every batch takes the array step
    assert _cartpole_trace(batch_cls, rows, integrator, states) == row_by_row
