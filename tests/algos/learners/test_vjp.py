"""Each hand-written vector-Jacobian product against torch.autograd of the same function (the
function written once over ``xp``, run on torch tensors), on random inputs and edge cases."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch

from palaestra.algos.dqn.objective import dqn_loss, dqn_loss_vjp
from palaestra.algos.learners import heads
from palaestra.algos.learners.mlp import mlp_forward, mlp_forward_vjp
from palaestra.algos.learners.xp import numpy_ops, torch_ops
from palaestra.algos.ppo.objective import ppo_loss, ppo_loss_vjp

RNG = np.random.default_rng(0)


def _f32(*shape: int, scale: float = 1.0) -> np.ndarray:
    return (RNG.normal(size=shape) * scale).astype(np.float32)


def _leaf(a: np.ndarray) -> torch.Tensor:
    return torch.tensor(a, requires_grad=True)


def _close(ours: np.ndarray, theirs: torch.Tensor | None, atol: float = 1e-5) -> None:
    assert theirs is not None
    np.testing.assert_allclose(ours, theirs.detach().numpy(), rtol=1e-4, atol=atol)


ACTS = [
    ("relu", 0.0),
    ("tanh", 0.0),
    ("elu", 1.0),
    ("elu", 0.5),
    ("leaky_relu", 0.01),
    ("sigmoid", 0.0),
    ("none", 0.0),
]


@pytest.mark.parametrize("act", ACTS, ids=[f"{a}-{p}" for a, p in ACTS])
def test_mlp_forward_vjp(act: tuple[str, float]) -> None:
    x = _f32(9, 4)
    ws = [_f32(6, 4), _f32(5, 6), _f32(3, 5)]
    bs = [_f32(6), _f32(5), _f32(3)]
    layers = [(w, b, act) for w, b in zip(ws, bs)]
    acts = mlp_forward([(w.copy(), b.copy(), a) for w, b, a in layers], x.copy())
    g_out = _f32(9, 3)
    grads = [np.empty_like(p) for w, b in zip(ws, bs) for p in (w, b)]
    g_x = mlp_forward_vjp(layers, acts, g_out, grads, input_grad=True)
    tw, tb, tx = [_leaf(w) for w in ws], [_leaf(b) for b in bs], _leaf(x)
    out = mlp_forward([(w, b, act) for w, b in zip(tw, tb)], tx)[-1]
    np.testing.assert_allclose(acts[-1], out.detach().numpy(), rtol=1e-5, atol=1e-6)
    (out * torch.as_tensor(g_out)).sum().backward()
    for ours, t in zip(grads, [p for w, b in zip(tw, tb) for p in (w, b)]):
        _close(ours, t.grad)
    _close(g_x, tx.grad)  # a critic's gradient with respect to its input
    assert mlp_forward_vjp(layers, acts, g_out, None) is None  # no parameter grads asked


def _head_check(
    evaluate: Any,
    vjp: Any,
    params: np.ndarray,
    actions: np.ndarray,
    g_mean_entropy: float,
    log_std: np.ndarray | None = None,
) -> None:
    """Loss = sum(g_lp * log_prob) + g_H * mean(entropy); compare d/d params (and log_std)."""
    g_lp = _f32(params.shape[0])
    np_args = (params,) if log_std is None else (params, log_std)
    lp, _, tape = evaluate(numpy_ops, *np_args, actions)
    got = vjp(tape, g_lp, g_mean_entropy)
    tp = _leaf(params)
    tls = None if log_std is None else _leaf(log_std)
    t_args = (tp,) if tls is None else (tp, tls)
    t_lp, t_ent, _ = evaluate(torch_ops, *t_args, torch.as_tensor(actions))
    np.testing.assert_allclose(lp, t_lp.detach().numpy(), rtol=1e-5, atol=1e-5)
    ((t_lp * torch.as_tensor(g_lp)).sum() + g_mean_entropy * t_ent.mean()).backward()
    if tls is None:
        _close(got, tp.grad)
    else:
        _close(got[0], tp.grad)
        _close(got[1], tls.grad)


@pytest.mark.parametrize("g_h", [0.0, -0.01, 0.3], ids=["ent0", "ent-", "ent+"])
def test_categorical_vjp(g_h: float) -> None:
    logits = _f32(8, 5, scale=2.0)
    logits[0] = [30.0, -30.0, 0.0, 0.0, 0.0]  # a near-deterministic row
    _head_check(
        heads.categorical_evaluate,
        heads.categorical_evaluate_vjp,
        logits,
        RNG.integers(0, 5, 8),
        g_h,
    )


def test_multi_categorical_vjp() -> None:
    sizes = [3, 2, 4]
    idx = np.stack([RNG.integers(0, n, 7) for n in sizes], axis=1)

    def evaluate(xp: Any, logits: Any, actions: Any) -> Any:
        return heads.multi_categorical_evaluate(xp, logits, actions, sizes)

    _head_check(evaluate, heads.multi_categorical_evaluate_vjp, _f32(7, 9), idx, -0.05)


@pytest.mark.parametrize("g_h", [0.0, -0.02])
def test_bernoulli_vjp(g_h: float) -> None:
    bits = RNG.integers(0, 2, (6, 4)).astype(np.float32)
    _head_check(
        heads.bernoulli_evaluate, heads.bernoulli_evaluate_vjp, _f32(6, 4, scale=3.0), bits, g_h
    )


@pytest.mark.parametrize("g_h", [0.0, -0.01])
def test_gaussian_vjp(g_h: float) -> None:
    _head_check(
        heads.gaussian_evaluate,
        heads.gaussian_evaluate_vjp,
        _f32(6, 3),
        _f32(6, 3),
        g_h,
        log_std=np.array([-0.5, 0.0, 0.7], np.float32),
    )


@pytest.mark.parametrize("case", ["random", "saturated", "log_std_bounds"])
def test_squashed_gaussian_vjp(case: str) -> None:
    # |u| below ~4 away from the edge cases: near |tanh| = 1, log(1 - a^2 + 1e-6) turns one
    # float32 ulp of tanh into a visible difference between any two implementations.
    mean, log_std, noise = _f32(7, 2, scale=0.5), _f32(7, 2, scale=0.3), _f32(7, 2)
    if case == "saturated":
        mean[:3] = [[20.0, -25.0], [30.0, 0.1], [-40.0, 0.5]]  # tanh == +-1 exactly in float32
    if case == "log_std_bounds":
        log_std[:3] = [[-25.0, 2.0], [5.0, -20.0], [-20.5, 2.5]]  # outside and on the bounds
    g_a, g_lp = _f32(7, 2), _f32(7)
    a, lp, tape = heads.squashed_gaussian_rsample(numpy_ops, mean, log_std, noise)
    g_mean, g_log_std = heads.squashed_gaussian_rsample_vjp(tape, g_a, g_lp)
    tm, tl = _leaf(mean), _leaf(log_std)
    ta, tlp, _ = heads.squashed_gaussian_rsample(torch_ops, tm, tl, torch.as_tensor(noise))
    np.testing.assert_allclose(a, ta.detach().numpy(), rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(lp, tlp.detach().numpy(), rtol=1e-4, atol=1e-4)
    ((ta * torch.as_tensor(g_a)).sum() + (tlp * torch.as_tensor(g_lp)).sum()).backward()
    _close(g_mean, tm.grad, atol=1e-4)
    _close(g_log_std, tl.grad, atol=1e-4)
    assert np.isfinite(lp).all()


def test_tanh_action_vjp_with_saturation() -> None:
    x = np.array([[0.0, 0.5, -3.0, 20.0, -40.0]], np.float32)
    g = _f32(1, 5)
    _, tape = heads.tanh_action(numpy_ops, x)
    tx = _leaf(x)
    ta, _ = heads.tanh_action(torch_ops, tx)
    (ta * torch.as_tensor(g)).sum().backward()
    _close(heads.tanh_action_vjp(tape, g), tx.grad)


def test_dqn_loss_vjp_with_huber_threshold() -> None:
    q, next_q = _f32(6, 3), _f32(6, 3)
    actions = np.array([0, 1, 2, 0, 1, 2])
    rewards, terminated = _f32(6), np.array([0, 1, 0, 0, 1, 0], np.float32)
    gamma = 0.9
    # rows 0 and 1 sit exactly at |diff| == 1 (both Huber branches have slope 1 there), row 2 at 0
    target = rewards + (1 - terminated) * gamma * next_q.max(axis=1)
    q[0, 0], q[1, 1], q[2, 2] = target[0] + 1.0, target[1] - 1.0, target[2]
    loss, _, tape = dqn_loss(numpy_ops, q, actions, rewards, terminated, next_q, gamma)
    tq = _leaf(q)
    t_loss, _, _ = dqn_loss(
        torch_ops,
        tq,
        torch.as_tensor(actions),
        torch.as_tensor(rewards),
        torch.as_tensor(terminated),
        torch.as_tensor(next_q),
        gamma,
    )
    t_loss.backward()
    assert loss == pytest.approx(float(t_loss), rel=1e-6)
    _close(dqn_loss_vjp(tape), tq.grad)


PPO_CASES = {
    "plain": dict(clip_range_vf=None, ent_coef=0.0, normalize_advantage=True),
    "vf_clip": dict(clip_range_vf=0.1, ent_coef=0.01, normalize_advantage=True),
    "no_norm": dict(clip_range_vf=0.3, ent_coef=0.02, normalize_advantage=False),
    "no_entropy": dict(clip_range_vf=None, ent_coef=0.05, normalize_advantage=True),
}


@pytest.mark.parametrize("name", sorted(PPO_CASES))
def test_ppo_loss_vjp(name: str) -> None:
    kw = PPO_CASES[name]
    n, clip = 12, 0.2
    old_lp = _f32(n)
    lp = old_lp + _f32(n, scale=0.3)
    # ratios exactly on the clip bounds and at 1 (the ties of min and clamp)
    lp[0], lp[1], lp[2] = old_lp[0] + np.log1p(clip), old_lp[1] + np.log1p(-clip), old_lp[2]
    adv, values, old_values, returns = _f32(n), _f32(n), _f32(n), _f32(n)
    values[3] = old_values[3] + 0.1  # the value clip's bound
    entropy = None if name == "no_entropy" else np.abs(_f32(n))
    _, metrics, tape = ppo_loss(
        numpy_ops, lp, old_lp, adv, values, old_values, returns, entropy, clip, **kw
    )
    g_lp, g_v, g_h = ppo_loss_vjp(tape)
    t_lp, t_v = _leaf(lp), _leaf(values)
    t_ent = None if entropy is None else _leaf(entropy)
    t = torch.as_tensor
    t_loss, t_metrics, _ = ppo_loss(
        torch_ops, t_lp, t(old_lp), t(adv), t_v, t(old_values), t(returns), t_ent, clip, **kw
    )
    t_loss.backward()
    _close(g_lp, t_lp.grad)
    _close(g_v, t_v.grad)
    if t_ent is not None:  # the gradient of the mean entropy, spread evenly over the rows
        _close(np.full(n, g_h / n, np.float32), t_ent.grad)
    for key, value in metrics.items():
        tol = 2.5 / n if key == "clip_fraction" else 1e-6  # the rows on the bounds may flip
        assert value == pytest.approx(float(t_metrics[key]), rel=1e-4, abs=tol), key


@pytest.mark.parametrize("n_critics", [1, 2, 3])
def test_actor_critic_loss_vjps(n_critics: int) -> None:
    """The SAC/TD3 losses' VJPs, with a tie between critics (torch.minimum splits it)."""
    from palaestra.algos.learners import losses
    from palaestra.algos.sac import objective as sac
    from palaestra.algos.td3 import objective as td3

    n = 10
    qs = [_f32(n) for _ in range(n_critics)]
    if n_critics > 1:
        qs[1][:3] = qs[0][:3]  # ties in the minimum
    log_prob, target = _f32(n), _f32(n)
    t_qs = [_leaf(q) for q in qs]
    t_lp = _leaf(log_prob)

    _, _, tape = losses.q_regression_loss(numpy_ops, qs, target, 0.5)
    loss, _, _ = losses.q_regression_loss(torch_ops, t_qs, torch.as_tensor(target), 0.5)
    loss.backward()
    for ours, t in zip(losses.q_regression_loss_vjp(tape), t_qs):
        _close(ours, t.grad)

    t_qs = [_leaf(q) for q in qs]
    _, _, tape = sac.soft_actor_loss(numpy_ops, 0.2, log_prob, qs)
    loss, _, _ = sac.soft_actor_loss(torch_ops, 0.2, t_lp, t_qs)
    loss.backward()
    g_lp, g_qs = sac.soft_actor_loss_vjp(tape)
    _close(g_lp, t_lp.grad)
    for ours, t in zip(g_qs, t_qs):
        _close(ours, t.grad)

    t_q = _leaf(qs[0])
    _, _, tape = td3.deterministic_actor_loss(numpy_ops, qs[0])
    td3.deterministic_actor_loss(torch_ops, t_q)[0].backward()
    _close(td3.deterministic_actor_loss_vjp(tape), t_q.grad)

    log_alpha = np.array([-0.3], np.float32)
    t_alpha = _leaf(log_alpha)
    _, _, tape = sac.ent_coef_loss(numpy_ops, log_alpha, log_prob, -1.0)
    sac.ent_coef_loss(torch_ops, t_alpha, t_lp.detach(), -1.0)[0].backward()
    _close(sac.ent_coef_loss_vjp(tape), t_alpha.grad)


def test_large_products_agree_with_numpy() -> None:
    """Products past ``LARGE_PRODUCT`` run on torch's kernels over the same memory: the same
    values to float32 rounding, into ``out`` too, transposed operands included."""
    from palaestra.algos.learners import mlp

    a, b = _f32(256, 300), _f32(256, 200)
    assert 300 * 256 * 200 >= mlp.LARGE_PRODUCT
    out = np.empty((300, 200), np.float32)
    got = mlp._product(a.T, b, out=out)
    assert got is out
    np.testing.assert_allclose(out, a.T.astype(np.float64) @ b, rtol=1e-4, atol=1e-3)
    small = _f32(8, 4)
    np.testing.assert_array_equal(mlp._product(small, small.T), small.dot(small.T))
