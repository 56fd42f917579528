"""Networks and action heads: SB3's sizes and inits, exact log-probs/entropies, image handling."""

import numpy as np
import pytest
import torch

from palaestra import spaces
from palaestra.algos.distributions import ActionHead
from palaestra.algos.dqn import QNetwork
from palaestra.algos.learners.xp import numpy_ops, torch_ops
from palaestra.algos.networks import CombinedExtractor, NatureCNN, preprocess_obs
from palaestra.algos.policies import ActorCritic, extractor_class

BOX4 = spaces.Box(-1, 1, (4,))


def _n_params(module: torch.nn.Module) -> int:
    return sum(p.numel() for p in module.parameters())


def test_parameter_counts_match_sb3() -> None:
    from gymnasium import spaces as g
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.common.torch_layers import FlattenExtractor
    from stable_baselines3.dqn.policies import QNetwork as SB3Q

    for ours, theirs in [
        (spaces.Discrete(3), g.Discrete(3)),
        (spaces.MultiDiscrete([3, 2]), g.MultiDiscrete([3, 2])),
        (spaces.MultiBinary(3), g.MultiBinary(3)),
        (spaces.Box(-1, 1, (2,)), g.Box(-1, 1, (2,))),
    ]:
        sb3 = ActorCriticPolicy(g.Box(-1, 1, (4,)), theirs, lambda _: 3e-4)
        assert _n_params(ActorCritic(BOX4, ours)) == _n_params(sb3), ours
    sb3_q = SB3Q(g.Box(-1, 1, (4,)), g.Discrete(3), FlattenExtractor(g.Box(-1, 1, (4,))), 4)
    assert _n_params(QNetwork(BOX4, spaces.Discrete(3))) == _n_params(sb3_q)


@pytest.mark.parametrize(
    "space",
    [
        spaces.Discrete(4),
        spaces.Discrete(3, start=-1),
        spaces.MultiDiscrete([3, 2, 4]),
        spaces.MultiBinary(3),
        spaces.Box(-1, 1, (2,)),
    ],
)
def test_action_heads_agree_with_torch_distributions(space: spaces.Space) -> None:
    """Samples lie in the space, and the log-probs/entropies written over ``xp`` equal
    ``torch.distributions``' on both namespaces."""
    torch.manual_seed(0)
    head = ActionHead(space, 5, log_std_init=-0.3)
    params = head.net(torch.randn(6, 5)).detach()
    log_std = head.log_std.detach() if hasattr(head, "log_std") else None
    np_log_std = None if log_std is None else log_std.numpy()
    actions, log_prob = head.sample(params.numpy(), np_log_std, np.random.default_rng(0), False)
    if not isinstance(space, spaces.Box):  # Gaussian samples are unbounded; the env clips
        assert all(space.contains(a) for a in actions.astype(space.dtype))
    idx = head.index(actions)
    lp_t, ent_t, _ = head.evaluate(torch_ops, params, log_std, torch.as_tensor(idx))
    lp_n, ent_n, _ = head.evaluate(numpy_ops, params.numpy(), np_log_std, idx)
    np.testing.assert_allclose(lp_n, log_prob, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(lp_t.numpy(), log_prob, rtol=1e-5, atol=1e-5)
    D = torch.distributions
    t_actions = torch.as_tensor(actions, dtype=torch.float32)
    if isinstance(space, spaces.Box):
        dist = D.Normal(params, log_std.exp())
        ref_lp, ref_ent = dist.log_prob(t_actions).sum(1), dist.entropy().sum(1)
    elif isinstance(space, spaces.MultiBinary):
        dist = D.Bernoulli(logits=params)
        ref_lp, ref_ent = dist.log_prob(t_actions).sum(1), dist.entropy().sum(1)
    else:
        sizes = [int(space.n)] if isinstance(space, spaces.Discrete) else space.nvec.tolist()
        ind = torch.as_tensor(idx).reshape(6, -1)
        parts = [D.Categorical(logits=chunk) for chunk in torch.split(params, sizes, 1)]
        ref_lp = sum(d.log_prob(ind[:, i]) for i, d in enumerate(parts))
        ref_ent = sum(d.entropy() for d in parts)
    torch.testing.assert_close(lp_t, ref_lp)
    torch.testing.assert_close(ent_t.expand(6), ref_ent)
    np.testing.assert_allclose(np.broadcast_to(ent_n, (6,)), ref_ent.numpy(), rtol=1e-5)
    mode, _ = head.sample(params.numpy(), np_log_std, np.random.default_rng(1), True)
    again, _ = head.sample(params.numpy(), np_log_std, np.random.default_rng(2), True)
    np.testing.assert_array_equal(mode, again)


def test_ortho_init_gains() -> None:
    torch.manual_seed(0)
    ac = ActorCritic(BOX4, spaces.Discrete(2))
    w = ac.action_head.net.weight
    # orthogonal rows scaled by 0.01
    torch.testing.assert_close(w @ w.T, 1e-4 * torch.eye(2), atol=1e-7, rtol=1e-4)
    assert float(ac.value_head.bias.detach()) == 0.0
    assert isinstance(ac.pi_net[1], torch.nn.Tanh)


def test_channel_last_images_are_permuted_and_scaled() -> None:
    hwc = spaces.Box(0, 255, (36, 40, 3), np.uint8)
    x = torch.randint(0, 256, (2, 36, 40, 3), dtype=torch.uint8)
    pre = preprocess_obs(x, hwc)
    assert pre.shape == (2, 3, 36, 40) and float(pre.max()) <= 1.0
    torch.testing.assert_close(pre[0, 1], x[0, :, :, 1].float() / 255)
    q = QNetwork(hwc, spaces.Discrete(4), NatureCNN)
    assert q(x).shape == (2, 4)
    assert len(q.mlp) == 0  # SB3: no hidden layers after NatureCNN


def test_multi_input_and_discrete_obs() -> None:
    space = spaces.Dict(
        {"img": spaces.Box(0, 255, (1, 36, 36), np.uint8), "pos": spaces.Discrete(3)}
    )
    ac = ActorCritic(space, spaces.Discrete(2), CombinedExtractor)
    obs = {
        "img": torch.zeros(5, 1, 36, 36, dtype=torch.uint8),
        "pos": torch.tensor([0, 1, 2, 0, 1]),
    }
    logits, values = ac.pi_and_vf(obs)
    assert logits.shape == (5, 2) and values.shape == (5, 1)
    assert ac.features_extractor.features_dim == 256 + 3
    one_hot = preprocess_obs(torch.tensor([2, 0]), spaces.Discrete(3))
    assert one_hot.tolist() == [[0, 0, 1], [1, 0, 0]]


def test_unknown_policy_and_bad_arch() -> None:
    with pytest.raises(ValueError, match="Policy 'MlpPolicyy' unknown"):
        extractor_class("MlpPolicyy")
    with pytest.raises(ValueError, match="net_arch"):
        ActorCritic(BOX4, spaces.Discrete(2), net_arch="big")
    with pytest.raises(TypeError, match="Tuple"):
        ActorCritic(BOX4, spaces.Tuple([spaces.Discrete(2)]))
    with pytest.raises(ValueError, match="image observation"):
        QNetwork(BOX4, spaces.Discrete(2), NatureCNN)


def test_mlp_modules_declines_what_numpy_cannot_read() -> None:
    assert QNetwork(BOX4, spaces.Discrete(2)).mlp_modules()[0] is not None
    modules, why = QNetwork(spaces.Discrete(5), spaces.Discrete(2)).mlp_modules()
    assert modules is None and "one-hot" in why
    img = spaces.Box(0, 255, (36, 36, 1), np.uint8)
    modules, why = QNetwork(img, spaces.Discrete(2), NatureCNN).mlp_modules()
    assert modules is None and "NatureCNN" in why
    modules, why = QNetwork(img, spaces.Discrete(2)).mlp_modules()
    assert modules is None and "scaled" in why


def test_numpy_categorical_draws_follow_the_softmax() -> None:
    from palaestra.algos.learners.heads import categorical_sample as sample_categorical

    logits = np.array([[0.0, 1.0, -1.0, 2.0]] * 200_000, dtype=np.float32)
    idx, log_prob = sample_categorical(logits, np.random.default_rng(0), False)
    expected = torch.log_softmax(torch.as_tensor(logits[0]), dim=0).numpy()
    freq = np.bincount(idx, minlength=4) / len(idx)
    np.testing.assert_allclose(freq, np.exp(expected), atol=0.005)  # ~5 standard errors
    np.testing.assert_allclose(log_prob, expected[idx], rtol=1e-6, atol=1e-6)
    mode, mode_lp = sample_categorical(logits[:3], np.random.default_rng(0), True)
    assert mode.tolist() == [3, 3, 3]
    np.testing.assert_allclose(mode_lp, expected[3], rtol=1e-6)


def test_numpy_categorical_draw_at_the_top_of_the_unit_interval_stays_in_range() -> None:
    from palaestra.algos.learners.heads import categorical_sample as sample_categorical

    class TopRng:
        def random(self, n: int) -> np.ndarray:
            return np.full(n, np.nextafter(1.0, 0.0))

    logits = np.random.default_rng(0).normal(scale=30, size=(10_000, 5)).astype(np.float32)
    idx, log_prob = sample_categorical(logits, TopRng(), False)  # type: ignore[arg-type]
    assert idx.max() <= 4 and np.isfinite(log_prob).all()
