"""Hand-computed checks of the pure math: schedules, GAE, PPO and DQN losses, polyak."""

import math

import numpy as np
import pytest
import torch

from palaestra.algos.dqn.objective import dqn_loss
from palaestra.algos.learners.losses import explained_variance, gae, polyak
from palaestra.algos.learners.xp import numpy_ops, torch_ops
from palaestra.algos.ppo.objective import ppo_loss
from palaestra.algos.schedules import (
    ConstantSchedule,
    LinearSchedule,
    TabulatedSchedule,
    as_schedule,
    schedule_from_json,
    schedule_to_json,
)


def test_linear_schedule_matches_sb3_get_linear_fn() -> None:
    from stable_baselines3.common.utils import LinearSchedule as SB3Linear

    ours, theirs = LinearSchedule(1.0, 0.05, 0.1), SB3Linear(1.0, 0.05, 0.1)
    for p in np.linspace(1.0, 0.0, 101):
        assert ours(p) == pytest.approx(theirs(p))
    assert LinearSchedule(3e-4, 0.0)(0.25) == pytest.approx(0.75e-4)
    assert LinearSchedule(1.0, 0.0, 0.0)(1.0) == 0.0  # zero fraction: already at the end


def test_as_schedule_and_json_roundtrip() -> None:
    assert as_schedule(0.5)(0.1) == 0.5
    fn = as_schedule(lambda p: 2 * p)
    assert fn(0.25) == 0.5
    with pytest.raises(TypeError):
        as_schedule("fast")  # type: ignore[arg-type]
    for s in (ConstantSchedule(1e-3), LinearSchedule(1.0, 0.1, 0.3)):
        assert schedule_from_json(schedule_to_json(s)) == s
    table = schedule_from_json(schedule_to_json(lambda p: p * p))
    assert isinstance(table, TabulatedSchedule)
    assert table(0.5) == pytest.approx(0.25, abs=1e-6)
    with pytest.raises(ValueError):
        schedule_from_json({"type": "python", "code": "import os"})


def test_gae_by_hand_with_episode_boundary() -> None:
    # One env, 3 steps; the episode ends after step 1 (episode_starts[2] = 1).
    r = np.array([[1.0], [2.0], [3.0]], dtype=np.float32)
    v = np.array([[0.5], [1.0], [1.5]], dtype=np.float32)
    starts = np.array([[1.0], [0.0], [1.0]], dtype=np.float32)
    g, lam = 0.9, 0.5
    adv, ret = gae(r, v, starts, np.array([2.0]), np.array([0.0]), g, lam)
    d2 = 3.0 + g * 2.0 - 1.5  # bootstraps from last_values (not done)
    d1 = 2.0 - 1.0  # next step starts a new episode: no bootstrap
    d0 = 1.0 + g * 1.0 - 0.5
    a2, a1 = d2, d1
    a0 = d0 + g * lam * a1
    np.testing.assert_allclose(adv.ravel(), [a0, a1, a2], rtol=1e-6)
    np.testing.assert_allclose(ret, adv + v, rtol=1e-6)


def test_gae_matches_sb3_rollout_buffer() -> None:
    from gymnasium import spaces as gspaces
    from stable_baselines3.common.buffers import RolloutBuffer as SB3Buffer

    rng = np.random.default_rng(0)
    t, n = 7, 3
    sb3 = SB3Buffer(
        t, gspaces.Box(-1, 1, (2,)), gspaces.Discrete(2), n_envs=n, gamma=0.97, gae_lambda=0.9
    )
    rewards, values = rng.normal(size=(t, n)), rng.normal(size=(t, n))
    starts = (rng.random((t, n)) < 0.3).astype(np.float32)
    for i in range(t):
        sb3.add(
            np.zeros((n, 2)),
            np.zeros((n, 1)),
            rewards[i],
            starts[i],
            torch.as_tensor(values[i]),
            torch.zeros(n),
        )
    last_v, dones = rng.normal(size=n), np.array([True, False, True])
    sb3.compute_returns_and_advantage(torch.as_tensor(last_v), dones)
    adv, ret = gae(
        rewards.astype(np.float32),
        values.astype(np.float32),
        starts,
        last_v.astype(np.float32),
        dones,
        0.97,
        0.9,
    )
    np.testing.assert_allclose(adv, sb3.advantages, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(ret, sb3.returns, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("xp", [numpy_ops, torch_ops], ids=["numpy", "torch"])
def test_ppo_loss_by_hand(xp) -> None:  # type: ignore[no-untyped-def]
    old = torch.log(torch.tensor([0.5, 0.5]))
    new = torch.log(torch.tensor([0.75, 0.25]))  # ratios 1.5 and 0.5
    adv = torch.tensor([1.0, 1.0])
    values, returns = torch.tensor([1.0, 2.0]), torch.tensor([2.0, 2.0])
    args = [new, old, adv, values, values, returns, torch.tensor([0.3, 0.1])]
    if xp is numpy_ops:
        args = [a.numpy() for a in args]
    _, out, _ = ppo_loss(
        xp, *args, clip_range=0.2, ent_coef=0.01, vf_coef=0.5, normalize_advantage=False
    )
    # min(1.5, 1.2) = 1.2 and min(0.5, 0.8) = 0.5 -> policy loss -(1.2 + 0.5) / 2
    assert float(out["policy_loss"]) == pytest.approx(-0.85)
    assert float(out["value_loss"]) == pytest.approx(0.5)
    assert float(out["entropy_loss"]) == pytest.approx(-0.2)
    assert float(out["loss"]) == pytest.approx(-0.85 + 0.01 * -0.2 + 0.5 * 0.5)
    assert float(out["clip_fraction"]) == 1.0
    kl = np.mean([(1.5 - 1) - math.log(1.5), (0.5 - 1) - math.log(0.5)])
    assert float(out["approx_kl"]) == pytest.approx(kl)


def test_ppo_loss_value_clipping_and_normalisation() -> None:
    v_old, v_new, ret = torch.tensor([0.0]), torch.tensor([1.0]), torch.tensor([1.0])
    lp = torch.zeros(1)
    _, clipped, _ = ppo_loss(
        torch_ops, lp, lp, torch.ones(1), v_new, v_old, ret, None, 0.2, clip_range_vf=0.1
    )
    assert float(clipped["value_loss"]) == pytest.approx(0.81)  # (1 - 0.1)^2
    assert float(clipped["entropy_loss"]) == 0.0  # -mean(-log_prob) with log_prob 0
    adv = torch.tensor([1.0, 3.0])
    lp2 = torch.tensor([0.1, 0.0])
    z = torch.zeros(2)
    _, normed, _ = ppo_loss(torch_ops, lp2, z, adv, z, z, z, None, 0.2)
    a = (adv - adv.mean()) / (adv.std() + 1e-8)  # [-0.707, 0.707]
    expect = -torch.min(a * lp2.exp(), a * torch.clamp(lp2.exp(), 0.8, 1.2)).mean()
    assert float(normed["policy_loss"]) == pytest.approx(float(expect))


def test_dqn_loss_huber_and_time_limit() -> None:
    q = torch.tensor([[1.0, 5.0], [0.0, 0.0]], requires_grad=True)
    next_q = torch.tensor([[2.0, 4.0], [10.0, 0.0]])
    loss, _, _ = dqn_loss(
        torch_ops,
        q,
        torch.tensor([1, 0]),
        torch.tensor([1.0, 1.0]),
        torch.tensor([0.0, 1.0]),
        next_q,
        gamma=0.5,
    )
    # row 0: target 1 + 0.5*4 = 3, error 2 -> 1.5 (linear part); row 1: terminal, error 1 -> 0.5
    assert float(loss.detach()) == pytest.approx((1.5 + 0.5) / 2)
    loss.backward()
    assert q.grad is not None and float(q.grad[0, 0]) == 0.0


def test_polyak_update() -> None:
    online, target = [torch.tensor([1.0, 2.0])], [torch.tensor([0.0, 0.0])]
    polyak(online, target, 0.25)
    assert target[0].tolist() == [0.25, 0.5]
    polyak(online, target, 1.0)
    assert target[0].tolist() == [1.0, 2.0]


def test_explained_variance() -> None:
    assert math.isnan(explained_variance(np.ones(3), np.ones(3)))
    assert explained_variance(np.zeros(2), np.array([1.0, -1.0])) == pytest.approx(0.0)


def test_gae_equals_the_step_by_step_recursion_bit_for_bit() -> None:
    """The vectorised per-step terms do the same float32 operations as SB3's loop."""
    rng = np.random.default_rng(1)
    t, n, g, lam = 64, 4, 0.99, 0.95
    rewards = rng.normal(size=(t, n)).astype(np.float32)
    values = rng.normal(size=(t, n)).astype(np.float32)
    starts = (rng.random((t, n)) < 0.1).astype(np.float32)
    last_v, dones = rng.normal(size=n).astype(np.float32), np.array([1, 0, 0, 1], np.float32)
    expected = np.zeros_like(rewards)
    last = np.zeros(n, dtype=np.float32)
    for i in reversed(range(t)):
        nnt = 1.0 - dones if i == t - 1 else 1.0 - starts[i + 1]
        nv = last_v if i == t - 1 else values[i + 1]
        delta = rewards[i] + g * nv * nnt - values[i]
        last = delta + g * lam * nnt * last
        expected[i] = last
    adv, ret = gae(rewards, values, starts, last_v, dones, g, lam)
    assert adv.dtype == ret.dtype == np.float32
    np.testing.assert_array_equal(adv, expected)
    np.testing.assert_array_equal(ret, expected + values)
