"""``FlatAdam``: torch's Adam on one flat buffer, kept consistent with the torch objects."""

from __future__ import annotations

import copy

import numpy as np
import torch

import palaestra as gym
from palaestra.algos import DQN, PPO
from palaestra.algos.numpy_nn import FlatAdam, LayerViews


def _twin_params(seed: int = 0) -> tuple[list[torch.Tensor], list[torch.Tensor]]:
    gen = torch.Generator().manual_seed(seed)
    shapes = [(5, 3), (5,), (2, 5), (2,)]
    ours = [torch.nn.Parameter(torch.randn(s, generator=gen)) for s in shapes]
    theirs = [torch.nn.Parameter(p.detach().clone()) for p in ours]
    return ours, theirs


def _step_both(flat: FlatAdam, ref: torch.optim.Adam, theirs: list[torch.Tensor], rng) -> None:
    grads = [rng.standard_normal(p.shape).astype(np.float32) for p in theirs]
    for view, g in zip(flat.grad_views(), grads):
        view[...] = g
    flat.step()
    for p, g in zip(theirs, grads):
        p.grad = torch.from_numpy(g.copy())
    ref.step()


def test_flat_adam_matches_torch_adam_over_many_steps() -> None:
    ours, theirs = _twin_params()
    flat = FlatAdam(torch.optim.Adam(ours, lr=1e-2, eps=1e-5), ours)
    ref = torch.optim.Adam(theirs, lr=1e-2, eps=1e-5, foreach=False)
    rng = np.random.default_rng(0)
    for _ in range(50):
        _step_both(flat, ref, theirs, rng)
    for p, q in zip(ours, theirs):
        torch.testing.assert_close(p.detach(), q.detach(), atol=1e-6, rtol=1e-5)
        st, rt = flat.optimizer.state[p], ref.state[q]
        assert float(st["step"]) == float(rt["step"]) == 50.0
        torch.testing.assert_close(st["exp_avg"], rt["exp_avg"], atol=1e-7, rtol=1e-5)
        torch.testing.assert_close(st["exp_avg_sq"], rt["exp_avg_sq"], atol=1e-8, rtol=1e-5)


def test_flat_adam_rebinds_after_optimizer_load_state_dict() -> None:
    ours, theirs = _twin_params(1)
    opt = torch.optim.Adam(ours, lr=1e-2)
    flat = FlatAdam(opt, ours)
    ref = torch.optim.Adam(theirs, lr=1e-2, foreach=False)
    rng = np.random.default_rng(1)
    for _ in range(3):
        _step_both(flat, ref, theirs, rng)
    # loading replaces the state tensors; per-tensor step counts that differ take the slow path
    saved = copy.deepcopy(ref.state_dict())
    saved["state"][0]["step"] = torch.tensor(7.0)
    ref.load_state_dict(copy.deepcopy(saved))
    opt.load_state_dict(saved)
    for p, q in zip(ours, theirs):  # same starting point for the comparison
        with torch.no_grad():
            p.copy_(q)
    for _ in range(3):
        _step_both(flat, ref, theirs, rng)
    for p, q in zip(ours, theirs):
        torch.testing.assert_close(p.detach(), q.detach(), atol=1e-6, rtol=1e-5)
        assert float(opt.state[p]["step"]) == float(ref.state[q]["step"])
    assert float(opt.state[ours[0]]["step"]) == 10.0


def test_flat_adam_follows_moved_parameters() -> None:
    ours, theirs = _twin_params(2)
    flat = FlatAdam(torch.optim.Adam(ours, lr=1e-2), ours)
    ref = torch.optim.Adam(theirs, lr=1e-2, foreach=False)
    ours[1].data = ours[1].data.clone()  # rebinding, as .to() would
    rng = np.random.default_rng(2)
    _step_both(flat, ref, theirs, rng)
    for p, q in zip(ours, theirs):
        torch.testing.assert_close(p.detach(), q.detach(), atol=1e-6, rtol=1e-5)


def test_deepcopied_model_trains_its_own_parameters() -> None:
    model = DQN("MlpPolicy", gym.make("CartPole-v1"), learning_starts=50, batch_size=32, seed=0)
    model.learn(200)
    before = {k: v.clone() for k, v in model.policy.state_dict().items()}
    twin = copy.deepcopy(model)
    twin.train(5, 32)
    for key, value in model.policy.state_dict().items():
        assert torch.equal(value, before[key]), key
    changed = [
        k
        for k, v in twin.policy.state_dict().items()
        if "target" not in k and not torch.equal(v, before[k])
    ]
    assert changed


def test_acting_sees_trained_parameters() -> None:
    """The numpy acting views point into the trainer's flat buffer (built after it)."""
    model = PPO("MlpPolicy", "CartPole-v1", n_steps=64, batch_size=32, n_epochs=2, seed=0)
    obs = np.random.default_rng(0).standard_normal((16, 4)).astype(np.float32)
    pi_fn, vf_fn = model._numpy
    initial = pi_fn(obs).copy()
    model.learn(128)
    with torch.no_grad():
        x = torch.from_numpy(obs)
        logits = model.policy.action_head.net(model.policy.pi_net(x)).numpy()
        values = model.policy.value_head(model.policy.vf_net(x)).numpy()
    assert not np.allclose(initial, logits)  # training moved the policy
    np.testing.assert_allclose(pi_fn(obs), logits, atol=1e-6)
    np.testing.assert_allclose(vf_fn(obs), values, atol=1e-6)


def test_layer_views_follow_moved_and_updated_parameters() -> None:
    lin = torch.nn.Linear(3, 2)
    cache = LayerViews([(lin, "tanh")])
    ((w, b, act),) = cache()[0]
    assert act == "tanh" and np.shares_memory(w, lin.weight.detach().numpy())
    with torch.no_grad():
        lin.bias.add_(1.0)  # in place: the same views see it
    assert cache()[0][0][1] is b
    np.testing.assert_array_equal(b, lin.bias.detach().numpy())
    lin.weight.data = lin.weight.data.clone()  # moved: new views
    w2 = cache()[0][0][0]
    assert w2 is not w and np.shares_memory(w2, lin.weight.detach().numpy())


def test_grad_views_are_cached_and_follow_a_deepcopy() -> None:
    ours, _ = _twin_params(3)
    flat = FlatAdam(torch.optim.Adam(ours, lr=1e-2), ours)
    assert flat.grad_views() is flat.grad_views()
    twin = copy.deepcopy(flat)
    for view in twin.grad_views():
        assert np.shares_memory(view, twin.grad) and not np.shares_memory(view, flat.grad)
