"""``palaestra.algos.distributions`` side by side with SB3's: same weights, parameters and
noise give log-probabilities and entropies equal to 1e-6, samples equal under the same torch
seed, same shapes and dtypes, and the same refusals."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch

from palaestra import spaces
from palaestra.algos import distributions as ours

sb3 = pytest.importorskip("stable_baselines3.common.distributions")
gym_spaces = pytest.importorskip("gymnasium.spaces")

B, L, D = 7, 5, 3


def _t(*shape: int, seed: int = 0, scale: float = 1.0) -> torch.Tensor:
    gen = torch.Generator().manual_seed(seed)
    return torch.randn(*shape, generator=gen) * scale


def _same(a: torch.Tensor | None, b: torch.Tensor | None) -> None:
    assert (a is None) == (b is None)
    if a is None or b is None:
        return
    assert a.shape == b.shape and a.dtype == b.dtype
    np.testing.assert_allclose(a.detach().numpy(), b.detach().numpy(), rtol=1e-6, atol=1e-6)


def test_public_names() -> None:
    for name in (
        "Distribution",
        "DiagGaussianDistribution",
        "SquashedDiagGaussianDistribution",
        "CategoricalDistribution",
        "MultiCategoricalDistribution",
        "BernoulliDistribution",
        "StateDependentNoiseDistribution",
        "TanhBijector",
        "make_proba_distribution",
        "kl_divergence",
        "sum_independent_dims",
    ):
        assert hasattr(ours, name), name
    from palaestra.algos.common import distributions

    assert ours is distributions


def _pair(name: str, *args: Any, **kwargs: Any) -> tuple[Any, Any]:
    return getattr(ours, name)(*args, **kwargs), getattr(sb3, name)(*args, **kwargs)


@pytest.mark.parametrize("squashed", [False, True])
def test_diag_gaussian(squashed: bool) -> None:
    name = "SquashedDiagGaussianDistribution" if squashed else "DiagGaussianDistribution"
    mine, theirs = _pair(name, D)
    torch.manual_seed(3)
    net_a, log_std_a = mine.proba_distribution_net(L, log_std_init=-0.4)
    torch.manual_seed(3)
    net_b, log_std_b = theirs.proba_distribution_net(L, log_std_init=-0.4)
    _same(net_a.weight, net_b.weight)
    _same(log_std_a, log_std_b)
    mean = _t(B, D)
    mine.proba_distribution(mean, log_std_a)
    theirs.proba_distribution(mean, log_std_b)
    actions = torch.tanh(_t(B, D, seed=1)) if squashed else _t(B, D, seed=1)
    _same(mine.log_prob(actions), theirs.log_prob(actions))
    _same(mine.entropy(), theirs.entropy())
    torch.manual_seed(5)
    a = mine.sample()
    torch.manual_seed(5)
    b = theirs.sample()
    _same(a, b)
    _same(mine.mode(), theirs.mode())
    torch.manual_seed(6)
    a, lp_a = mine.log_prob_from_params(mean, log_std_a)
    torch.manual_seed(6)
    b, lp_b = theirs.log_prob_from_params(mean, log_std_b)
    _same(a, b)
    _same(lp_a, lp_b)


def test_diag_gaussian_log_std_per_row() -> None:
    """SAC's actor hands SB3's distribution a log-std per row."""
    mine, theirs = _pair("DiagGaussianDistribution", D)
    mean, log_std = _t(B, D), _t(B, D, seed=2, scale=0.3)
    mine.proba_distribution(mean, log_std)
    theirs.proba_distribution(mean, log_std)
    actions = _t(B, D, seed=4)
    _same(mine.log_prob(actions), theirs.log_prob(actions))
    _same(mine.entropy(), theirs.entropy())


@pytest.mark.parametrize(
    ("name", "arg", "space"),
    [
        ("CategoricalDistribution", 4, gym_spaces.Discrete(4)),
        ("MultiCategoricalDistribution", [2, 3, 4], gym_spaces.MultiDiscrete([2, 3, 4])),
        ("BernoulliDistribution", 5, gym_spaces.MultiBinary(5)),
    ],
)
def test_discrete_distributions(name: str, arg: Any, space: Any) -> None:
    mine, theirs = _pair(name, arg)
    torch.manual_seed(0)
    net_a = mine.proba_distribution_net(L)
    torch.manual_seed(0)
    net_b = theirs.proba_distribution_net(L)
    _same(net_a.weight, net_b.weight)
    logits = net_a(_t(B, L))
    mine.proba_distribution(logits)
    theirs.proba_distribution(logits)
    actions = torch.as_tensor(np.stack([space.sample() for _ in range(B)]))
    if name == "BernoulliDistribution":
        actions = actions.float()
    _same(mine.log_prob(actions), theirs.log_prob(actions))
    _same(mine.entropy(), theirs.entropy())
    _same(mine.mode(), theirs.mode())
    torch.manual_seed(9)
    a, lp_a = mine.log_prob_from_params(logits)
    torch.manual_seed(9)
    b, lp_b = theirs.log_prob_from_params(logits)
    _same(a, b)
    _same(lp_a, lp_b)
    _same(ours.kl_divergence(mine, mine), sb3.kl_divergence(theirs, theirs))


def _sde_pair(**kwargs: Any) -> tuple[Any, Any, torch.Tensor, torch.Tensor]:
    mine, theirs = _pair("StateDependentNoiseDistribution", D, **kwargs)
    torch.manual_seed(1)
    net_a, log_std_a = mine.proba_distribution_net(L, log_std_init=-0.5)
    torch.manual_seed(1)
    net_b, log_std_b = theirs.proba_distribution_net(L, log_std_init=-0.5)
    _same(net_a.weight, net_b.weight)
    _same(log_std_a, log_std_b)
    _same(mine.exploration_mat, theirs.exploration_mat)
    _same(mine.exploration_matrices, theirs.exploration_matrices)
    return mine, theirs, log_std_a, log_std_b


SDE_CASES = [
    {},
    {"full_std": False},
    {"use_expln": True},
    {"squash_output": True},
    {"squash_output": True, "learn_features": True, "use_expln": True},
]


@pytest.mark.parametrize("kwargs", SDE_CASES, ids=lambda k: "-".join(k) or "default")
def test_state_dependent_noise(kwargs: dict[str, Any]) -> None:
    mine, theirs, log_std_a, log_std_b = _sde_pair(**kwargs)
    with torch.no_grad():  # both sides of expln's threshold
        log_std_a += _t(*log_std_a.shape, seed=8, scale=0.7)
        log_std_b.copy_(log_std_a)
    _same(mine.get_std(log_std_a), theirs.get_std(log_std_b))
    torch.manual_seed(2)
    mine.sample_weights(log_std_a, batch_size=B)
    torch.manual_seed(2)
    theirs.sample_weights(log_std_b, batch_size=B)
    _same(mine.exploration_matrices, theirs.exploration_matrices)
    mean, latent = _t(B, D, seed=3), _t(B, L, seed=4)
    mine.proba_distribution(mean, log_std_a, latent)
    theirs.proba_distribution(mean, log_std_b, latent)
    if kwargs.get("squash_output"):
        actions = torch.tanh(_t(B, D, seed=5))
    else:
        actions = _t(B, D, seed=5)
    _same(mine.log_prob(actions), theirs.log_prob(actions))
    _same(mine.entropy(), theirs.entropy())
    _same(mine.sample(), theirs.sample())  # one matrix per row: B matrices for B rows
    _same(mine.mode(), theirs.mode())
    _same(mine.get_noise(latent[:3]), theirs.get_noise(latent[:3]))  # the single matrix
    a, lp_a = mine.log_prob_from_params(mean, log_std_a, latent)
    b, lp_b = theirs.log_prob_from_params(mean, log_std_b, latent)
    _same(a, b)
    _same(lp_a, lp_b)
    # Gradients reach the log-std (and the features only with learn_features).
    latent_a = latent.clone().requires_grad_(True)
    latent_b = latent.clone().requires_grad_(True)
    mine.proba_distribution(mean, log_std_a, latent_a).log_prob(actions).sum().backward()
    theirs.proba_distribution(mean, log_std_b, latent_b).log_prob(actions).sum().backward()
    _same(log_std_a.grad, log_std_b.grad)
    _same(latent_a.grad, latent_b.grad)


def test_sample_weights_from_a_numpy_generator_changes_the_matrices() -> None:
    mine, _, log_std, _ = _sde_pair()
    before = mine.exploration_matrices.clone()
    mine.sample_weights(log_std, batch_size=2, rng=np.random.default_rng(0))
    assert mine.exploration_matrices.shape == (2, L, D)
    assert not torch.equal(mine.exploration_matrices[:1], before)
    again = np.random.default_rng(0).standard_normal((3, L, D), np.float32)
    np.testing.assert_allclose(
        mine.exploration_matrices.detach().numpy(),
        again[1:] * np.exp(log_std.detach().numpy()),
        rtol=1e-6,
    )


def test_tanh_bijector() -> None:
    x = torch.tensor([[-1.0, -0.3, 0.0, 0.7, 1.0]])
    for fn in ("forward", "atanh", "inverse"):
        _same(getattr(ours.TanhBijector, fn)(x * 0.999), getattr(sb3.TanhBijector, fn)(x * 0.999))
    _same(ours.TanhBijector.inverse(x), sb3.TanhBijector.inverse(x))
    _same(ours.TanhBijector().log_prob_correction(x), sb3.TanhBijector().log_prob_correction(x))


@pytest.mark.parametrize(
    ("space", "gspace", "use_sde"),
    [
        (spaces.Box(-1, 1, (3,)), gym_spaces.Box(-1, 1, (3,)), False),
        (spaces.Box(-1, 1, (3,)), gym_spaces.Box(-1, 1, (3,)), True),
        (spaces.Discrete(3), gym_spaces.Discrete(3), False),
        (spaces.MultiDiscrete([2, 3]), gym_spaces.MultiDiscrete([2, 3]), False),
        (spaces.MultiBinary(4), gym_spaces.MultiBinary(4), False),
    ],
)
def test_make_proba_distribution(space: Any, gspace: Any, use_sde: bool) -> None:
    mine = ours.make_proba_distribution(space, use_sde=use_sde)
    theirs = sb3.make_proba_distribution(gspace, use_sde=use_sde)
    assert type(mine).__name__ == type(theirs).__name__
    assert isinstance(mine, ours.Distribution)


def test_make_proba_distribution_refusals() -> None:
    with pytest.raises(NotImplementedError, match="Must be of type Gym Spaces"):
        ours.make_proba_distribution(spaces.Tuple([spaces.Discrete(2)]))
    with pytest.raises(ValueError, match=r"Multi-dimensional MultiBinary\(\(2, 2\)\)"):
        ours.make_proba_distribution(spaces.MultiBinary([2, 2]))


def test_kl_divergence_refuses_mixed_classes() -> None:
    a = ours.CategoricalDistribution(3).proba_distribution(_t(2, 3))
    b = ours.BernoulliDistribution(3).proba_distribution(_t(2, 3))
    with pytest.raises(TypeError, match="should be the same type"):
        ours.kl_divergence(a, b)
