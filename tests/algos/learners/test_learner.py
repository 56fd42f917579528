"""The two learners: the numpy learner's updates equal the torch learner's (float32 rounding)
on whole models, the choice of learner is visible and forcible, and the torch objects users
read are kept in step with the numpy-owned parameters at the documented points."""

from __future__ import annotations

import copy
import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

import palaestra as gym
from palaestra.algos import DQN, PPO
from palaestra.algos.learners import NumpyLearner, TorchLearner
from palaestra.algos.learners.adam import FlatAdam

from ..toys import Toy

DATA = Path(__file__).parent.parent / "data"


def _torch_twin(model: Any) -> Any:
    """A deep copy of ``model`` whose learner is the torch learner over the same objects."""
    twin = copy.deepcopy(model)
    twin.learner.to_torch()
    old = twin.learner
    twin.learner = TorchLearner(old.nets, old.groups, torch.device("cpu"), "test twin")
    twin._rng.bit_generator.state = model._rng.bit_generator.state
    return twin


def _assert_same_state(model: Any, twin: Any, atol: float = 1e-6) -> None:
    ours, theirs = model.policy.state_dict(), twin.policy.state_dict()
    for key, value in ours.items():
        torch.testing.assert_close(value, theirs[key], atol=atol, rtol=1e-5, msg=key)
    ours_opt, theirs_opt = model.optimizer.state_dict(), twin.optimizer.state_dict()
    for index, state in ours_opt["state"].items():
        other = theirs_opt["state"][index]
        assert float(state["step"]) == float(other["step"])
        torch.testing.assert_close(state["exp_avg"], other["exp_avg"], atol=1e-7, rtol=1e-4)
        torch.testing.assert_close(state["exp_avg_sq"], other["exp_avg_sq"], atol=1e-8, rtol=1e-4)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"activation_fn": torch.nn.ReLU},
        {"activation_fn": torch.nn.Tanh},
        {"activation_fn": torch.nn.ELU},
        {"optimizer_kwargs": {"weight_decay": 1e-3}},
    ],
    ids=["relu", "tanh", "elu", "weight_decay"],
)
def test_dqn_numpy_update_matches_torch(kwargs: dict[str, Any]) -> None:
    model = DQN(
        "MlpPolicy",
        gym.make("CartPole-v1"),
        learning_starts=50,
        batch_size=64,
        seed=0,
        max_grad_norm=0.5,
        policy_kwargs=kwargs,
    )
    assert isinstance(model.learner, NumpyLearner)
    model.learn(400)
    twin = _torch_twin(model)
    model.train(5, 64)
    twin.train(5, 64)
    _assert_same_state(model, twin)
    assert model.logger.name_to_value["train/loss"] == pytest.approx(
        twin.logger.name_to_value["train/loss"], rel=1e-4
    )


@pytest.mark.parametrize(
    ("env", "kwargs"),
    [
        ("CartPole-v1", {"ent_coef": 0.01}),
        ("CartPole-v1", {"clip_range_vf": 0.1, "normalize_advantage": False}),
        ("Pendulum-v1", {"ent_coef": 0.01, "clip_range_vf": 0.2}),
        (Toy(), {"policy_kwargs": {"activation_fn": torch.nn.ReLU}}),
        (Toy(action="multidiscrete"), {"ent_coef": 0.01}),
        (Toy(action="multibinary"), {"ent_coef": 0.01}),
    ],
    ids=["cartpole", "vf_clip", "pendulum", "relu", "multidiscrete", "multibinary"],
)
def test_ppo_numpy_update_matches_torch(env: object, kwargs: dict[str, Any]) -> None:
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=16, n_epochs=3, seed=0, **kwargs)
    assert isinstance(model.learner, NumpyLearner)
    model.learn(128)
    twin = _torch_twin(model)
    model.train()
    twin.train()
    _assert_same_state(model, twin)
    for key in ("train/approx_kl", "train/clip_fraction", "train/value_loss", "train/entropy_loss"):
        ours, theirs = model.logger.name_to_value[key], twin.logger.name_to_value[key]
        assert ours == pytest.approx(theirs, rel=1e-4, abs=1e-6), key


def test_learner_choice_is_visible_and_forcible(capsys: pytest.CaptureFixture[str]) -> None:
    assert isinstance(PPO("MlpPolicy", "CartPole-v1").learner, NumpyLearner)
    assert isinstance(DQN("MlpPolicy", Toy(obs="image")).learner, TorchLearner)  # /255 in torch
    assert isinstance(PPO("CnnPolicy", Toy(obs="image")).learner, TorchLearner)
    sgd = {"optimizer_class": torch.optim.SGD}
    assert isinstance(PPO("MlpPolicy", "CartPole-v1", policy_kwargs=sgd).learner, TorchLearner)
    forced = PPO("MlpPolicy", "CartPole-v1", policy_kwargs={"backend": "torch"})
    assert isinstance(forced.learner, TorchLearner)
    PPO("MlpPolicy", "CartPole-v1", verbose=1)
    PPO("MlpPolicy", "CartPole-v1", verbose=1, policy_kwargs=sgd)
    out = capsys.readouterr().out
    assert "Training with the numpy learner (small MLPs with Adam on the CPU)" in out
    assert (
        "Training with the torch learner (numpy cannot: the optimizer is SGD, not Adam or RMSprop)"
        in out
    )


def test_numpy_learner_refuses_what_it_cannot_run() -> None:
    with pytest.raises(
        ValueError, match="backend='numpy' cannot train this model: the optimizer is SGD"
    ):
        DQN(
            "MlpPolicy",
            "CartPole-v1",
            policy_kwargs={"backend": "numpy", "optimizer_class": torch.optim.SGD},
        )
    with pytest.raises(ValueError, match="features extractor is NatureCNN"):
        PPO("CnnPolicy", Toy(obs="image"), policy_kwargs={"backend": "numpy"})
    with pytest.raises(ValueError, match="GELU is not a Linear layer or a known activation"):
        PPO(
            "MlpPolicy",
            "CartPole-v1",
            policy_kwargs={"backend": "numpy", "activation_fn": torch.nn.GELU},
        )
    with pytest.raises(
        ValueError, match=r"backend must be one of \('auto', 'numpy', 'torch'\), got 'jax'"
    ):
        PPO("MlpPolicy", "CartPole-v1", policy_kwargs={"backend": "jax"})
    with pytest.raises(ValueError, match="amsgrad"):
        DQN(
            "MlpPolicy",
            "CartPole-v1",
            policy_kwargs={"backend": "numpy", "optimizer_kwargs": {"amsgrad": True}},
        )


def test_backend_is_saved_and_loaded(tmp_path: Path) -> None:
    model = PPO("MlpPolicy", "CartPole-v1", n_steps=64, policy_kwargs={"backend": "torch"})
    model.save(tmp_path / "m.zip")
    assert isinstance(PPO.load(tmp_path / "m.zip").learner, TorchLearner)


def test_policy_read_through_the_model_is_current_and_writable() -> None:
    model = PPO("MlpPolicy", "CartPole-v1", n_steps=64, batch_size=32, n_epochs=2, seed=0)
    held = model.policy  # taken before learning
    before = held.value_head.bias.detach().clone()
    model.learn(128)
    assert not torch.equal(held.value_head.bias.detach(), before)  # learn's end synchronises
    obs = np.zeros((1, 4), np.float32)
    values = model.learner.forward("vf", obs)[:, 0]
    with torch.no_grad():
        model.policy.value_head.bias.add_(1.0)  # changed through the model: the learner sees it
    np.testing.assert_allclose(model.learner.forward("vf", obs)[:, 0], values + 1, rtol=1e-6)


def test_set_parameters_and_deepcopy_with_the_numpy_learner() -> None:
    a = DQN("MlpPolicy", "CartPole-v1", learning_starts=10, seed=0)
    b = DQN("MlpPolicy", "CartPole-v1", learning_starts=10, seed=1)
    a.learn(200)
    b.set_parameters(a.get_parameters())
    obs = np.random.default_rng(0).normal(size=(8, 4)).astype(np.float32)
    np.testing.assert_array_equal(a.learner.forward("q", obs), b.learner.forward("q", obs))
    c = copy.deepcopy(a)
    c.learn(200, reset_num_timesteps=False)
    assert not np.array_equal(a.learner.forward("q", obs), c.learner.forward("q", obs))
    # the copy trains its own buffers: a is where it was
    np.testing.assert_array_equal(a.learner.forward("q", obs), b.learner.forward("q", obs))


@pytest.mark.parametrize("algo", ["ppo", "dqn"])
def test_models_saved_before_the_learners_load_and_predict_the_same(algo: str) -> None:
    expected = json.loads((DATA / "pre_learners_predictions.json").read_text())[algo]
    cls = PPO if algo == "ppo" else DQN
    model = cls.load(DATA / f"pre_learners_{algo}_cartpole.zip")
    obs = np.asarray(expected["obs"], np.float32)
    assert model.predict(obs, deterministic=True)[0].tolist() == expected["actions"]
    if algo == "ppo":
        np.testing.assert_allclose(
            model.learner.forward("vf", obs)[:, 0], expected["values"], rtol=1e-6, atol=1e-6
        )
    else:
        np.testing.assert_allclose(
            model.learner.forward("q", obs), expected["q"], rtol=1e-6, atol=1e-6
        )


def test_flat_adam_matches_torch_adam_and_hands_its_state_over() -> None:
    gen = torch.Generator().manual_seed(0)
    shapes = [(5, 3), (5,), (2, 5), (2,)]
    theirs = [torch.nn.Parameter(torch.randn(s, generator=gen)) for s in shapes]
    ours = [torch.nn.Parameter(p.detach().clone()) for p in theirs]
    ref = torch.optim.Adam(theirs, lr=1e-2, eps=1e-5, weight_decay=1e-3, foreach=False)
    opt = torch.optim.Adam(ours, lr=1e-2, eps=1e-5, weight_decay=1e-3)
    bounds = np.cumsum([0] + [p.numel() for p in ours]).tolist()
    slices = [slice(a, b) for a, b in itertools.pairwise(bounds)]
    adam = FlatAdam(bounds[-1], len(ours), slices)
    adam.from_torch(opt, ours)
    flat = np.concatenate([p.detach().numpy().ravel() for p in ours])
    rng = np.random.default_rng(0)
    for _ in range(50):
        grads = [rng.standard_normal(p.shape).astype(np.float32) for p in theirs]
        adam.grad[:] = np.concatenate([g.ravel() for g in grads])
        adam.step(flat)
        for p, g in zip(theirs, grads):
            p.grad = torch.from_numpy(g.copy())
        ref.step()
    np.testing.assert_allclose(
        flat, np.concatenate([p.detach().numpy().ravel() for p in theirs]), atol=1e-6, rtol=1e-5
    )
    adam.to_torch(opt, ours)
    for p, q in zip(ours, theirs):
        st, rt = opt.state[p], ref.state[q]
        assert float(st["step"]) == float(rt["step"]) == 50.0
        torch.testing.assert_close(st["exp_avg"], rt["exp_avg"], atol=1e-7, rtol=1e-5)
        torch.testing.assert_close(st["exp_avg_sq"], rt["exp_avg_sq"], atol=1e-8, rtol=1e-5)
    again = FlatAdam(bounds[-1], len(ours), slices)
    again.from_torch(opt, ours)  # a state read back is the state handed over
    np.testing.assert_array_equal(again.m, adam.m)
    np.testing.assert_array_equal(again.v, adam.v)
    np.testing.assert_array_equal(again.steps, adam.steps)


@pytest.mark.parametrize("tau", [1.0, 0.5])
def test_target_net_follows_on_both_learners(tau: float) -> None:
    """The target update moves every parameter of the target net, CNNs included."""
    for env, policy in [(Toy(obs="image"), "CnnPolicy"), ("CartPole-v1", "MlpPolicy")]:
        model = DQN(
            policy,
            env,
            learning_starts=10,
            target_update_interval=10**6,
            tau=tau,
            buffer_size=500,
            batch_size=8,
            learning_rate=1e-2,
            seed=0,
        )
        model.learn(40)  # the online net moves away from the target
        before = {k: v.clone() for k, v in model.q_net_target.state_dict().items()}
        model.learner.polyak("q_target", tau)  # what learn does every target_update_interval
        online, target = model.q_net.state_dict(), model.q_net_target.state_dict()
        assert any(not torch.equal(online[k], before[k]) for k in online)
        for key, value in target.items():
            expected = tau * online[key] + (1 - tau) * before[key]
            torch.testing.assert_close(value, expected, rtol=1e-6, atol=1e-6, msg=key)
