"""``RMSpropTFLike`` (``palaestra.algos.sb2_compat.rmsprop_tf_like``) against SB3's: the same
parameters and gradients give the same steps and state to 1e-6 for every option; the same
errors; A2C trains with it (on the torch learner, saying why) and saves and loads it."""

from __future__ import annotations

import pytest
import torch
from stable_baselines3.common.sb2_compat.rmsprop_tf_like import RMSpropTFLike as SB3RMSpropTFLike

from palaestra.algos import A2C
from palaestra.algos.sb2_compat import RMSpropTFLike
from palaestra.algos.sb2_compat.rmsprop_tf_like import RMSpropTFLike as AtModulePath

OPTIONS = [
    {},
    {"lr": 7e-4, "eps": 1e-5},
    {"momentum": 0.9},
    {"centered": True, "alpha": 0.9},
    {"weight_decay": 0.1, "momentum": 0.5, "centered": True},
]


@pytest.mark.parametrize("options", OPTIONS, ids=str)
def test_steps_equal_sb3s(options: dict[str, float]) -> None:
    generator = torch.Generator().manual_seed(0)
    start = [torch.randn(4, 3, generator=generator), torch.randn(3, generator=generator)]
    ours = [torch.nn.Parameter(t.clone()) for t in start]
    theirs = [torch.nn.Parameter(t.clone()) for t in start]
    opt, ref = RMSpropTFLike(ours, **options), SB3RMSpropTFLike(theirs, **options)
    for _ in range(6):
        grads = [torch.randn(t.shape, generator=generator) for t in start]
        for params, optimizer in ((ours, opt), (theirs, ref)):
            for p, g in zip(params, grads):
                p.grad = g.clone()
            optimizer.step()
    for p, q in zip(ours, theirs):
        torch.testing.assert_close(p, q, rtol=0, atol=1e-6)
    for p, q in zip(ours, theirs):
        a, b = opt.state[p], ref.state[q]
        assert a.keys() == b.keys() and a["step"] == b["step"] == 6
        for key in set(a) - {"step"}:
            torch.testing.assert_close(a[key], b[key], rtol=0, atol=1e-6)
    assert ours[0].ne(start[0]).all()  # it moved


def test_the_first_step_is_tf_sized() -> None:
    """The average starts at ones and eps is inside the root: a first step of
    ``lr * g / sqrt(alpha + (1 - alpha) g**2 + eps)``, not torch's ``lr``-sized one."""
    p = torch.nn.Parameter(torch.zeros(1))
    p.grad = torch.tensor([2.0])
    RMSpropTFLike([p], lr=0.1, alpha=0.99, eps=1e-8).step()
    expected = -0.1 * 2.0 / (0.99 + 0.01 * 4.0 + 1e-8) ** 0.5
    assert p.item() == pytest.approx(expected, rel=1e-6)


def test_closure_loss_is_returned() -> None:
    p = torch.nn.Parameter(torch.ones(2))

    def closure() -> float:
        loss = (p**2).sum()
        loss.backward()
        return float(loss.detach())

    assert RMSpropTFLike([p]).step(closure) == 2.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"lr": -1.0}, "Invalid learning rate: -1.0"),
        ({"eps": -1e-3}, "Invalid epsilon value: -0.001"),
        ({"momentum": -0.5}, "Invalid momentum value: -0.5"),
        ({"weight_decay": -2}, "Invalid weight_decay value: -2"),
        ({"alpha": -0.1}, "Invalid alpha value: -0.1"),
        ({"lr": float("nan")}, "Invalid learning rate: nan"),
    ],
)
def test_bad_options_raise_sb3s_errors(kwargs: dict[str, float], message: str) -> None:
    params = [torch.nn.Parameter(torch.zeros(1))]
    with pytest.raises(ValueError) as ours:
        RMSpropTFLike(params, **kwargs)
    with pytest.raises(ValueError) as theirs:
        SB3RMSpropTFLike(params, **kwargs)
    assert str(ours.value) == str(theirs.value) == message


def test_sparse_gradients_are_refused() -> None:
    p = torch.nn.Parameter(torch.zeros(3))
    p.grad = torch.zeros(3).to_sparse()
    with pytest.raises(RuntimeError, match="RMSpropTF does not support sparse gradients"):
        RMSpropTFLike([p]).step()


KWARGS = {"optimizer_class": RMSpropTFLike, "optimizer_kwargs": {"eps": 1e-5}}


def test_a2c_trains_with_it_on_the_torch_learner(capsys: pytest.CaptureFixture[str]) -> None:
    assert AtModulePath is RMSpropTFLike
    model = A2C("MlpPolicy", "CartPole-v1", policy_kwargs=KWARGS, verbose=1, seed=0)
    assert "numpy cannot: the optimizer is RMSpropTFLike" in capsys.readouterr().out
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(50)
    assert type(model.optimizer) is RMSpropTFLike
    assert model.optimizer.param_groups[0]["eps"] == 1e-5
    assert any(not torch.equal(a, b) for a, b in zip(before, model.policy.parameters()))
    with pytest.raises(ValueError, match="backend='numpy' cannot train this model: the optimizer"):
        A2C("MlpPolicy", "CartPole-v1", policy_kwargs={**KWARGS, "backend": "numpy"})


def test_a2c_saves_and_loads_it_and_resumes_exactly(tmp_path: object) -> None:
    env_id, path = "CartPole-v1", f"{tmp_path}/a2c"
    straight = A2C("MlpPolicy", env_id, policy_kwargs=KWARGS, seed=3).learn(100)
    first = A2C("MlpPolicy", env_id, policy_kwargs=KWARGS, seed=3).learn(50)
    first.save(path)
    resumed = A2C.load(path, env=first.get_env())
    assert type(resumed.optimizer) is RMSpropTFLike
    resumed.learn(50, reset_num_timesteps=False)
    for a, b in zip(straight.policy.parameters(), resumed.policy.parameters()):
        torch.testing.assert_close(a, b, rtol=0, atol=0)
