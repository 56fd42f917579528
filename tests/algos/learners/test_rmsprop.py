"""``FlatRMSprop`` against ``torch.optim.RMSprop`` over many steps, its state handed to torch
and back, and the learner picking the flat optimizer by the torch optimizer's type."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import torch

from palaestra.algos.learners.learner import flat_unsupported
from palaestra.algos.learners.rmsprop import FlatRMSprop


def _pair(**kwargs: float) -> tuple[list, list, torch.optim.Optimizer, torch.optim.Optimizer]:
    gen = torch.Generator().manual_seed(0)
    shapes = [(6, 4), (6,), (3, 6), (3,)]
    theirs = [torch.nn.Parameter(torch.randn(s, generator=gen)) for s in shapes]
    ours = [torch.nn.Parameter(p.detach().clone()) for p in theirs]
    ref = torch.optim.RMSprop(theirs, foreach=False, **kwargs)
    return theirs, ours, ref, torch.optim.RMSprop(ours, **kwargs)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"lr": 7e-4, "alpha": 0.99, "eps": 1e-5, "weight_decay": 0.0},  # SB3's A2C
        {"lr": 1e-2, "alpha": 0.9, "eps": 1e-8, "weight_decay": 1e-3},
    ],
    ids=["sb3", "weight_decay"],
)
def test_flat_rmsprop_matches_torch_and_hands_its_state_over(kwargs: dict[str, float]) -> None:
    theirs, ours, ref, opt = _pair(**kwargs)
    bounds = np.cumsum([0] + [p.numel() for p in ours]).tolist()
    slices = [slice(a, b) for a, b in itertools.pairwise(bounds)]
    flat_opt = FlatRMSprop(bounds[-1], len(ours), slices)
    flat_opt.from_torch(opt, ours)
    assert (flat_opt.lr, flat_opt.alpha, flat_opt.eps, flat_opt.weight_decay) == (
        kwargs["lr"],
        kwargs["alpha"],
        kwargs["eps"],
        kwargs["weight_decay"],
    )
    flat = np.concatenate([p.detach().numpy().ravel() for p in ours])
    rng = np.random.default_rng(0)
    for step in range(300):
        # gradients of changing scale, as training sees them (and exact zeros)
        grads = [
            (rng.standard_normal(p.shape) * 10.0 ** -(step % 4)).astype(np.float32) for p in theirs
        ]
        grads[1][0] = 0.0
        flat_opt.grad[:] = np.concatenate([g.ravel() for g in grads])
        flat_opt.step(flat)
        for p, g in zip(theirs, grads):
            p.grad = torch.from_numpy(g.copy())
        ref.step()
    expected = np.concatenate([p.detach().numpy().ravel() for p in theirs])
    np.testing.assert_allclose(flat, expected, atol=1e-6, rtol=1e-5)
    flat_opt.to_torch(opt, ours)
    for p, q in zip(ours, theirs):
        st, rt = opt.state[p], ref.state[q]
        assert set(st) == set(rt) == {"step", "square_avg"}
        assert float(st["step"]) == float(rt["step"]) == 300.0
        torch.testing.assert_close(st["square_avg"], rt["square_avg"], atol=1e-9, rtol=1e-5)
    # the round trip: what torch holds is read back as it was handed over
    again = FlatRMSprop(bounds[-1], len(ours), slices)
    again.from_torch(opt, ours)
    np.testing.assert_array_equal(again.square_avg, flat_opt.square_avg)
    np.testing.assert_array_equal(again.steps, flat_opt.steps)
    # and a torch optimizer loading that state continues exactly as the reference does
    for p, sl in zip(ours, slices):
        with torch.no_grad():
            p.copy_(torch.from_numpy(flat[sl]).view_as(p))
    g = [torch.ones_like(p) for p in ours]
    for p, q, gi in zip(ours, theirs, g):
        p.grad, q.grad = gi.clone(), gi.clone()
    opt.step()
    ref.step()
    for p, q in zip(ours, theirs):
        torch.testing.assert_close(p.detach(), q.detach(), atol=1e-6, rtol=1e-5)


def test_never_stepped_tensors_have_no_torch_state() -> None:
    _, ours, _, opt = _pair(lr=1e-3)
    bounds = np.cumsum([0] + [p.numel() for p in ours]).tolist()
    slices = [slice(a, b) for a, b in itertools.pairwise(bounds)]
    flat_opt = FlatRMSprop(bounds[-1], len(ours), slices)
    flat_opt.to_torch(opt, ours)
    assert not opt.state


def test_flat_optimizer_is_picked_by_type() -> None:
    params = [torch.nn.Parameter(torch.zeros(2))]
    assert flat_unsupported(torch.optim.RMSprop(params)) is None
    assert flat_unsupported(torch.optim.Adam(params)) is None
    cases = [
        (torch.optim.SGD(params, lr=0.1), "the optimizer is SGD, not Adam or RMSprop"),
        (torch.optim.RMSprop(params, momentum=0.9), "RMSprop with momentum"),
        (torch.optim.RMSprop(params, centered=True), "RMSprop with centered=True"),
        (torch.optim.RMSprop(params, maximize=True), "RMSprop with maximize=True"),
        (torch.optim.Adam(params, amsgrad=True), "Adam with amsgrad=True"),
    ]
    for optimizer, why in cases:
        assert flat_unsupported(optimizer) == why
