"""gSDE in PPO, A2C and SAC side by side with SB3: not a flag accepted and ignored. The
policy's ``action_dist`` is a ``StateDependentNoiseDistribution`` (the class of
``palaestra.algos.distributions``) whose log-probabilities and entropies equal SB3's for the
same weights and exploration matrices, ``reset_noise`` draws new matrices, the matrices are
redrawn as SB3's rollouts redraw them, and both learners compute the same updates."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch

from palaestra.algos import A2C, PPO, SAC
from palaestra.algos.callbacks import BaseCallback
from palaestra.algos.distributions import StateDependentNoiseDistribution
from palaestra.algos.learners.xp import torch_ops
from palaestra.algos.sac.objective import SDEDraw

sb3 = pytest.importorskip("stable_baselines3")
sb3_dist = pytest.importorskip("stable_baselines3.common.distributions")

ON_POLICY_KWARGS = [
    {},
    {"full_std": False},
    {"use_expln": True},
    {"squash_output": True},
    {"squash_output": True, "full_std": False, "use_expln": True},
]
_TO_SB3 = {
    "pi_net.": "mlp_extractor.policy_net.",
    "vf_net.": "mlp_extractor.value_net.",
    "action_head.log_std": "log_std",
    "action_head.net.": "action_net.",
    "value_head.": "value_net.",
}


def _sb3_state(state: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    out = {}
    for key, value in state.items():
        for ours, theirs in _TO_SB3.items():
            if key.startswith(ours):
                key = theirs + key[len(ours) :]
                break
        out[key] = value
    return out


def _close(a: Any, b: Any, tol: float = 1e-6) -> None:
    a = a.detach().numpy() if isinstance(a, torch.Tensor) else np.asarray(a)
    b = b.detach().numpy() if isinstance(b, torch.Tensor) else np.asarray(b)
    assert a.shape == b.shape
    np.testing.assert_allclose(a, b, rtol=tol, atol=tol)


@pytest.mark.parametrize("algo", [PPO, A2C])
@pytest.mark.parametrize("kwargs", ON_POLICY_KWARGS, ids=lambda k: "-".join(k) or "default")
def test_on_policy_action_dist_equals_sb3(algo: Any, kwargs: dict[str, Any]) -> None:
    policy_kwargs = {"log_std_init": -0.7, **kwargs}
    ours = algo("MlpPolicy", "Pendulum-v1", use_sde=True, seed=0, policy_kwargs=policy_kwargs)
    theirs = getattr(sb3, algo.__name__)(
        "MlpPolicy", "Pendulum-v1", use_sde=True, seed=0, policy_kwargs=policy_kwargs
    )
    policy = ours.policy
    assert isinstance(policy.action_dist, StateDependentNoiseDistribution)
    assert type(policy.action_dist).__module__ == "palaestra.algos.common.distributions"
    with torch.no_grad():  # move the log-std off its initial value, both sides of expln's 0
        policy.action_head.log_std.add_(
            torch.linspace(-1.0, 1.0, policy.action_head.log_std.numel()).reshape(
                policy.action_head.log_std.shape
            )
        )
    theirs.policy.load_state_dict(_sb3_state(policy.state_dict()))
    obs = torch.as_tensor(np.random.default_rng(0).normal(size=(16, 3)).astype(np.float32))
    actions = torch.as_tensor(
        np.random.default_rng(1).uniform(-0.9, 0.9, (16, 1)).astype(np.float32)
    )
    values, log_prob, entropy = policy.evaluate_actions(obs, actions)
    t_values, t_log_prob, t_entropy = theirs.policy.evaluate_actions(obs, actions)
    _close(values, t_values.squeeze(1))
    _close(log_prob, t_log_prob)
    if kwargs.get("squash_output"):
        assert entropy is None and t_entropy is None
    else:
        _close(entropy, t_entropy)
    dist, t_dist = policy.get_distribution(obs), theirs.policy.get_distribution(obs)
    _close(dist.log_prob(actions), t_dist.log_prob(actions))
    # the same exploration matrices give the same sampled actions (one matrix per env)
    policy.reset_noise(16)
    t_dist.exploration_mat = policy.action_dist.exploration_mat
    t_dist.exploration_matrices = policy.action_dist.exploration_matrices
    _close(dist.sample(), t_dist.sample())


@pytest.mark.parametrize("algo", [PPO, A2C])
def test_reset_noise_changes_the_exploration_matrices(algo: Any) -> None:
    model = algo("MlpPolicy", "Pendulum-v1", use_sde=True, seed=0)
    dist = model.policy.action_dist
    before = dist.exploration_matrices.clone()
    model.policy.reset_noise(4)
    assert dist.exploration_matrices.shape == (4, 64, 1)
    assert not torch.equal(dist.exploration_matrices[:1], before)
    first = dist.exploration_mat.clone()
    model.policy.reset_noise()
    assert not torch.equal(dist.exploration_mat, first)
    # the model acts with the policy's matrices: a new matrix, another exploring action
    obs = np.zeros(3, np.float32) + 0.5
    a, _ = model.predict(obs)
    dist.exploration_mat = dist.exploration_mat * 0.0
    dist.exploration_matrices = dist.exploration_matrices * 0.0
    model.policy.action_head._noise_from_dist()
    b, _ = model.predict(obs)
    mode, _ = model.predict(obs, deterministic=True)
    assert not np.allclose(a, b)
    np.testing.assert_allclose(b, mode, rtol=1e-6)


class _Matrices(BaseCallback):
    """Records the exploration matrix each step acted with."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: list[np.ndarray] = []

    def _on_step(self) -> bool:
        noise = self.model._head._noise if hasattr(self.model, "_head") else None
        if noise is None:
            noise = (self.model._sde_dist.exploration_mat.numpy(),)
        self.seen.append(noise[0].copy())
        return True


def _changes(seen: list[np.ndarray]) -> list[int]:
    return [i for i in range(1, len(seen)) if not np.array_equal(seen[i], seen[i - 1])]


@pytest.mark.parametrize(("freq", "expected"), [(-1, [16]), (4, [4, 8, 12, 16, 20, 24, 28])])
def test_on_policy_noise_is_redrawn_as_sb3_does(freq: int, expected: list[int]) -> None:
    """SB3's collect_rollouts: new matrices when a rollout starts, and every sde_sample_freq
    steps of it (the callback sees the matrix of the step just taken)."""
    model = PPO(
        "MlpPolicy",
        "Pendulum-v1",
        use_sde=True,
        sde_sample_freq=freq,
        n_steps=16,
        batch_size=16,
        n_epochs=1,
        seed=0,
    )
    cb = _Matrices()
    model.learn(32, callback=cb)
    assert _changes(cb.seen) == expected


def test_sac_noise_is_redrawn_as_sb3_does() -> None:
    """SB3's off-policy collect_rollouts: new matrices as each collection of train_freq steps
    starts and every sde_sample_freq steps of it; gSDE acts from the start with
    use_sde_at_warmup."""
    model = SAC(
        "MlpPolicy",
        "Pendulum-v1",
        use_sde=True,
        sde_sample_freq=2,
        train_freq=5,
        learning_starts=10,
        batch_size=8,
        seed=0,
        policy_kwargs={"net_arch": [8]},
    )
    cb = _Matrices()
    model.learn(20, callback=cb)
    assert _changes(cb.seen) == [2, 4, 5, 7, 9, 10, 12, 14, 15, 17, 19]
    uniform = SAC("MlpPolicy", "Pendulum-v1", use_sde=True, learning_starts=50, seed=0)
    warm = SAC(
        "MlpPolicy",
        "Pendulum-v1",
        use_sde=True,
        learning_starts=50,
        use_sde_at_warmup=True,
        seed=0,
        policy_kwargs={"log_std_init": -20.0},
    )
    uniform.learn(10)
    warm.learn(10)
    # the warm-up acts with the (near-deterministic) policy: the stored actions are its mean's
    acts = warm.replay_buffer.actions[:10, 0]
    assert np.ptp(acts) < 0.2 < np.ptp(uniform.replay_buffer.actions[:10, 0])


@pytest.mark.parametrize("kwargs", [{}, {"use_expln": True, "clip_mean": 0.0}, {"clip_mean": 0.05}])
def test_sac_actor_log_prob_equals_sb3(kwargs: dict[str, Any]) -> None:
    """The losses' gSDE draw (SDEDraw on torch) equals SB3's Actor.action_log_prob for the
    same weights and the same exploration matrix, gradients included."""
    policy_kwargs = {"net_arch": [16, 16], "log_std_init": -0.5, **kwargs}
    ours = SAC("MlpPolicy", "Pendulum-v1", use_sde=True, seed=0, policy_kwargs=policy_kwargs)
    theirs = sb3.SAC("MlpPolicy", "Pendulum-v1", use_sde=True, seed=0, policy_kwargs=policy_kwargs)
    actor, t_actor = ours.policy.actor, theirs.policy.actor
    assert isinstance(actor.action_dist, StateDependentNoiseDistribution)
    t_actor.load_state_dict(actor.state_dict())
    obs = torch.as_tensor(np.random.default_rng(0).normal(size=(32, 3)).astype(np.float32))
    eps = torch.as_tensor(np.random.default_rng(1).standard_normal((16, 1)).astype(np.float32))
    t_std = t_actor.action_dist.get_std(t_actor.log_std)
    t_actor.action_dist.sample_weights(t_actor.log_std)
    t_actor.action_dist.exploration_mat = t_std * eps  # SB3's rsample, had it drawn eps
    t_actions, t_log_prob = t_actor.action_log_prob(obs)
    draw = SDEDraw(actor.use_expln, True, actor.clip_mean, 1)
    run = lambda name, x: {"latent": actor.latent, "mu": actor.mean_layer()}[name](x)  # noqa: E731
    actions, log_prob, _ = draw.rsample(
        torch_ops, run, {"log_std": actor.log_std}, obs, {"sde_noise": eps}
    )
    _close(actions, t_actions)
    _close(log_prob, t_log_prob, 1e-5)
    (log_prob.sum() + actions.sum()).backward()
    (t_log_prob.sum() + t_actions.sum()).backward()
    _close(actor.log_std.grad, t_actor.log_std.grad, 1e-4)
    _close(actor.latent_pi[0].weight.grad, t_actor.latent_pi[0].weight.grad, 1e-4)


def _trained(algo: Any, backend: str, **kwargs: Any) -> dict[str, torch.Tensor]:
    model = algo(
        "MlpPolicy",
        "Pendulum-v1",
        use_sde=True,
        seed=3,
        policy_kwargs={"backend": backend, **kwargs.pop("policy_kwargs", {})},
        **kwargs,
    )
    model.learn(kwargs.get("n_steps", 128) * 2 if algo is not SAC else 120)
    return model.policy.state_dict()


@pytest.mark.parametrize(
    ("algo", "kwargs"),
    [
        (PPO, {"n_steps": 64, "batch_size": 32, "n_epochs": 2}),
        (
            PPO,
            {
                "n_steps": 64,
                "batch_size": 32,
                "n_epochs": 2,
                "sde_sample_freq": 4,
                "policy_kwargs": {"squash_output": True, "use_expln": True, "full_std": False},
            },
        ),
        (A2C, {"n_steps": 16, "policy_kwargs": {"use_expln": True}}),
        (
            SAC,
            {
                "learning_starts": 40,
                "batch_size": 16,
                "sde_sample_freq": 3,
                "policy_kwargs": {"net_arch": [16]},
            },
        ),
        (
            SAC,
            {
                "learning_starts": 40,
                "batch_size": 16,
                "policy_kwargs": {
                    "net_arch": [16],
                    "use_expln": True,
                    "log_std_init": 0.5,
                    "clip_mean": 0.3,
                },
            },
        ),
    ],
    ids=["ppo", "ppo-squash-expln", "a2c-expln", "sac", "sac-expln-clip"],
)
def test_numpy_and_torch_learners_train_alike(algo: Any, kwargs: dict[str, Any]) -> None:
    """The numpy VJPs give the updates torch autograd gives (same seed, same draws)."""
    a = _trained(
        algo, "numpy", **{**kwargs, "policy_kwargs": dict(kwargs.get("policy_kwargs", {}))}
    )
    b = _trained(
        algo, "torch", **{**kwargs, "policy_kwargs": dict(kwargs.get("policy_kwargs", {}))}
    )
    for key, value in a.items():
        np.testing.assert_allclose(value.numpy(), b[key].numpy(), rtol=2e-3, atol=2e-4, err_msg=key)


def test_refusals() -> None:
    with pytest.raises(ValueError, match=r"gSDE\) can only be used with continuous actions"):
        PPO("MlpPolicy", "CartPole-v1", use_sde=True)
    with pytest.raises(ValueError, match="squash_output=True is only available when using gSDE"):
        PPO("MlpPolicy", "Pendulum-v1", policy_kwargs={"squash_output": True})
    with pytest.raises(ValueError, match="reset_noise\\(\\) is only available when using gSDE"):
        PPO("MlpPolicy", "Pendulum-v1").policy.reset_noise()
    with pytest.raises(ValueError, match="reset_noise\\(\\) is only available when using gSDE"):
        SAC("MlpPolicy", "Pendulum-v1").policy.reset_noise()
    with pytest.raises(ValueError, match="policy_kwargs use_sde=True contradicts use_sde=False"):
        PPO("MlpPolicy", "Pendulum-v1", policy_kwargs={"use_sde": True})
    with pytest.raises(TypeError, match="sde_sample_freq must be an int"):
        PPO("MlpPolicy", "Pendulum-v1", use_sde=True, sde_sample_freq="4")


@pytest.mark.parametrize("algo", [PPO, SAC])
def test_save_and_load_keep_gsde(algo: Any, tmp_path: Any) -> None:
    extra = (
        {"learning_starts": 10, "policy_kwargs": {"net_arch": [8]}}
        if algo is SAC
        else {"n_steps": 32, "batch_size": 32}
    )
    model = algo("MlpPolicy", "Pendulum-v1", use_sde=True, sde_sample_freq=5, seed=0, **extra)
    model.learn(40)
    model.save(tmp_path / "m.zip")
    loaded = algo.load(tmp_path / "m.zip")
    assert loaded.use_sde is True and loaded.sde_sample_freq == 5
    obs = np.full((1, 3), 0.3, np.float32)
    np.testing.assert_allclose(
        loaded.predict(obs, deterministic=True)[0], model.predict(obs, deterministic=True)[0]
    )
    dist = loaded.policy.actor.action_dist if algo is SAC else loaded.policy.action_dist
    assert isinstance(dist, StateDependentNoiseDistribution)
