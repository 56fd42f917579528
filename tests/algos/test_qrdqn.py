"""QR-DQN (``palaestra.algos.qrdqn``) against sb3-contrib's: constructor and policy signatures,
the quantile Huber loss and its VJP, the two learners, model files and the preset (the CLI:
``tests/cli/test_qrdqn.py``)."""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

import palaestra as gym
from palaestra import presets, spaces
from palaestra.algos import ModelFileError, evaluate_policy
from palaestra.algos.common.model_io import read_archive, write_archive
from palaestra.algos.learners import NumpyLearner, TorchLearner
from palaestra.algos.learners.xp import numpy_ops, torch_ops
from palaestra.algos.qrdqn import (
    QRDQN,
    CnnPolicy,
    MlpPolicy,
    MultiInputPolicy,
    QRDQNPolicy,
    QuantileNetwork,
)
from palaestra.algos.qrdqn.objective import (
    qrdqn_loss,
    qrdqn_loss_vjp,
    quantile_huber_loss,
    quantile_huber_loss_vjp,
    quantile_midpoints,
)
from palaestra.vec_env import make_vec_env

from .test_exact_resume import StopAt
from .toys import Toy

RNG = np.random.default_rng(0)
SMALL: dict[str, Any] = {"learning_starts": 50, "batch_size": 16, "buffer_size": 500, "seed": 0}


def _f32(*shape: int, scale: float = 1.0) -> np.ndarray:
    return (RNG.normal(size=shape) * scale).astype(np.float32)


def _described(fn: Any) -> list[tuple[str, Any, Any]]:
    """Each parameter's name, default and kind, in order; a class default by its name (ours
    are palaestra's classes of sb3's names)."""
    return [
        (p.name, p.default.__name__ if isinstance(p.default, type) else p.default, p.kind)
        for p in inspect.signature(fn).parameters.values()
    ]


def _contrib() -> Any:
    import sb3_contrib.qrdqn.policies

    return sb3_contrib


# -- the public API is sb3-contrib's ---------------------------------------------------------
@pytest.mark.parametrize(
    ("ours", "theirs"),
    [
        (QRDQN, "QRDQN"),
        (QRDQNPolicy, "qrdqn.policies.QRDQNPolicy"),
        (MlpPolicy, "qrdqn.policies.MlpPolicy"),
        (CnnPolicy, "qrdqn.policies.CnnPolicy"),
        (MultiInputPolicy, "qrdqn.policies.MultiInputPolicy"),
        (QuantileNetwork, "qrdqn.policies.QuantileNetwork"),
    ],
    ids=lambda v: v if isinstance(v, str) else v.__name__,
)
def test_constructor_signatures_equal_sb3_contrib(ours: Any, theirs: str) -> None:
    """Names, defaults and order of every parameter (``n_quantiles=200`` in the policy's)."""
    cls = _contrib()
    for part in theirs.split("."):
        cls = getattr(cls, part)
    assert _described(ours.__init__) == _described(cls.__init__)


def test_policy_aliases_and_defaults() -> None:
    assert QRDQN.policy_aliases == {
        "MlpPolicy": QRDQNPolicy,
        "CnnPolicy": CnnPolicy,
        "MultiInputPolicy": MultiInputPolicy,
    }
    model = QRDQN("MlpPolicy", "CartPole-v1", buffer_size=100, seed=0)
    assert model.n_quantiles == 200 and model.max_grad_norm is None
    assert model.quantile_net(torch.zeros(3, 4)).shape == (3, 200, 2)
    assert model.quantile_net_target is model.policy.q_net_target
    # sb3-contrib's Adam: eps 0.01 / batch_size unless an optimizer_class is given
    assert model.optimizer.param_groups[0]["eps"] == pytest.approx(0.01 / 32)
    assert model.policy_kwargs == {}  # the default is not written into the user's kwargs
    mine = QRDQN("MlpPolicy", "CartPole-v1", buffer_size=100, batch_size=64,
                 policy_kwargs={"optimizer_kwargs": {"weight_decay": 0.1}})  # fmt: skip
    assert mine.optimizer.param_groups[0]["eps"] == pytest.approx(0.01 / 64)
    assert mine.optimizer.param_groups[0]["weight_decay"] == 0.1
    plain = QRDQN("MlpPolicy", "CartPole-v1", buffer_size=100,
                  policy_kwargs={"optimizer_class": torch.optim.Adam})  # fmt: skip
    assert plain.optimizer.param_groups[0]["eps"] == 1e-8


def test_policy_acts_on_the_mean_of_the_quantiles() -> None:
    env = gym.make("CartPole-v1")
    actions = spaces.Discrete(2)
    policy = QRDQNPolicy(env.observation_space, actions, lambda _: 1e-3, n_quantiles=7)
    obs = torch.as_tensor(_f32(5, 4))
    quantiles = policy.quantile_net(obs)
    assert quantiles.shape == (5, 7, 2)
    assert torch.equal(policy(obs), quantiles.mean(dim=1).argmax(dim=1))
    assert policy.make_quantile_net() is not policy.quantile_net
    for name in ("quantile_net", "quantile_net_target"):
        net = getattr(policy, name)
        assert [m.out_features for m in net.quantile_net if isinstance(m, torch.nn.Linear)] == [
            64,
            64,
            14,
        ]
    cnn = CnnPolicy(Toy(obs="image").observation_space, actions, lambda _: 1e-3)
    assert cnn.features_extractor_class.__name__ == "NatureCNN" and cnn.n_quantiles == 200
    assert [type(m).__name__ for m in cnn.quantile_net.quantile_net] == ["Linear"]  # net_arch []


@pytest.mark.parametrize("value", [0, -3, 2.5, True, "10"])
def test_bad_n_quantiles_is_refused(value: Any) -> None:
    with pytest.raises(ValueError) as info:
        QRDQN("MlpPolicy", "CartPole-v1", buffer_size=100, policy_kwargs={"n_quantiles": value})
    assert str(info.value) == f"n_quantiles must be a positive int, got {value!r}"


def test_custom_quantile_net_is_used_and_trained_by_torch() -> None:
    class Wider(QRDQNPolicy):
        def make_quantile_net(self) -> QuantileNetwork:
            net = super().make_quantile_net()
            net.marker = True  # type: ignore[assignment]
            return net

    model = QRDQN(Wider, "CartPole-v1", **SMALL, policy_kwargs={"n_quantiles": 5})
    assert isinstance(model.learner, TorchLearner)
    assert model.quantile_net.marker and model.quantile_net_target.marker
    model.learn(100)
    assert model._n_updates > 0
    with pytest.raises(ValueError, match="a policy name or a QRDQNPolicy subclass"):
        QRDQN(torch.nn.Module, "CartPole-v1", buffer_size=100)  # type: ignore[arg-type, call-arg]


# -- the loss: sb3-contrib's value, and the numpy VJP equal to autograd ------------------------
@pytest.mark.parametrize("n_target", [6, 3])
def test_quantile_huber_loss_matches_sb3_contrib(n_target: int) -> None:
    from sb3_contrib.common.utils import quantile_huber_loss as reference

    current, target = _f32(9, 6, scale=2.0), _f32(9, n_target, scale=2.0)
    current[0, 0], current[0, 1], current[0, 2] = target[0, 0] - 1.0, target[0, 0] + 1.0, 0.0
    target[0, 1] = 0.0  # deltas of exactly 1, -1 and 0 (the Huber and weight kinks)
    tc = torch.tensor(current, requires_grad=True)
    expected = reference(tc, torch.as_tensor(target), sum_over_quantiles=True)
    expected.backward()
    ours, tape = quantile_huber_loss(numpy_ops, current, target, quantile_midpoints(6))
    assert ours == pytest.approx(expected.item(), rel=1e-6)
    t_ours, _ = quantile_huber_loss(
        torch_ops, torch.as_tensor(current), torch.as_tensor(target),
        torch.as_tensor(quantile_midpoints(6)),
    )  # fmt: skip
    assert float(t_ours) == pytest.approx(expected.item(), rel=1e-6)
    assert tc.grad is not None
    np.testing.assert_allclose(quantile_huber_loss_vjp(tape), tc.grad.numpy(), atol=1e-7)


def _qrdqn_case(n_quantiles: int, n_actions: int, batch: int) -> dict[str, np.ndarray]:
    return {
        "quantiles": _f32(batch, n_quantiles * n_actions, scale=2.0),
        "actions": RNG.integers(0, n_actions, size=batch),
        "rewards": _f32(batch),
        "terminated": (RNG.random(batch) < 0.3).astype(np.float32),
        "next_quantiles_target": _f32(batch, n_quantiles * n_actions, scale=2.0),
        "rows": np.arange(batch),
        "cum_prob": quantile_midpoints(n_quantiles),
    }


@pytest.mark.parametrize(("n_quantiles", "n_actions"), [(5, 3), (1, 2), (200, 2)])
def test_qrdqn_loss_and_vjp_against_autograd(n_quantiles: int, n_actions: int) -> None:
    """The whole loss on numpy and on torch (flat net outputs, as the numpy learner hands them
    over), its value as sb3-contrib's ``QRDQN.train`` computes it, and the VJP."""
    from sb3_contrib.common.utils import quantile_huber_loss as reference

    case, gamma, batch = _qrdqn_case(n_quantiles, n_actions, 8), 0.9, 8
    loss, metrics, tape = qrdqn_loss(numpy_ops, *case.values(), gamma)  # type: ignore[arg-type]
    tensors = {k: torch.as_tensor(v) for k, v in case.items()}
    tq = tensors["quantiles"] = tensors["quantiles"].clone().requires_grad_(True)
    t_loss, _, _ = qrdqn_loss(torch_ops, *tensors.values(), gamma)  # type: ignore[arg-type, call-arg]
    t_loss.backward()
    # sb3-contrib's train(), on the [B, N, n_actions] views of the same outputs
    nq = tensors["next_quantiles_target"].view(-1, n_quantiles, n_actions)
    greedy = nq.mean(dim=1, keepdim=True).argmax(dim=2, keepdim=True)
    nq = nq.gather(dim=2, index=greedy.expand(batch, n_quantiles, 1)).squeeze(dim=2)
    done, reward = tensors["terminated"][:, None], tensors["rewards"][:, None]
    target = reward + (1 - done) * gamma * nq
    index = tensors["actions"][:, None, None].expand(batch, n_quantiles, 1)
    current = tq.detach().view(-1, n_quantiles, n_actions).gather(2, index).squeeze(2)
    expected = float(reference(current, target, sum_over_quantiles=True))
    assert loss == metrics["loss"] == pytest.approx(expected, rel=1e-5)
    assert t_loss.item() == pytest.approx(expected, rel=1e-5)
    g = qrdqn_loss_vjp(tape)
    assert g.shape == case["quantiles"].shape and g.dtype == np.float32
    assert tq.grad is not None
    np.testing.assert_allclose(g, tq.grad.numpy(), rtol=1e-4, atol=1e-7)
    chosen = np.zeros((batch, n_quantiles, n_actions), bool)
    chosen[np.arange(batch), :, case["actions"]] = True
    assert not g.reshape(chosen.shape)[~chosen].any()  # other actions get no gradient


# -- the two learners train alike ---------------------------------------------------------------
@pytest.mark.parametrize("kwargs", [{}, {"max_grad_norm": 0.5, "gamma": 0.9}], ids=["sb3", "clip"])
def test_numpy_and_torch_learners_train_the_same(kwargs: dict[str, Any]) -> None:
    """A short run from the same seed on each learner: the same parameters, optimizer state
    and losses to float32 rounding (and therefore the same actions all along)."""
    models = []
    for backend in ("numpy", "torch"):
        policy_kwargs = {"backend": backend, "n_quantiles": 10, "net_arch": [32, 32]}
        model = QRDQN("MlpPolicy", "CartPole-v1", **SMALL, learning_rate=1e-3,
                      target_update_interval=40, policy_kwargs=policy_kwargs, **kwargs)  # fmt: skip
        models.append(model.learn(400))
    ours, theirs = models
    assert isinstance(ours.learner, NumpyLearner) and isinstance(theirs.learner, TorchLearner)
    assert ours._n_updates == theirs._n_updates > 80
    for key, value in ours.policy.state_dict().items():
        torch.testing.assert_close(value, theirs.policy.state_dict()[key], atol=2e-5, rtol=1e-4)
    exp_avg = [s["exp_avg"] for s in ours.optimizer.state_dict()["state"].values()]
    other = [s["exp_avg"] for s in theirs.optimizer.state_dict()["state"].values()]
    for a, b in zip(exp_avg, other, strict=True):
        torch.testing.assert_close(a, b, atol=1e-6, rtol=1e-3)
    assert ours.logger.name_to_value["train/loss"] == pytest.approx(
        theirs.logger.name_to_value["train/loss"], rel=1e-4
    )
    assert np.array_equal(ours.replay_buffer.actions, theirs.replay_buffer.actions)


@pytest.mark.parametrize("obs", ["image", "dict"])
def test_cnn_and_multi_input_policies_train(obs: str) -> None:
    policy = "CnnPolicy" if obs == "image" else "MultiInputPolicy"
    model = QRDQN(policy, Toy(obs=obs), learning_starts=8, batch_size=8, buffer_size=200,
                  seed=0, policy_kwargs={"n_quantiles": 4})  # fmt: skip
    before = {k: v.clone() for k, v in model.policy.state_dict().items()}
    model.learn(24)
    after = model.policy.state_dict()
    assert any(not torch.equal(before[k], after[k]) for k in before if k.startswith("q_net."))
    frame = Toy(obs=obs).reset(seed=0)[0]
    assert model.predict(frame, deterministic=True)[0].shape == ()


# -- model files -----------------------------------------------------------------------------------
def test_predict_save_load_round_trip(tmp_path: Path) -> None:
    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    model = QRDQN("MlpPolicy", venv, **SMALL, policy_kwargs={"n_quantiles": 12}).learn(300)
    model.save(tmp_path / "qrdqn.zip")
    loaded = QRDQN.load(tmp_path / "qrdqn.zip")
    obs = _f32(20, 4)
    assert np.array_equal(
        model.predict(obs, deterministic=True)[0], loaded.predict(obs, deterministic=True)[0]
    )
    with torch.no_grad():
        torch.testing.assert_close(
            model.quantile_net(torch.as_tensor(obs)), loaded.quantile_net(torch.as_tensor(obs))
        )
    assert loaded.n_quantiles == 12 and loaded.max_grad_norm is None
    assert loaded.num_timesteps == model.num_timesteps and loaded.exploration_rate == 0.01
    assert loaded.optimizer.param_groups[0]["eps"] == pytest.approx(0.01 / 16)
    assert type(loaded.policy) is QRDQNPolicy and isinstance(loaded.learner, NumpyLearner)
    single, _ = gym.make("CartPole-v1").reset(seed=0)
    action, state = loaded.predict(single, deterministic=True)
    assert action.shape == () and state is None


def test_a_run_stopped_and_loaded_ends_bit_identical(tmp_path: Path) -> None:
    """DQN's exact resume carries over: stopped mid-collection at step 150, saved with its
    replay buffer, loaded and continued, the run ends with the same bits as one never stopped."""

    def model() -> Any:
        venv = make_vec_env("CartPole-v1", n_envs=2, seed=1)
        return QRDQN("MlpPolicy", venv, **SMALL, target_update_interval=40, train_freq=8,
                     gradient_steps=2, policy_kwargs={"n_quantiles": 8})  # fmt: skip

    full = model().learn(400)
    cut = model().learn(400, callback=StopAt(150))
    assert cut.num_timesteps == 150
    cut.save(tmp_path / "m.zip")
    cut.save_replay_buffer(tmp_path / "rb.zip")
    resumed = QRDQN.load(tmp_path / "m.zip", env=cut.get_env())
    resumed.load_replay_buffer(tmp_path / "rb.zip")
    resumed.learn(400 - resumed.num_timesteps, reset_num_timesteps=False)
    assert resumed.num_timesteps == full.num_timesteps
    for key, value in full.policy.state_dict().items():
        assert torch.equal(value, resumed.policy.state_dict()[key]), key
    assert resumed.exploration_rate == full.exploration_rate


def test_model_file_n_quantiles_is_bounded(tmp_path: Path) -> None:
    QRDQN("MlpPolicy", "CartPole-v1", buffer_size=100, seed=0).save(tmp_path / "m.zip")
    meta, arrays = read_archive(tmp_path / "m.zip", "model")
    meta["policy_kwargs"] = {"n_quantiles": 10**9}
    write_archive(tmp_path / "bad.zip", "model", meta, arrays)
    with pytest.raises(ModelFileError) as info:
        QRDQN.load(tmp_path / "bad.zip")
    assert str(info.value) == (
        f"{tmp_path / 'bad.zip'}: policy_kwargs n_quantiles=1000000000 is refused: expected an "
        "integer from 1 to 65536"
    )


# -- the preset ----------------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_cartpole_preset_is_learned(seed: int) -> None:
    """The shipped preset (RL Zoo's QR-DQN CartPole settings, 50k steps: ~55 s a seed on one
    core) as ``palaestra train qrdqn CartPole-v1 --seed S`` builds it. Its measured block has
    500 on all 5 seeds (100 episodes each); 400 over 10 episodes leaves a margin."""
    preset = presets.get_preset("qrdqn", "CartPole-v1")
    venv = make_vec_env("CartPole-v1", n_envs=preset["n_envs"], seed=seed)
    model = QRDQN(preset["policy"], venv, seed=seed, **presets.resolve(preset["hyperparams"]))
    model.learn(preset["n_timesteps"])
    env = gym.make("CartPole-v1")
    env.reset(seed=10_000 + seed)
    mean, _ = evaluate_policy(model, env, n_eval_episodes=10)
    assert float(mean) >= 400  # type: ignore[arg-type]
