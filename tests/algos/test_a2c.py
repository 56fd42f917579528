"""A2C: SB3's constructor and optimizer, every action space, predict/callbacks/save/load/seeds
(ported in spirit from SB3's test_run, test_predict, test_callbacks, test_save_load,
test_deterministic), its loss on hand-computed n-step advantages, one update equal to SB3's
own ``A2C.train`` on the same rollout, the numpy learner equal to the torch learner, and bad
input."""

from __future__ import annotations

import inspect
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

import palaestra as gym
from palaestra.algos import A2C, PPO, ModelFileError, evaluate_policy
from palaestra.algos.a2c.objective import a2c_loss, a2c_loss_vjp
from palaestra.algos.callbacks import CheckpointCallback, EvalCallback
from palaestra.algos.learners import NumpyLearner, TorchLearner
from palaestra.algos.learners.losses import gae
from palaestra.algos.learners.xp import numpy_ops, torch_ops
from palaestra.vec_env import DummyVecEnv, make_vec_env

from .toys import Toy

OBS = np.random.default_rng(0).normal(size=(32, 4)).astype(np.float32)


def test_defaults_match_sb3() -> None:
    import stable_baselines3 as sb3

    mine = inspect.signature(A2C.__init__).parameters
    for name, param in inspect.signature(sb3.A2C.__init__).parameters.items():
        if name in ("self", "policy", "env") or param.default is inspect.Parameter.empty:
            continue
        assert name in mine, name
        assert mine[name].default == param.default, name
    assert inspect.signature(A2C.learn).parameters["log_interval"].default == 100


def test_optimizer_is_sb3s() -> None:
    """RMSprop(alpha=0.99, eps=rms_prop_eps, weight_decay=0) replaces the policy's optimizer
    (even its optimizer_kwargs, as SB3); use_rms_prop=False or an optimizer_class keeps the
    policy's (Adam with eps=1e-5)."""
    import stable_baselines3 as sb3

    theirs = sb3.A2C("MlpPolicy", "CartPole-v1", rms_prop_eps=1e-4).policy.optimizer
    ours = A2C("MlpPolicy", "CartPole-v1", rms_prop_eps=1e-4).optimizer
    assert type(ours) is type(theirs) is torch.optim.RMSprop
    for key in ("lr", "alpha", "eps", "weight_decay", "momentum", "centered"):
        assert ours.param_groups[0][key] == theirs.param_groups[0][key], key
    replaced = A2C("MlpPolicy", "CartPole-v1", policy_kwargs={"optimizer_kwargs": {"eps": 0.1}})
    assert replaced.optimizer.param_groups[0]["eps"] == 1e-5
    assert replaced.policy_kwargs == {"optimizer_kwargs": {"eps": 0.1}}  # saved as given
    adam = A2C("MlpPolicy", "CartPole-v1", use_rms_prop=False)
    assert (
        type(adam.optimizer) is torch.optim.Adam and adam.optimizer.param_groups[0]["eps"] == 1e-5
    )
    assert isinstance(adam.learner, NumpyLearner)
    sgd = A2C("MlpPolicy", "CartPole-v1", policy_kwargs={"optimizer_class": torch.optim.SGD})
    assert type(sgd.optimizer) is torch.optim.SGD and isinstance(sgd.learner, TorchLearner)


@pytest.mark.parametrize("action", ["discrete", "box", "multidiscrete", "multibinary"])
@pytest.mark.parametrize("n_envs", [1, 3])
def test_run_on_every_action_space(action: str, n_envs: int) -> None:
    venv = DummyVecEnv([lambda: Toy(action=action)] * n_envs)
    model = A2C("MlpPolicy", venv, seed=0).learn(60)
    assert model.num_timesteps == 60  # rollouts of 5 * n_envs steps
    assert isinstance(model.learner, NumpyLearner)
    a, _ = model.predict(np.zeros(3, np.float32), deterministic=True)
    assert model.action_space.contains(a.astype(model.action_space.dtype))
    logged = model.logger.name_to_value
    for key in ("train/entropy_loss", "train/policy_loss", "train/value_loss"):
        assert math.isfinite(logged[key]), key
    assert logged["train/n_updates"] == model._n_updates == 60 // (5 * n_envs)
    assert logged["train/learning_rate"] == 7e-4
    assert ("train/std" in logged) == (action == "box")


def test_verbose_table_has_sb3s_keys(capsys: pytest.CaptureFixture[str]) -> None:
    A2C("MlpPolicy", "Pendulum-v1", verbose=1, seed=0).learn(100, log_interval=10)
    out = capsys.readouterr().out
    assert "Training with the numpy learner (small MLPs with RMSprop on the CPU)" in out
    for key in (
        "entropy_loss",
        "explained_variance",
        "learning_rate",
        "n_updates",
        "policy_loss",
        "std",
        "value_loss",
        "iterations",
    ):
        assert f"|    {key} " in out, key


def test_predict_shapes() -> None:
    model = A2C("MlpPolicy", "CartPole-v1", seed=0)
    obs, _ = gym.make("CartPole-v1").reset(seed=0)
    action, state = model.predict(obs, deterministic=True)
    assert action.shape == () and state is None
    assert model.predict(np.stack([obs] * 5))[0].shape == (5,)
    with pytest.raises(ValueError, match="Unexpected observation shape"):
        model.predict(np.zeros(3))
    box = A2C("MlpPolicy", Toy(action="box"), seed=0)
    a, _ = box.predict(np.zeros((4, 3), np.float32))
    assert a.shape == (4, 2) and np.all(np.abs(a) <= 1)


def test_callbacks(tmp_path: Path) -> None:
    seen: list[list[str]] = []

    def stop_after_seven(locals_: dict[str, Any], globals_: dict[str, Any]) -> bool:
        seen.append(sorted(locals_))
        return len(seen) < 7

    model = A2C("MlpPolicy", "CartPole-v1", seed=0).learn(1000, callback=stop_after_seven)
    assert model.num_timesteps == 7 and model.rollout_buffer.pos == 2  # a partial rollout kept
    assert {"actions", "dones", "infos", "new_obs", "rewards"} <= set(seen[0])
    eval_cb = EvalCallback(gym.make("CartPole-v1"), eval_freq=50, n_eval_episodes=2)
    ckpt = CheckpointCallback(save_freq=100, save_path=str(tmp_path), name_prefix="a2c")
    A2C("MlpPolicy", "CartPole-v1", seed=0).learn(200, callback=[eval_cb, ckpt])
    assert len(eval_cb.evaluations_results) == 4
    assert sorted(p.name for p in tmp_path.glob("a2c_*.zip")) == [
        "a2c_100_steps.zip",
        "a2c_200_steps.zip",
    ]
    assert A2C.load(tmp_path / "a2c_200_steps.zip").num_timesteps == 200


def test_save_load(tmp_path: Path) -> None:
    model = A2C("MlpPolicy", "CartPole-v1", seed=3, ent_coef=0.01).learn(300)
    model.save(tmp_path / "a2c")
    loaded = A2C.load(tmp_path / "a2c.zip")
    np.testing.assert_array_equal(
        model.predict(OBS, deterministic=True)[0], loaded.predict(OBS, deterministic=True)[0]
    )
    assert loaded.ent_coef == 0.01 and loaded.num_timesteps == 300
    params = model.get_parameters()
    assert set(params) == {"policy", "policy.optimizer"}  # SB3's keys
    opt_state = loaded.optimizer.state_dict()["state"]
    for index, state in params["policy.optimizer"]["state"].items():
        assert set(state) == {"step", "square_avg"}
        assert torch.equal(state["square_avg"], opt_state[index]["square_avg"])
    with pytest.raises(ModelFileError, match=r"load it with A2C\.load"):
        PPO.load(tmp_path / "a2c.zip")


def test_same_seed_same_bits() -> None:
    a, b = (A2C("MlpPolicy", "CartPole-v1", seed=1).learn(400) for _ in range(2))
    for (k, x), (_, y) in zip(a.policy.state_dict().items(), b.policy.state_dict().items()):
        assert torch.equal(x, y), k
    c = A2C("MlpPolicy", "CartPole-v1", seed=2).learn(400)
    assert not all(torch.equal(x, y) for x, y in zip(a.policy.parameters(), c.policy.parameters()))


def test_evaluate_policy() -> None:
    model = A2C("MlpPolicy", "CartPole-v1", seed=0)
    env = gym.make("CartPole-v1")
    env.reset(seed=0)
    rewards, lengths = evaluate_policy(model, env, n_eval_episodes=3, return_episode_rewards=True)
    assert len(rewards) == len(lengths) == 3 and rewards == [float(n) for n in lengths]


def test_bad_input() -> None:
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ValueError, match=rf"n_steps must be a positive integer, got {bad!r}"):
            A2C("MlpPolicy", "CartPole-v1", n_steps=bad)  # type: ignore[arg-type]
    for eps in (0.0, -1e-5, math.nan, math.inf, "1e-5"):
        with pytest.raises(
            ValueError, match=rf"rms_prop_eps must be a positive finite number, got {eps!r}"
        ):
            A2C("MlpPolicy", "CartPole-v1", rms_prop_eps=eps)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"gae_lambda must be a number in \[0, 1\], got 1.5"):
        A2C("MlpPolicy", "CartPole-v1", gae_lambda=1.5)
    with pytest.raises(ValueError, match=r"gamma must be a number in \[0, 1\], got -0.1"):
        A2C("MlpPolicy", "CartPole-v1", gamma=-0.1)
    with pytest.raises(ValueError, match=r"gSDE\) can only be used with continuous actions"):
        A2C("MlpPolicy", "CartPole-v1", use_sde=True)  # SB3's refusal, word for word
    with pytest.raises(ValueError, match=r"normalize_advantage=True needs more than one sample"):
        A2C("MlpPolicy", "CartPole-v1", n_steps=1, normalize_advantage=True)
    model = A2C("MlpPolicy", "CartPole-v1", n_steps=1, normalize_advantage=False)
    assert model.learn(3).num_timesteps == 3  # one sample per update is fine without it
    centered = {"optimizer_class": torch.optim.RMSprop, "optimizer_kwargs": {"centered": True}}
    with pytest.raises(
        ValueError, match="backend='numpy' cannot train this model: RMSprop with centered=True"
    ):
        A2C("MlpPolicy", "CartPole-v1", policy_kwargs={"backend": "numpy", **centered})
    assert isinstance(A2C("MlpPolicy", "CartPole-v1", policy_kwargs=centered).learner, TorchLearner)


# -- the loss ---------------------------------------------------------------------------------
def test_a2c_loss_on_hand_computed_n_step_advantages() -> None:
    """n_steps=5, one env, gamma=0.5, gae_lambda=1: returns are 5-step discounted sums
    bootstrapped by V(s_5), cut where an episode ends (after step 2)."""
    rewards = np.ones((5, 1), np.float32)
    values = np.full((5, 1), 0.5, np.float32)
    starts = np.array([[0], [0], [0], [1], [0]], np.float32)  # step 3 starts a new episode
    adv, ret = gae(rewards, values, starts, np.array([0.5]), np.array([0.0]), 0.5, 1.0)
    # t=4: 1 + 0.5*0.5; t=3: 1 + 0.5*1.25; t=2: 1 (episode end); t=1: 1.5; t=0: 1.75
    np.testing.assert_allclose(ret.ravel(), [1.75, 1.5, 1.0, 1.625, 1.25])
    np.testing.assert_allclose(adv.ravel(), [1.25, 1.0, 0.5, 1.125, 0.75])
    log_prob = np.log(np.array([0.5, 0.25, 0.5, 0.5, 0.25], np.float32))
    entropy = np.full(5, 0.6, np.float32)
    loss, metrics, _ = a2c_loss(
        numpy_ops, log_prob, adv.ravel(), values.ravel(), ret.ravel(), entropy, 0.01, 0.5
    )
    ln2 = math.log(2)
    policy = -(1.25 * -ln2 + 1.0 * -2 * ln2 + 0.5 * -ln2 + 1.125 * -ln2 + 0.75 * -2 * ln2) / 5
    value = (1.25**2 + 1.0**2 + 0.5**2 + 1.125**2 + 0.75**2) / 5
    assert metrics["policy_loss"] == pytest.approx(policy, rel=1e-6)
    assert metrics["value_loss"] == pytest.approx(value, rel=1e-6)
    assert metrics["entropy_loss"] == pytest.approx(-0.6, rel=1e-6)
    assert float(loss) == pytest.approx(policy - 0.01 * 0.6 + 0.5 * value, rel=1e-6)
    # normalised advantages: mean 0, unbiased std 1 (SB3's +1e-8 aside)
    _, normed, _ = a2c_loss(
        numpy_ops, log_prob, adv.ravel(), values.ravel(), ret.ravel(), None, 0.0, 0.5, True
    )
    a = adv.ravel().astype(np.float64)
    z = (a - a.mean()) / a.std(ddof=1)
    assert normed["policy_loss"] == pytest.approx(float(-(z * log_prob).mean()), rel=1e-5)
    assert normed["entropy_loss"] == pytest.approx(float(log_prob.mean()), rel=1e-6)


A2C_CASES = {
    "plain": dict(ent_coef=0.0, normalize_advantage=False),
    "entropy": dict(ent_coef=0.01, normalize_advantage=False),
    "normalized": dict(ent_coef=0.02, normalize_advantage=True),
    "no_entropy": dict(ent_coef=0.05, normalize_advantage=True),  # a head without entropy
}


@pytest.mark.parametrize("name", sorted(A2C_CASES))
def test_a2c_loss_vjp_against_autograd(name: str) -> None:
    rng = np.random.default_rng(1)
    n = 10
    lp, adv, values, returns = (rng.normal(size=n).astype(np.float32) for _ in range(4))
    entropy = None if name == "no_entropy" else np.abs(rng.normal(size=n)).astype(np.float32)
    kw = A2C_CASES[name]
    _, metrics, tape = a2c_loss(numpy_ops, lp, adv, values, returns, entropy, **kw)
    g_lp, g_v, g_h = a2c_loss_vjp(tape)
    t_lp, t_v = torch.tensor(lp, requires_grad=True), torch.tensor(values, requires_grad=True)
    t_ent = None if entropy is None else torch.tensor(entropy, requires_grad=True)
    t = torch.as_tensor
    t_loss, t_metrics, _ = a2c_loss(torch_ops, t_lp, t(adv), t_v, t(returns), t_ent, **kw)
    t_loss.backward()
    assert t_lp.grad is not None and t_v.grad is not None
    np.testing.assert_allclose(g_lp, t_lp.grad.numpy(), rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(g_v, t_v.grad.numpy(), rtol=1e-5, atol=1e-7)
    if t_ent is not None:
        assert t_ent.grad is not None
        np.testing.assert_allclose(np.full(n, g_h / n), t_ent.grad.numpy(), rtol=1e-5)
    else:
        assert g_h == 0.0
    for key, value in metrics.items():
        assert value == pytest.approx(torch_ops.scalar(t_metrics[key]), rel=1e-5, abs=1e-7), key


# -- whole updates ----------------------------------------------------------------------------
UPDATE_CASES = [
    ("CartPole-v1", {"ent_coef": 0.01}),
    ("Pendulum-v1", {"ent_coef": 0.01, "normalize_advantage": True}),
    ("CartPole-v1", {"use_rms_prop": False}),
    (Toy(action="multidiscrete"), {"ent_coef": 0.01}),
    (Toy(action="multibinary"), {"ent_coef": 0.01}),
]
UPDATE_IDS = ["cartpole", "pendulum", "adam", "multidiscrete", "multibinary"]


@pytest.mark.parametrize(("env", "kwargs"), UPDATE_CASES, ids=UPDATE_IDS)
def test_numpy_update_matches_torch(env: Any, kwargs: dict[str, Any]) -> None:
    """Three updates on the numpy learner equal them on the torch learner (float32 rounding:
    repeated on one rollout, the differences grow by about 10x per 5 updates)."""
    import copy

    model = A2C("MlpPolicy", env, n_steps=8, seed=0, **kwargs)
    assert isinstance(model.learner, NumpyLearner)
    model.learn(40)
    twin = copy.deepcopy(model)
    twin.learner.to_torch()
    old = twin.learner
    twin.learner = TorchLearner(old.nets, old.groups, torch.device("cpu"), "test twin")
    for _ in range(3):
        model.train()
        twin.train()
    ours, theirs = model.policy.state_dict(), twin.policy.state_dict()
    for key, value in ours.items():
        torch.testing.assert_close(value, theirs[key], atol=1e-5, rtol=1e-4, msg=key)
    opt, twin_opt = model.optimizer.state_dict()["state"], twin.optimizer.state_dict()["state"]
    for index, state in opt.items():
        assert float(state["step"]) == float(twin_opt[index]["step"])
        moment = "square_avg" if "square_avg" in state else "exp_avg_sq"
        torch.testing.assert_close(state[moment], twin_opt[index][moment], atol=1e-7, rtol=1e-4)
    for key in ("train/policy_loss", "train/value_loss", "train/entropy_loss"):
        ours_v, theirs_v = model.logger.name_to_value[key], twin.logger.name_to_value[key]
        assert ours_v == pytest.approx(theirs_v, rel=1e-4, abs=1e-6), key


_SB3_KEYS = {
    "pi_net.": "mlp_extractor.policy_net.",
    "vf_net.": "mlp_extractor.value_net.",
    "action_head.net.": "action_net.",
    "action_head.log_std": "log_std",
    "value_head.": "value_net.",
}


def _sb3_key(key: str) -> str:
    for ours, theirs in _SB3_KEYS.items():
        if key.startswith(ours):
            return theirs + key[len(ours) :]
    raise KeyError(key)


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        ("CartPole-v1", {"ent_coef": 0.01}),
        ("Pendulum-v1", {"ent_coef": 0.01, "normalize_advantage": True}),
        ("CartPole-v1", {"use_rms_prop": False, "vf_coef": 0.25}),
    ],
    ids=["cartpole", "pendulum", "adam"],
)
def test_updates_equal_sb3s_train_on_the_same_rollouts(env_id: str, kwargs: dict[str, Any]) -> None:
    """SB3's own ``A2C.train`` and ours, from the same weights on the same rollouts, move the
    weights the same way (three updates, so the RMSprop averages carry over)."""
    import stable_baselines3 as sb3
    from stable_baselines3.common.logger import Logger

    n_envs, n_steps = 2, 5
    theirs = sb3.A2C("MlpPolicy", make_vec_env_sb3(env_id, n_envs), n_steps=n_steps, **kwargs)
    theirs._logger = Logger(folder=None, output_formats=[])
    ours = A2C("MlpPolicy", make_vec_env(env_id, n_envs=n_envs), n_steps=n_steps, seed=0, **kwargs)
    ours_state = ours.policy.state_dict()
    theirs.policy.load_state_dict({_sb3_key(k): v for k, v in ours_state.items()})
    rng = np.random.default_rng(0)
    for _ in range(3):
        buf, ref = ours.rollout_buffer, theirs.rollout_buffer
        buf.observations[...] = rng.normal(size=buf.observations.shape)
        samples = [ours.action_space.sample() for _ in range(n_steps * n_envs)]
        buf.actions[...] = np.asarray(samples).reshape(buf.actions.shape)
        buf.values[...] = rng.normal(size=buf.values.shape)
        buf.returns[...] = rng.normal(size=buf.returns.shape)
        buf.advantages[...] = rng.normal(size=buf.advantages.shape)
        ref.reset()
        ref.observations[...] = buf.observations
        ref.actions[...] = buf.actions.reshape(ref.actions.shape)
        for name in ("values", "returns", "advantages"):
            getattr(ref, name)[...] = getattr(buf, name)
        ref.pos, ref.full = n_steps, True
        ours.train()
        theirs.train()
    for key, value in ours.policy.state_dict().items():
        torch.testing.assert_close(
            value, theirs.policy.state_dict()[_sb3_key(key)], atol=1e-5, rtol=1e-4, msg=key
        )
    for key in ("train/policy_loss", "train/value_loss", "train/entropy_loss"):
        assert ours.logger.name_to_value[key] == pytest.approx(
            theirs.logger.name_to_value[key], rel=1e-4, abs=1e-6
        ), key


def make_vec_env_sb3(env_id: str, n_envs: int) -> Any:
    from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env

    return sb3_make_vec_env(env_id, n_envs=n_envs)


@pytest.mark.slow
@pytest.mark.parametrize("action", ["discrete", "box"])
def test_identity(action: str) -> None:
    """SB3's test_identity in spirit: the Toy env rewards the action matching the observation;
    A2C finds it (random play scores about half the horizon)."""
    venv = DummyVecEnv([lambda: Toy(action=action, horizon=10)] * 4)
    model = A2C("MlpPolicy", venv, seed=0, learning_rate=3e-3, ent_coef=0.0)
    model.learn(20_000 if action == "box" else 8_000)
    mean, _ = evaluate_policy(model, Toy(action=action, horizon=10), n_eval_episodes=20)
    assert mean >= 9.0
