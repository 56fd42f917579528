"""gSDE's maths in ``learners.heads``: each numpy VJP against torch.autograd of the same function
(written once over ``xp``, run on torch tensors), for every std parameterisation, squashed or
not, with the features learned (SAC) or not (PPO)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from palaestra.algos.learners import heads
from palaestra.algos.learners.xp import numpy_ops, torch_ops

RNG = np.random.default_rng(7)
B, L, D = 9, 5, 3


def _f32(*shape: int, scale: float = 1.0) -> np.ndarray:
    return (RNG.normal(size=shape) * scale).astype(np.float32)


def _leaf(a: np.ndarray) -> torch.Tensor:
    return torch.tensor(a, requires_grad=True)


def _close(ours: np.ndarray | None, theirs: torch.Tensor | None) -> None:
    assert ours is not None and theirs is not None
    np.testing.assert_allclose(ours, theirs.detach().numpy(), rtol=2e-4, atol=2e-5)


STDS = [(False, True), (True, True), (False, False), (True, False)]
STD_IDS = ["exp-full", "expln-full", "exp-shared", "expln-shared"]


def _log_std(full_std: bool) -> np.ndarray:
    # Both signs, so expln's two branches are both crossed.
    return _f32(L, D if full_std else 1, scale=0.8)


@pytest.mark.parametrize(("use_expln", "full_std"), STDS, ids=STD_IDS)
def test_sde_std_matches_torch_and_its_vjp(use_expln: bool, full_std: bool) -> None:
    log_std = _log_std(full_std)
    std, tape = heads.sde_std(numpy_ops, log_std, use_expln, full_std, D)
    t_log_std = _leaf(log_std)
    t_std, _ = heads.sde_std(torch_ops, t_log_std, use_expln, full_std, D)
    assert std.shape == (L, D) and std.dtype == np.float32
    np.testing.assert_allclose(std, t_std.detach().numpy(), rtol=1e-6)
    g = _f32(L, D)
    (t_std * torch.as_tensor(g)).sum().backward()
    _close(heads.sde_std_vjp(tape, g), t_log_std.grad)


def test_sde_std_expln_values() -> None:
    """expln: exp below zero, log1p(x + 1e-6) + 1 above (continuous at 0)."""
    log_std = np.array([[-1.0, 0.0, 2.0]], dtype=np.float32)
    std, _ = heads.sde_std(numpy_ops, log_std, True, True, 3)
    np.testing.assert_allclose(std, [[np.exp(-1.0), 1.0, np.log1p(2.0 + 1e-6) + 1.0]], rtol=1e-6)


@pytest.mark.parametrize("squash", [False, True], ids=["gaussian", "squashed"])
@pytest.mark.parametrize("latent_grad", [False, True], ids=["frozen-features", "learned"])
@pytest.mark.parametrize("g_h", [0.0, 0.37])
def test_sde_log_prob_vjp(squash: bool, latent_grad: bool, g_h: float) -> None:
    mean, std, latent = _f32(B, D), np.exp(_f32(L, D, scale=0.5)), _f32(B, L)
    x = _f32(B, D, scale=1.5)
    g_lp = _f32(B)
    lp, ent, tape = heads.sde_log_prob(numpy_ops, mean, std, latent, x, squash)
    got = heads.sde_log_prob_vjp(tape, g_lp, g_h, latent_grad)
    tm, ts, tl, tx = (_leaf(a) for a in (mean, std, latent, x))
    t_lp, t_ent, _ = heads.sde_log_prob(torch_ops, tm, ts, tl, tx, squash)
    np.testing.assert_allclose(lp, t_lp.detach().numpy(), rtol=1e-5, atol=1e-5)
    loss = (t_lp * torch.as_tensor(g_lp)).sum()
    if squash:
        assert ent is None and t_entropy_is_none(t_ent)
    else:
        assert ent.shape == (B,)
        loss = loss + g_h * t_ent.mean()
    loss.backward()
    _close(got[0], tm.grad)
    _close(got[1], ts.grad)
    if latent_grad:
        _close(got[2], tl.grad)
    else:
        assert got[2] is None
    _close(got[3], tx.grad)


def t_entropy_is_none(entropy: object) -> bool:
    return entropy is None


def test_sde_log_prob_is_the_normal_of_latent_noise() -> None:
    """The variance is ``latent^2 @ std^2`` (+1e-6): the density of ``latent @ W`` for
    ``W ~ N(0, std^2)``, checked against torch.distributions.Normal."""
    mean, std, latent, x = _f32(B, D), np.exp(_f32(L, D)), _f32(B, L), _f32(B, D)
    lp, ent, _ = heads.sde_log_prob(numpy_ops, mean, std, latent, x, False)
    sigma = torch.sqrt(torch.as_tensor(latent**2) @ torch.as_tensor(std**2) + 1e-6)
    normal = torch.distributions.Normal(torch.as_tensor(mean), sigma)
    np.testing.assert_allclose(lp, normal.log_prob(torch.as_tensor(x)).sum(1), rtol=1e-5)
    np.testing.assert_allclose(ent, normal.entropy().sum(1), rtol=1e-5)


@pytest.mark.parametrize("with_action_grad", [True, False])
def test_sde_rsample_vjp(with_action_grad: bool) -> None:
    # Scaled so tanh does not saturate: 1 - a^2 + 1e-6 loses its digits in float32 there.
    mean, std, latent = _f32(B, D, scale=0.5), np.exp(_f32(L, D, scale=0.3)), _f32(B, L, scale=0.3)
    eps = _f32(L, D)
    g_a = _f32(B, D) if with_action_grad else None
    g_lp = _f32(B)
    a, lp, tape = heads.sde_rsample(numpy_ops, mean, std, latent, eps)
    g_mean, g_std, g_latent = heads.sde_rsample_vjp(tape, g_a, g_lp)
    tm, ts, tl = (_leaf(v) for v in (mean, std, latent))
    t_a, t_lp, _ = heads.sde_rsample(torch_ops, tm, ts, tl, torch.as_tensor(eps))
    np.testing.assert_allclose(a, t_a.detach().numpy(), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(lp, t_lp.detach().numpy(), rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(a, np.tanh(mean + latent @ (std * eps)), rtol=1e-5, atol=1e-6)
    loss = (t_lp * torch.as_tensor(g_lp)).sum()
    if g_a is not None:
        loss = loss + (t_a * torch.as_tensor(g_a)).sum()
    loss.backward()
    _close(g_mean, tm.grad)
    _close(g_std, ts.grad)
    _close(g_latent, tl.grad)


def test_sde_noise_one_matrix_or_one_per_row() -> None:
    """SB3's get_noise: a batch of one, or a batch not of the matrices' count, uses the single
    matrix; otherwise row i uses matrix i."""
    latent, mat, mats = _f32(4, L), _f32(L, D), _f32(4, L, D)
    np.testing.assert_allclose(heads.sde_noise(numpy_ops, latent, mat, None), latent @ mat)
    rows = heads.sde_noise(numpy_ops, latent, mat, mats)
    np.testing.assert_allclose(rows, np.stack([latent[i] @ mats[i] for i in range(4)]), rtol=1e-6)
    np.testing.assert_allclose(heads.sde_noise(numpy_ops, latent[:3], mat, mats), latent[:3] @ mat)
    one = heads.sde_noise(numpy_ops, latent[:1], mat, mats[:1])
    np.testing.assert_allclose(one, latent[:1] @ mat)
    t_args = (torch.as_tensor(a) for a in (latent, mat, mats))
    t = heads.sde_noise(torch_ops, *t_args)
    np.testing.assert_allclose(t.numpy(), rows, rtol=1e-6)


def test_tanh_inverse_clips_saturated_actions() -> None:
    y = np.array([[-1.0, -0.5, 0.0, 0.999, 1.0]], dtype=np.float32)
    x = heads.tanh_inverse(numpy_ops, y)
    assert np.isfinite(x).all()
    np.testing.assert_allclose(np.tanh(x[:, 1:4]), y[:, 1:4], rtol=1e-5)
    np.testing.assert_allclose(x, heads.tanh_inverse(torch_ops, torch.as_tensor(y)).numpy())
