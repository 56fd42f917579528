"""DQN/PPO construction, predict's shape rules, every space they support, and bad input."""

from __future__ import annotations

import numpy as np
import pytest

import palaestra as gym
from palaestra import algos
from palaestra.algos import DQN, PPO
from palaestra.runs.algorithms import ALGO_CLASSES
from palaestra.vec_env import DummyVecEnv, make_vec_env

from .toys import Toy

SMALL_PPO = {"n_steps": 16, "batch_size": 8, "n_epochs": 2, "seed": 0}
SMALL_DQN = {"learning_starts": 8, "batch_size": 8, "buffer_size": 200, "seed": 0}


def test_defaults_match_sb3() -> None:
    import inspect

    import stable_baselines3 as sb3

    for ours, theirs in [(DQN, sb3.DQN), (PPO, sb3.PPO)]:
        mine = inspect.signature(ours.__init__).parameters
        ref = inspect.signature(theirs.__init__).parameters
        for name, param in ref.items():
            if name in ("self", "policy", "env") or param.default is inspect.Parameter.empty:
                continue
            assert name in mine, f"{ours.__name__} lacks {name}"
            assert mine[name].default == param.default, (ours.__name__, name)


def test_predict_shapes_single_and_batched() -> None:
    model = DQN("MlpPolicy", "CartPole-v1", seed=0)
    obs, _ = gym.make("CartPole-v1").reset(seed=0)
    action, state = model.predict(obs, deterministic=True)
    assert action.shape == () and state is None and action.dtype == np.int64
    actions, _ = model.predict(np.stack([obs] * 5), deterministic=True)
    assert actions.shape == (5,)
    with pytest.raises(ValueError, match="Unexpected observation shape"):
        model.predict(np.zeros(3))
    with pytest.raises(ValueError, match="mixing Gym API"):
        model.predict(gym.make("CartPole-v1").reset())
    ppo = PPO("MlpPolicy", Toy(action="box"), **SMALL_PPO)
    a, _ = ppo.predict(np.zeros(3, np.float32))
    assert a.shape == (2,) and np.all(np.abs(a) <= 1)  # clipped to the Box
    a, _ = ppo.predict(np.zeros((4, 3), np.float32))
    assert a.shape == (4, 2)


@pytest.mark.parametrize("action", ["discrete", "box", "multidiscrete", "multibinary"])
def test_ppo_runs_on_every_action_space(action: str) -> None:
    model = PPO("MlpPolicy", Toy(action=action), **SMALL_PPO).learn(32)
    assert model.num_timesteps == 32
    a, _ = model.predict(np.zeros(3, np.float32), deterministic=True)
    assert model.action_space.contains(a.astype(model.action_space.dtype))


@pytest.mark.parametrize("obs", ["image", "image_chw"])
def test_cnn_policies(obs: str) -> None:
    dqn = DQN("CnnPolicy", Toy(obs=obs), **SMALL_DQN).learn(24)
    ppo = PPO("CnnPolicy", Toy(obs=obs), **SMALL_PPO).learn(16)
    frame = Toy(obs=obs).reset(seed=0)[0]
    assert dqn.predict(frame)[0].shape == () and ppo.predict(frame[None])[0].shape == (1,)


def test_multi_input_policy() -> None:
    ppo = PPO("MultiInputPolicy", Toy(obs="dict"), **SMALL_PPO).learn(16)
    dqn = DQN("MultiInputPolicy", Toy(obs="dict"), **SMALL_DQN).learn(24)
    obs = Toy(obs="dict").reset(seed=1)[0]
    assert ppo.predict(obs)[0].shape == () and dqn.predict(obs)[0].shape == ()


def test_any_number_of_envs() -> None:
    venv = make_vec_env("CartPole-v1", n_envs=3, seed=0)
    dqn = DQN("MlpPolicy", venv, **SMALL_DQN).learn(60)
    assert dqn.num_timesteps >= 60 and dqn.replay_buffer is not None
    ppo = PPO("MlpPolicy", DummyVecEnv([lambda: Toy()] * 2), **SMALL_PPO).learn(64)
    assert ppo.num_timesteps == 64


def test_bad_input_errors() -> None:
    with pytest.raises(ValueError, match="Policy 'MlpPolicyy' unknown"):
        PPO("MlpPolicyy", "CartPole-v1")
    with pytest.raises(TypeError, match="DQN does not support"):
        DQN("MlpPolicy", "Pendulum-v1")
    model = PPO("MlpPolicy", "CartPole-v1", **SMALL_PPO)
    for bad in (0, -5):
        with pytest.raises(ValueError, match="total_timesteps must be positive"):
            model.learn(bad)
    with pytest.raises(TypeError, match="total_timesteps"):
        model.learn(1e4)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="Observation spaces do not match"):
        model.set_env(gym.make("MountainCar-v0"))
    with pytest.raises(ValueError, match="Action spaces do not match"):
        PPO("MlpPolicy", Toy(), **SMALL_PPO).set_env(Toy(action="box"))
    with pytest.raises(ValueError, match="batch_size"):
        PPO("MlpPolicy", "CartPole-v1", batch_size=1)
    with pytest.raises(ValueError, match="clip_range_vf"):
        PPO("MlpPolicy", "CartPole-v1", clip_range_vf=0.0)
    with pytest.raises(TypeError, match="env must be"):
        DQN("MlpPolicy", 42)


@pytest.mark.parametrize("name", sorted(ALGO_CLASSES.values()))
def test_building_without_an_env_is_refused_by_name(name: str) -> None:
    """env=None is SB3's way to load into a model later; building its networks needs an env."""
    cls = getattr(algos, name)
    with pytest.raises(ValueError, match=rf"^{name} needs an env \(an id string, an Env"):
        cls("MlpPolicy", None)
    model = cls("MlpPolicy", None, _init_setup_model=False)  # allowed: nothing is built
    assert model.env is None


def test_set_env_and_get_env() -> None:
    model = PPO("MlpPolicy", "CartPole-v1", **SMALL_PPO)
    venv = make_vec_env("CartPole-v1", n_envs=2)
    model.set_env(venv)
    assert model.get_env() is venv and model.n_envs == 2
    model.learn(32)
    assert model.rollout_buffer.n_envs == 2


def test_callbacks_see_documented_locals_and_can_stop() -> None:
    seen = []

    def stop_after_ten(locals_: dict, globals_: dict) -> bool:
        seen.append(sorted(locals_))
        return len(seen) < 10

    model = DQN("MlpPolicy", "CartPole-v1", **SMALL_DQN).learn(1000, callback=stop_after_ten)
    assert model.num_timesteps == 10
    assert {"actions", "dones", "infos", "new_obs", "rewards", "total_timesteps"} <= set(seen[0])


def test_dqn_train_freq_variants() -> None:
    per_episode = DQN(
        "MlpPolicy", Toy(horizon=5), train_freq=(1, "episode"), gradient_steps=-1, **SMALL_DQN
    ).learn(30)
    # one update round per 5-step episode once learning starts: gradient_steps = steps collected
    assert per_episode._n_updates == 5 * (per_episode.num_timesteps // 5 - 1)
    with pytest.raises(ValueError, match="train_freq"):
        DQN("MlpPolicy", Toy(), train_freq=(2, "epoch"))


def test_ppo_target_kl_and_value_clipping(capsys: pytest.CaptureFixture[str]) -> None:
    model = PPO(
        "MlpPolicy",
        "CartPole-v1",
        target_kl=1e-9,
        clip_range_vf=0.2,
        verbose=1,
        learning_rate=1e-2,
        **SMALL_PPO,
    )
    model.learn(32)
    out = capsys.readouterr().out
    assert "Early stopping at step 0 due to reaching max kl" in out
    assert "clip_range_vf" in out and model._n_updates == 2  # one epoch per train() call
