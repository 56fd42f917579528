"""SAC, TD3 and DDPG: SB3's API and defaults, their losses by hand, both learners agreeing,
save/load, determinism, bad input; learning checks under ``slow``."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

import palaestra as gym
from palaestra.algos import (
    DDPG,
    SAC,
    TD3,
    NormalActionNoise,
    OrnsteinUhlenbeckActionNoise,
    VectorizedActionNoise,
    evaluate_policy,
)
from palaestra.algos.callbacks import CheckpointCallback, EvalCallback
from palaestra.algos.common.off_policy_actor_critic import ActorCriticOffPolicy
from palaestra.algos.learners import NumpyLearner, TorchLearner
from palaestra.algos.learners.xp import numpy_ops
from palaestra.algos.sac.objective import SACCriticObjective
from palaestra.algos.td3.objective import TD3CriticObjective
from palaestra.runs.algorithms import REGISTRY, algo_class
from palaestra.vec_env import make_vec_env

from .toys import Toy

# The declared algorithms that are off-policy actor-critics (SAC, TD3, DDPG, ...)
ALGOS = [
    cls
    for cls in (algo_class(entry.name) for entry in REGISTRY)
    if issubclass(cls, ActorCriticOffPolicy)
]
SMALL = {"net_arch": [32, 32]}


def _model(cls: Any, env: Any = "Pendulum-v1", **kwargs: Any) -> Any:
    kwargs.setdefault("policy_kwargs", dict(SMALL))
    return cls("MlpPolicy", env, learning_starts=50, batch_size=32, seed=0, **kwargs)


@pytest.mark.parametrize("cls", ALGOS)
def test_defaults_are_sb3s(cls: Any) -> None:
    import stable_baselines3 as sb3

    theirs = getattr(sb3, cls.__name__)("MlpPolicy", "Pendulum-v1")
    ours = cls("MlpPolicy", "Pendulum-v1")
    for name in (
        "learning_rate",
        "buffer_size",
        "learning_starts",
        "batch_size",
        "tau",
        "gamma",
        "gradient_steps",
    ):
        assert getattr(ours, name) == getattr(theirs, name), name
    assert ours.train_freq == (theirs.train_freq.frequency, theirs.train_freq.unit.value)
    for name in (
        "policy_delay",
        "target_policy_noise",
        "target_noise_clip",
        "target_update_interval",
    ):
        if hasattr(theirs, name):
            assert getattr(ours, name) == getattr(theirs, name), name
    ours_keys = {k: tuple(v.shape) for k, v in ours.policy.state_dict().items()}
    theirs_keys = {k: tuple(v.shape) for k, v in theirs.policy.state_dict().items()}
    assert {k: v for k, v in ours_keys.items() if not k.startswith("ent_coef")} == theirs_keys
    if cls is SAC:
        assert ours.target_entropy == theirs.target_entropy == -1.0
        assert ours._current_ent_coef() == pytest.approx(float(theirs.log_ent_coef.exp()))


@pytest.mark.parametrize("cls", ALGOS)
@pytest.mark.parametrize(
    "train",
    [dict(train_freq=4, gradient_steps=-1), dict(train_freq=(1, "episode"), gradient_steps=2)],
    ids=["steps", "episodes"],
)
def test_run_with_several_envs(cls: Any, train: dict[str, Any]) -> None:
    env = make_vec_env("Pendulum-v1", n_envs=2, seed=0)
    model = _model(cls, env, **train)
    model.learn(500)
    assert model._n_updates > 0
    assert np.isfinite(model.logger.name_to_value["train/critic_loss"])
    actions, _ = model.predict(env.reset(), deterministic=True)
    assert actions.shape == (2, 1) and np.all(np.abs(actions) <= 2.0)


@pytest.mark.parametrize("cls", ALGOS)
def test_predict_shapes_and_bounds(cls: Any) -> None:
    env = Toy(action="box")  # bounds [-1, 1] x 2
    model = _model(cls, env)
    obs, _ = env.reset(seed=0)
    action, _ = model.predict(obs)
    assert action.shape == (2,) and env.action_space.contains(action)
    batch, _ = model.predict(np.stack([obs] * 5), deterministic=True)
    assert batch.shape == (5, 2)


def test_actions_are_scaled_to_the_bounds() -> None:
    model = _model(SAC, gym.make("MountainCarContinuous-v0"))
    scaled = np.array([[-1.0], [0.0], [1.0]], np.float32)
    np.testing.assert_allclose(model._unscale(scaled).ravel(), [-1.0, 0.0, 1.0])
    pendulum = _model(SAC)
    np.testing.assert_allclose(pendulum._unscale(scaled).ravel(), [-2.0, 0.0, 2.0])


@pytest.mark.parametrize("cls", ALGOS)
def test_same_seed_same_bits_and_learners_agree(cls: Any) -> None:
    def run(backend: str) -> Any:
        noise = NormalActionNoise(np.zeros(1), np.full(1, 0.1))
        model = _model(cls, action_noise=noise, policy_kwargs={**SMALL, "backend": backend})
        model.learn(300)
        return model

    a, b, t = run("numpy"), run("numpy"), run("torch")
    assert isinstance(a.learner, NumpyLearner) and isinstance(t.learner, TorchLearner)
    for key, value in a.policy.state_dict().items():
        assert torch.equal(value, b.policy.state_dict()[key]), key
        torch.testing.assert_close(value, t.policy.state_dict()[key], atol=1e-4, rtol=1e-3)


@pytest.mark.parametrize("cls", ALGOS)
def test_save_load_and_continue(cls: Any, tmp_path: Path) -> None:
    model = _model(cls, action_noise=OrnsteinUhlenbeckActionNoise(np.zeros(1), np.full(1, 0.2)))
    model.learn(120)
    model.save(tmp_path / "m.zip")
    model.save_replay_buffer(tmp_path / "rb.zip")
    loaded = cls.load(tmp_path / "m.zip", env="Pendulum-v1")
    loaded.load_replay_buffer(tmp_path / "rb.zip")
    obs = np.random.default_rng(0).normal(size=(6, 3)).astype(np.float32)
    np.testing.assert_array_equal(
        model.predict(obs, deterministic=True)[0], loaded.predict(obs, deterministic=True)[0]
    )
    assert isinstance(loaded.action_noise, OrnsteinUhlenbeckActionNoise)
    np.testing.assert_array_equal(loaded.action_noise.noise_prev, model.action_noise.noise_prev)
    assert loaded.replay_buffer.size() == model.replay_buffer.size()
    params = model.get_parameters()
    assert {"policy", "actor.optimizer", "critic.optimizer"} <= set(params)
    loaded.learn(100, reset_num_timesteps=False)
    assert loaded.num_timesteps == 220


def test_sac_fixed_and_learned_entropy_coefficient() -> None:
    fixed = _model(SAC, ent_coef=0.05)
    fixed.learn(120)
    assert fixed.logger.name_to_value["train/ent_coef"] == pytest.approx(0.05)
    assert "train/ent_coef_loss" not in fixed.logger.name_to_value
    learned = _model(SAC, ent_coef="auto_0.5")
    assert learned._current_ent_coef() == pytest.approx(0.5)
    learned.learn(200)
    logged = learned.logger.name_to_value
    assert {"train/actor_loss", "train/critic_loss", "train/ent_coef", "train/ent_coef_loss"} <= (
        set(logged)
    )
    assert learned._current_ent_coef() != pytest.approx(0.5)


def test_sac_critic_target_by_hand() -> None:
    """r + gamma (1 - done) (min_i Q'_i(s', a') - alpha log pi(a'|s')), with the nets replaced
    by constants: Q'_0 = 2, Q'_1 = 3, a' = tanh(0) = 0, log pi = log N(0) - log(1 + 1e-6)."""
    outputs = {
        "latent": np.zeros((2, 4), np.float32),
        "mu": np.zeros((2, 1), np.float32),
        "log_std": np.zeros((2, 1), np.float32),
        "qf0_target": np.full((2, 1), 2.0, np.float32),
        "qf1_target": np.full((2, 1), 3.0, np.float32),
        "qf0": np.array([[1.0], [0.0]], np.float32),
        "qf1": np.array([[2.0], [0.0]], np.float32),
    }
    batch = {
        "observations": np.zeros((2, 3), np.float32),
        "next_observations": np.zeros((2, 3), np.float32),
        "actions": np.zeros((2, 1), np.float32),
        "rewards": np.array([1.0, 1.0], np.float32),
        "terminated": np.array([0.0, 1.0], np.float32),
        "next_noise": np.zeros((2, 1), np.float32),
    }
    loss, _, (errors, _) = SACCriticObjective(2, 0.9, 0.2).loss(
        numpy_ops, lambda name, x: outputs[name], {}, batch
    )
    log_pi = -0.5 * math.log(2 * math.pi) - math.log(1 + 1e-6)
    target = np.array([1.0 + 0.9 * (2.0 - 0.2 * log_pi), 1.0])
    np.testing.assert_allclose(errors[0], [1.0 - target[0], -1.0], rtol=1e-6)
    expected = 0.5 * (
        np.mean((np.array([1.0, 0.0]) - target) ** 2)
        + np.mean((np.array([2.0, 0.0]) - target) ** 2)
    )
    assert loss == pytest.approx(expected, rel=1e-6)


class _Spaces(gym.Env):  # type: ignore[type-arg]
    """Only spaces (the update tests never step it): ``obs_dim`` float64s, ``act_dim`` in
    [-1, 1]."""

    def __init__(self, obs_dim: int, act_dim: int) -> None:
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (obs_dim,), np.float64)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (act_dim,), np.float32)


class _QueuedNoise:
    """Stands in for the model's generator in ``SAC.train``: hands out queued noise."""

    def __init__(self, queue: list[np.ndarray]) -> None:
        self.queue = queue

    def standard_normal(self, shape: tuple[int, ...], dtype: Any = None) -> np.ndarray:
        noise = self.queue.pop(0)
        assert noise.shape == tuple(shape)
        return noise


@pytest.mark.parametrize("backend", ["numpy", "torch"])
def test_sac_updates_equal_sb3s_train_on_the_same_batches_and_noise(
    backend: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """SB3's own ``SAC.train`` and ours, from the same weights, batches and Gaussian noise,
    move the actor, the critics, their targets and the temperature alike over 30 updates
    (SB3's default 256-256 nets; observation and action sizes of HalfCheetah)."""
    import gymnasium
    import stable_baselines3 as sb3
    from stable_baselines3.common.logger import Logger
    from stable_baselines3.common.type_aliases import ReplayBufferSamples

    obs_dim, act_dim, n_updates, batch_size = 17, 6, 30, 64
    obs_space = (-np.inf, np.inf, (obs_dim,), np.float64)
    ours = SAC("MlpPolicy", _Spaces(obs_dim, act_dim), seed=0, policy_kwargs={"backend": backend})
    assert ours.learner.backend == backend

    class GymSpaces(gymnasium.Env):  # type: ignore[type-arg]
        observation_space = gymnasium.spaces.Box(*obs_space)
        action_space = gymnasium.spaces.Box(-1.0, 1.0, (act_dim,), np.float32)

    theirs = sb3.SAC("MlpPolicy", GymSpaces(), seed=0)
    theirs._logger = Logger(folder=None, output_formats=[])
    theirs._current_progress_remaining = ours._current_progress_remaining = 1.0
    ours.learner.to_torch()  # hands the torch objects out: it reads them back before training
    for part in ("actor", "critic", "critic_target"):
        getattr(ours.policy, part).load_state_dict(getattr(theirs.policy, part).state_dict())
    with torch.no_grad():
        theirs.log_ent_coef.fill_(math.log(0.5))  # a temperature that moves the losses
        ours.policy.ent_coef.log_ent_coef.copy_(theirs.log_ent_coef)

    rng = np.random.default_rng(0)
    batches = [
        {
            "observations": rng.normal(size=(batch_size, obs_dim)).astype(np.float32),
            "actions": rng.uniform(-1, 1, (batch_size, act_dim)).astype(np.float32),
            "next_observations": rng.normal(size=(batch_size, obs_dim)).astype(np.float32),
            "rewards": rng.normal(size=batch_size).astype(np.float32),
            "terminated": (rng.uniform(size=batch_size) < 0.2).astype(np.float32),
        }
        for _ in range(n_updates)
    ]
    # per update: the actor's actions' noise, then the next actions' (both libraries' order)
    noise = [
        rng.standard_normal((batch_size, act_dim)).astype(np.float32) for _ in range(2 * n_updates)
    ]

    ours_batches = list(batches)
    monkeypatch.setattr(ours, "_sample_batch", lambda size: dict(ours_batches.pop(0)))
    ours._rng = _QueuedNoise(list(noise))
    ours.train(n_updates, batch_size)

    theirs_batches, theirs_noise = list(batches), list(noise)

    def sample(size: int, env: Any = None) -> ReplayBufferSamples:
        b = theirs_batches.pop(0)
        return ReplayBufferSamples(
            *(torch.as_tensor(b[k]) for k in ("observations", "actions", "next_observations")),
            torch.as_tensor(b["terminated"][:, None]),
            torch.as_tensor(b["rewards"][:, None]),
        )

    monkeypatch.setattr(theirs.replay_buffer, "sample", sample)
    monkeypatch.setattr(
        torch.distributions.Normal,
        "rsample",
        lambda self, shape=(): self.loc + self.scale * torch.as_tensor(theirs_noise.pop(0)),
    )
    theirs.train(n_updates, batch_size)
    assert not ours_batches and not theirs_batches and not theirs_noise

    ours.learner.to_torch()
    for part in ("actor", "critic", "critic_target"):
        mine, other = (
            getattr(ours.policy, part).state_dict(),
            getattr(theirs.policy, part).state_dict(),
        )
        for key, value in mine.items():
            torch.testing.assert_close(value, other[key], atol=2e-5, rtol=1e-4, msg=f"{part} {key}")
    assert ours.policy.ent_coef.log_ent_coef.item() == pytest.approx(
        theirs.log_ent_coef.item(), abs=1e-6
    )
    for key in ("train/actor_loss", "train/critic_loss", "train/ent_coef", "train/ent_coef_loss"):
        assert ours.logger.name_to_value[key] == pytest.approx(
            theirs.logger.name_to_value[key], rel=1e-4, abs=1e-6
        ), key


class _Transcript(gym.Wrapper):  # type: ignore[type-arg]
    """Writes down every reset observation and every step as the env saw it."""

    def __init__(self, env: Any) -> None:
        super().__init__(env)
        self.steps: list[tuple[Any, ...]] = []
        self.obs: Any = None

    def reset(self, **kwargs: Any) -> Any:
        self.obs, info = self.env.reset(**kwargs)
        return self.obs, info

    def step(self, action: Any) -> Any:
        out = self.env.step(action)
        self.steps.append((self.obs, np.array(action), *out[:4]))
        self.obs = out[0]
        return out


@pytest.mark.parametrize("cls", ALGOS)
def test_replay_buffer_holds_what_the_env_did_across_truncations(cls: Any) -> None:
    """Every stored transition is the env's own step: observation, action, next observation
    (the terminal one at a truncation, not the reset's), reward; truncations stored as not
    terminated so targets bootstrap (SB3's handle_timeout_termination)."""
    env = _Transcript(gym.make("Pendulum-v1"))
    model = _model(cls, env)
    model.learn(450)
    ring = model.replay_buffer
    assert ring.size() == len(env.steps) == 450
    for t, (obs, action, next_obs, reward, terminated, truncated) in enumerate(env.steps):
        np.testing.assert_array_equal(ring.observations[t, 0], obs, err_msg=str(t))
        # stored rescaled to [-1, 1] as SB3 stores them; Pendulum's torque bound is 2
        np.testing.assert_allclose(2.0 * ring.actions[t, 0], action, atol=1e-6, err_msg=str(t))
        np.testing.assert_array_equal(ring.next_observations[t, 0], next_obs, err_msg=str(t))
        assert ring.rewards[t, 0] == np.float32(reward)
        assert ring.terminated[t, 0] == float(terminated and not truncated)
    assert [t for t, step in enumerate(env.steps) if step[5]] == [199, 399]


def test_td3_target_smoothing_by_hand() -> None:
    """Target actions: clip(mu'(s') + clipped noise, -1, 1); the target is the smaller Q'."""
    seen: dict[str, Any] = {}

    def run(name: str, x: Any) -> np.ndarray:
        seen[name] = x
        if name == "actor_target":
            return np.array([[0.9], [-0.2]], np.float32)
        if name.endswith("_target"):
            a = x[1]
            return (a * (2.0 if name == "qf0_target" else 3.0)).astype(np.float32)
        return np.zeros((2, 1), np.float32)

    batch = {
        "observations": np.zeros((2, 3), np.float32),
        "next_observations": np.zeros((2, 3), np.float32),
        "actions": np.zeros((2, 1), np.float32),
        "rewards": np.zeros(2, np.float32),
        "terminated": np.zeros(2, np.float32),
        "target_noise": np.array([[0.5], [0.1]], np.float32),  # already clipped at 0.5
    }
    _, _, (errors, _) = TD3CriticObjective(2, 1.0).loss(numpy_ops, run, {}, batch)
    np.testing.assert_allclose(seen["qf0_target"][1].ravel(), [1.0, -0.1], rtol=1e-6)
    np.testing.assert_allclose(-errors[0], [2.0, -0.3], rtol=1e-6)  # min(2a, 3a)
    model = _model(TD3, target_policy_noise=10.0, target_noise_clip=0.3)
    model.learn(60)
    noise = np.clip(np.random.default_rng(0).normal(0, 10.0, 1000), -0.3, 0.3)
    assert np.abs(noise).max() == pytest.approx(0.3)  # the clip the batch noise goes through


def test_ddpg_is_td3_without_the_tricks() -> None:
    model = _model(DDPG)
    assert model.policy_delay == 1 and model.target_noise_clip == 0.0
    assert len(model.critic.q_networks) == 1
    assert len(_model(DDPG, policy_kwargs={**SMALL, "n_critics": 2}).critic.q_networks) == 2


def test_vectorized_noise_and_resets() -> None:
    env = make_vec_env("Pendulum-v1", n_envs=3, seed=0)
    ou = OrnsteinUhlenbeckActionNoise(np.zeros(1), np.full(1, 0.3))
    model = _model(TD3, env, action_noise=ou)
    model.learn(60)
    assert isinstance(model.action_noise, VectorizedActionNoise)  # wrapped, as SB3
    assert model.action_noise.shape == (3, 1)
    model.action_noise.reset([1])
    assert np.all(model.action_noise.noises[1].noise_prev == 0)
    with pytest.raises(ValueError, match="positive integer"):
        VectorizedActionNoise(ou, 0)


@pytest.mark.parametrize("cls", ALGOS)
def test_callbacks_and_evaluation(cls: Any, tmp_path: Path) -> None:
    eval_env = gym.make("Pendulum-v1")
    callbacks = [
        CheckpointCallback(100, str(tmp_path), name_prefix="ckpt"),
        EvalCallback(eval_env, eval_freq=100, n_eval_episodes=1, log_path=str(tmp_path)),
    ]
    model = _model(cls)
    model.learn(200, callback=callbacks)
    assert sorted(p.name for p in tmp_path.glob("ckpt_*.zip")) == [
        "ckpt_100_steps.zip",
        "ckpt_200_steps.zip",
    ]
    mean, std = evaluate_policy(model, eval_env, n_eval_episodes=2)
    assert -2000 < mean < 0 and std >= 0


def test_bad_input() -> None:
    for cls in ALGOS:
        with pytest.raises(TypeError, match=f"{cls.__name__} does not support Discrete"):
            cls("MlpPolicy", "CartPole-v1")
        with pytest.raises(ValueError, match=r"tau must be a number in \[0, 1\], got -0.1"):
            cls("MlpPolicy", "Pendulum-v1", tau=-0.1)
        with pytest.raises(ValueError, match=r"action_noise of shape \(2,\) does not fit"):
            cls("MlpPolicy", "Pendulum-v1", action_noise=NormalActionNoise(np.zeros(2), np.ones(2)))
    with pytest.raises(TypeError, match="policy_delay"):  # DDPG's is fixed, as in SB3
        DDPG("MlpPolicy", "Pendulum-v1", policy_delay=2)
    with pytest.raises(ValueError, match="policy_delay must be a positive int, got 0"):
        TD3("MlpPolicy", "Pendulum-v1", policy_delay=0)
    with pytest.raises(ValueError, match=r"ent_coef must be .* got .auto_x."):
        SAC("MlpPolicy", "Pendulum-v1", ent_coef="auto_x")
    with pytest.raises(ValueError, match=r"ent_coef must be .* got -1"):
        SAC("MlpPolicy", "Pendulum-v1", ent_coef=-1)
    with pytest.raises(TypeError, match="action_noise must be"):
        TD3("MlpPolicy", "Pendulum-v1", action_noise=0.1)
    with pytest.raises(TypeError, match="sde_sample_freq must be an int"):
        SAC("MlpPolicy", "Pendulum-v1", use_sde=True, sde_sample_freq=2.5)
    with pytest.raises(ValueError, match="net_arch must be"):
        SAC("MlpPolicy", "Pendulum-v1", policy_kwargs={"net_arch": "big"})
    with pytest.raises(TypeError, match=r"unexpected keys \['ortho_init'\]"):
        TD3("MlpPolicy", "Pendulum-v1", policy_kwargs={"ortho_init": True})


def test_image_observations_train_on_the_torch_learner() -> None:
    model = SAC(
        "CnnPolicy",
        Toy(obs="image", action="box"),
        learning_starts=10,
        batch_size=8,
        buffer_size=200,
        seed=0,
        policy_kwargs={"net_arch": [16]},
    )
    assert isinstance(model.learner, TorchLearner)
    before = copy.deepcopy(model.critic_target.state_dict())
    model.learn(30)
    after = model.critic_target.state_dict()
    assert any(not torch.equal(before[k], after[k]) for k in before)  # targets move, CNN too
    assert any(not torch.equal(before[k], after[k]) for k in before if "features_extractor" in k)


@pytest.mark.slow
@pytest.mark.parametrize("cls", [SAC, TD3])
def test_pendulum_is_learned(cls: Any) -> None:
    kwargs: dict[str, Any] = dict(learning_rate=1e-3, seed=0)
    if cls is TD3:
        kwargs["action_noise"] = NormalActionNoise(np.zeros(1), np.full(1, 0.1))
    model = cls("MlpPolicy", "Pendulum-v1", **kwargs)
    model.learn(8000)
    mean, _ = evaluate_policy(model, gym.make("Pendulum-v1"), n_eval_episodes=10)
    assert mean > -400  # random: about -1200
