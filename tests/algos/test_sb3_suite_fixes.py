"""What SB3's own test suite (``tests/compat/sb3_suite.py``) found, each side by side with
stable-baselines3: action noise that broadcasts onto the action space, ``VectorizedActionNoise
.noises`` checked when set, ``evaluate_policy``'s callback locals (``observations`` and
``new_observations``), ``from ... import HER``'s ImportError, ``load_replay_buffer`` after
``del model.replay_buffer``, SB3's test envs with a ``Discrete`` action space not starting at
0, ``device="cuda"`` on a machine without CUDA, SAC's actor and critics called as modules,
SB3's words for DQN's target-interval warning and for a file that is no zip, and a
multi-dimensional ``MultiBinary`` action space (SB3 asserts)."""

from __future__ import annotations

import importlib.util
import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from tests.raised import raised

import palaestra
from palaestra import spaces
from palaestra.algos import DQN, TD3
from palaestra.algos.action_noise import (
    NormalActionNoise,
    OrnsteinUhlenbeckActionNoise,
    VectorizedActionNoise,
)
from palaestra.algos.envs import BitFlippingEnv, FakeImageEnv
from palaestra.algos.evaluation import evaluate_policy
from palaestra.error import InvalidAction
from palaestra.vec_env import DummyVecEnv

HAS_SB3 = importlib.util.find_spec("stable_baselines3") is not None
pytestmark = pytest.mark.skipif(not HAS_SB3, reason="stable-baselines3 (dev dependency) missing")


# -- action noise ------------------------------------------------------------------------------
def test_action_noise_of_one_dimension_is_added_to_every_action_dimension() -> None:
    """SB3's HER tests give ``NormalActionNoise(np.zeros(1), ...)`` on a 10-dim Box: numpy
    broadcasting adds the one draw to every dimension. The stored (scaled) actions minus the
    deterministic policy's are one value per step on both sides."""
    from stable_baselines3 import TD3 as SB3TD3
    from stable_baselines3.common.envs import BitFlippingEnv as SB3BitFlippingEnv
    from stable_baselines3.common.noise import NormalActionNoise as SB3Noise

    cases = [
        (TD3, NormalActionNoise, BitFlippingEnv),
        (SB3TD3, SB3Noise, SB3BitFlippingEnv),
    ]
    for algo, noise_class, env_class in cases:
        env = env_class(n_bits=10, continuous=True, max_steps=10)
        noise = noise_class(np.zeros(1), 0.1 * np.ones(1))
        model = algo(
            "MultiInputPolicy", env, action_noise=noise, learning_starts=0,
            train_freq=(100, "step"), seed=0,
        )  # fmt: skip
        model.learn(6)
        buffer = model.replay_buffer
        observations = {key: value[:6, 0] for key, value in buffer.observations.items()}
        stored = np.asarray(buffer.actions[:6, 0], dtype=np.float64)
        planned = model.predict(observations, deterministic=True)[0].astype(np.float64)
        offsets = stored - planned
        inside = np.abs(stored) < 1.0  # not clipped at the bounds
        assert inside.sum(axis=1).min() >= 2, algo
        for row, keep in zip(offsets, inside, strict=True):
            np.testing.assert_allclose(row[keep], row[keep][0], atol=1e-5)
        assert np.abs(offsets[inside]).max() > 1e-3  # the noise was added


def test_action_noise_that_does_not_broadcast_is_a_value_error() -> None:
    env = BitFlippingEnv(n_bits=10, continuous=True)
    noise = NormalActionNoise(np.zeros(3), np.ones(3))
    with pytest.raises(ValueError) as info:
        TD3("MultiInputPolicy", env, action_noise=noise)
    assert str(info.value) == (
        "action_noise of shape (3,) does not fit the action space Box(-1.0, 1.0, (10,), "
        "float32) (expected (10,) or a shape that broadcasts to it, or (n_envs, *(10,)) for "
        "VectorizedActionNoise)"
    )


def test_vectorized_action_noise_checks_noises_when_set() -> None:
    """SB3's test_vec_noise: the setter takes ``n_envs`` noises of the base noise's type and
    resets them; a wrong count is a ``ValueError`` here (SB3: ``AssertionError``)."""
    from stable_baselines3.common.noise import OrnsteinUhlenbeckActionNoise as SB3OU
    from stable_baselines3.common.noise import VectorizedActionNoise as SB3Vec

    for vec_class, ou_class in (
        (VectorizedActionNoise, OrnsteinUhlenbeckActionNoise),
        (SB3Vec, SB3OU),
    ):
        base = ou_class(np.zeros(2), 0.4 * np.ones(2))
        vec = vec_class(base, 3)
        assert type(raised(lambda vec=vec: setattr(vec, "noises", None))) is TypeError
        wrong_type = raised(lambda vec=vec: setattr(vec, "noises", [None] * 3))
        assert type(wrong_type) is ValueError
        moved = ou_class(np.zeros(2), 0.4 * np.ones(2))
        moved()
        assert np.any(moved.noise_prev != 0)
        vec.noises = [moved, ou_class(np.zeros(2), np.ones(2)), base]
        assert vec.noises[0] is moved and np.all(moved.noise_prev == 0)  # reset
        assert len(vec.noises) == 3
    ours_base = OrnsteinUhlenbeckActionNoise(np.zeros(2), np.ones(2))
    ours = raised(lambda: setattr(VectorizedActionNoise(ours_base, 3), "noises", []))
    assert type(ours) is ValueError
    assert str(ours) == "Expected a list of 3 ActionNoises, found 0."
    theirs = raised(lambda: setattr(SB3Vec(SB3OU(np.zeros(2), np.ones(2)), 3), "noises", []))
    assert type(theirs) is AssertionError


# -- evaluate_policy ---------------------------------------------------------------------------
def test_evaluate_policy_callback_sees_the_observations_before_and_after_the_step() -> None:
    """SB3 2.x's locals: ``observations`` were acted on, ``new_observations`` the step gave."""
    import gymnasium
    from stable_baselines3 import A2C as SB3A2C
    from stable_baselines3.common.evaluation import evaluate_policy as sb3_evaluate
    from stable_baselines3.common.vec_env import DummyVecEnv as SB3DummyVecEnv

    import palaestra
    from palaestra.algos import A2C

    cases = [
        (A2C, evaluate_policy, lambda: DummyVecEnv([lambda: palaestra.make("Pendulum-v1")])),
        (SB3A2C, sb3_evaluate, lambda: SB3DummyVecEnv([lambda: gymnasium.make("Pendulum-v1")])),
    ]
    for algo, evaluate, make in cases:
        model = algo("MlpPolicy", "Pendulum-v1", seed=0)
        seen: list[tuple[np.ndarray, np.ndarray]] = []

        def callback(locals_: dict[str, Any], _: dict[str, Any], seen: list = seen) -> None:
            seen.append((locals_["observations"].copy(), locals_["new_observations"].copy()))

        env = make()
        env.seed(3)
        evaluate(model, env, 1, callback=callback, warn=False)
        assert len(seen) == 200
        env.seed(3)
        np.testing.assert_array_equal(seen[0][0], env.reset())
        for (_, after), (before, _) in itertools.pairwise(seen):
            np.testing.assert_array_equal(after, before)
        assert not np.allclose(seen[0][0], seen[0][1])


# -- HER ---------------------------------------------------------------------------------------
def test_importing_her_names_its_replacement() -> None:
    """SB3 1.x's ``HER`` class is an ImportError pointing at the docs: SB3 2.x raises it when
    ``HER`` is called, palaestra already at the import."""
    for module in ("palaestra.algos", "stable_baselines3"):
        with pytest.raises(ImportError) as info:
            exec(f"from {module} import HER\nHER('MlpPolicy')")  # SB3's test_import_error
        assert "documentation" in str(info.value)
        assert "HerReplayBuffer" in str(info.value)
    with pytest.raises(ImportError, match="replay_buffer_class=HerReplayBuffer"):
        from palaestra.algos import HER  # noqa: F401


def test_load_replay_buffer_after_deleting_the_attribute(tmp_path: Path) -> None:
    """SB3's test_save_load_replay_buffer deletes ``model.replay_buffer`` before loading."""
    model = DQN("MlpPolicy", "CartPole-v1", buffer_size=500, learning_starts=50, seed=0)
    model.learn(80)
    old = model.replay_buffer
    assert old is not None
    model.save_replay_buffer(tmp_path / "buffer.zip")
    del model.replay_buffer
    with pytest.raises(AttributeError):
        model.replay_buffer  # noqa: B018
    model.load_replay_buffer(tmp_path / "buffer.zip")
    assert model.replay_buffer is not old and model.replay_buffer.pos == old.pos == 80
    np.testing.assert_array_equal(model.replay_buffer.observations, old.observations)
    np.testing.assert_array_equal(model.replay_buffer.actions, old.actions)


# -- SB3's test envs ---------------------------------------------------------------------------
def test_test_env_steps_a_discrete_space_that_does_not_start_at_zero() -> None:
    """SB3's test_non_default_action_spaces gives FakeImageEnv ``Discrete(3, start=-1)``."""
    from stable_baselines3.common.envs import FakeImageEnv as SB3FakeImageEnv

    for env in (FakeImageEnv(discrete=False), SB3FakeImageEnv(discrete=False)):
        env.action_space = spaces.Discrete(3, start=-1)
        env.reset(seed=0)
        for action in (-1, 0, 1, np.int64(-1)):
            env.step(action)
    env = FakeImageEnv(discrete=False)
    env.action_space = spaces.Discrete(3, start=-1)
    env.reset(seed=0)
    for bad in (2, np.int64(-2)):
        with pytest.raises(InvalidAction, match="Discrete"):
            env.step(bad)


# -- device ------------------------------------------------------------------------------------
@pytest.mark.skipif(torch.cuda.is_available(), reason="checks the fallback of a CPU-only machine")
def test_cuda_device_without_cuda_is_the_cpu(tmp_path: Path) -> None:
    """SB3's ``get_device``: ``device="cuda"`` on a machine without CUDA runs on the CPU (SB3's
    test_save_load loads with ``device="cuda"`` everywhere); a policy file loads likewise."""
    from stable_baselines3 import PPO as SB3PPO

    from palaestra.algos import PPO
    from palaestra.algos.policies import ActorCriticPolicy

    for algo in (PPO, SB3PPO):
        model = algo("MlpPolicy", "CartPole-v1", device="cuda", n_steps=64, batch_size=32)
        assert model.device == torch.device("cpu") and model.policy.device.type == "cpu"
        model.learn(64)
        model.save(tmp_path / "model.zip")
        loaded = algo.load(tmp_path / "model.zip", device="cuda")
        assert loaded.device == torch.device("cpu")
    model = PPO(ActorCriticPolicy, "CartPole-v1", n_steps=64, batch_size=32)
    model.policy.save(tmp_path / "policy.zip")
    policy = ActorCriticPolicy.load(tmp_path / "policy.zip", device="cuda")
    assert policy.device.type == "cpu"


# -- warnings ----------------------------------------------------------------------------------
def test_dqn_warns_with_sb3s_words_when_envs_exceed_the_target_interval() -> None:
    from stable_baselines3 import DQN as SB3DQN
    from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env

    from palaestra.vec_env import make_vec_env

    messages = []
    for algo, make in ((DQN, make_vec_env), (SB3DQN, sb3_make_vec_env)):
        with pytest.warns(UserWarning, match="The number of environments used is greater") as got:
            algo(
                "MlpPolicy",
                make("CartPole-v1", n_envs=2),
                buffer_size=100,
                target_update_interval=1,
            )
        messages.append([str(w.message) for w in got if "number of environments" in str(w.message)])
    assert (
        messages[0]
        == messages[1]
        == [
            "The number of environments used is greater than the target network update interval "
            "(2 > 1), therefore the target network will be updated after each call to env.step() "
            "which corresponds to 2 steps."
        ]
    )


# -- SAC's and TD3's modules called as SB3's -------------------------------------------------
@pytest.mark.parametrize("use_sde", [False, True])
def test_sac_actor_and_critic_forward_equal_sb3s_for_the_same_weights(use_sde: bool) -> None:
    """SB3's test_infinite_horizon calls ``model.critic(obs, model.actor(obs))``; its
    test_state_dependent_noise calls ``model.policy.actor.get_std()``."""
    from stable_baselines3 import SAC as SB3SAC

    from palaestra.algos import SAC

    kwargs: dict[str, Any] = dict(policy_kwargs=dict(net_arch=[8]), use_sde=use_sde, seed=0)
    ours, theirs = (
        SAC("MlpPolicy", "Pendulum-v1", **kwargs),
        SB3SAC("MlpPolicy", "Pendulum-v1", **kwargs),
    )
    for mine, other in ((ours.actor, theirs.actor), (ours.critic, theirs.critic)):
        mine.load_state_dict(other.state_dict())
    obs = torch.as_tensor(np.random.default_rng(0).normal(size=(5, 3)), dtype=torch.float32)
    with torch.no_grad():
        action = ours.actor(obs, deterministic=True)
        np.testing.assert_allclose(action, theirs.actor(obs, deterministic=True), atol=1e-6)
        assert ours.actor(obs).shape == (5, 1)
        q_ours, q_theirs = ours.critic(obs, action), theirs.critic(obs, action)
        assert len(q_ours) == len(q_theirs) == 2
        for a, b in zip(q_ours, q_theirs, strict=True):
            np.testing.assert_allclose(a, b, atol=1e-6)
        np.testing.assert_allclose(
            ours.critic.q1_forward(obs, action), theirs.critic.q1_forward(obs, action), atol=1e-6
        )
    if use_sde:
        np.testing.assert_allclose(
            ours.policy.actor.get_std().detach(), theirs.policy.actor.get_std().detach(), atol=1e-6
        )
    else:
        with pytest.raises(ValueError, match=r"get_std\(\) is only available when using gSDE"):
            ours.policy.actor.get_std()


def test_loading_a_file_that_is_no_zip_says_so_in_sb3s_words(tmp_path: Path) -> None:
    from stable_baselines3 import PPO as SB3PPO

    from palaestra.algos import PPO

    bad = tmp_path / "not_a_zip.zip"
    bad.write_text("this is not a zip file")
    for algo in (PPO, SB3PPO):
        with pytest.raises(ValueError, match="wasn't a zip-file"):
            algo.load(str(bad))
    with pytest.raises(ValueError) as info:
        PPO.load(str(bad))
    assert str(info.value) == (
        f"{bad} is corrupt or not a palaestra model file (it wasn't a zip-file: File is not a "
        "zip file)"
    )


class _MultiBinaryGrid(palaestra.Env):  # type: ignore[type-arg]
    """Reward: how many of the six bits of the (2, 3) action are set."""

    observation_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
    action_space = spaces.MultiBinary([2, 3])

    def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[Any, dict]:
        super().reset(seed=seed)
        return np.zeros(2, np.float32), {}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        assert self.action_space.contains(action), action
        return np.zeros(2, np.float32), float(np.sum(action)), False, False, {}


def test_a2c_acts_on_a_multi_dimensional_multi_binary_space() -> None:
    """SB3 asserts ("Multi-dimensional MultiBinary(...) action space is not supported");
    palaestra's head takes the flattened bits and acts in the space's shape."""
    from palaestra.algos import A2C

    model = A2C("MlpPolicy", _MultiBinaryGrid(), n_steps=8, seed=0).learn(32)
    action, _ = model.predict(np.zeros(2, np.float32))
    assert action.shape == (2, 3) and model.action_space.contains(action.astype(np.int8))
