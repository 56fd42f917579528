"""SB3's public policy surface (issue 26): ``model.policy.predict``/``obs_to_tensor``/
``is_vectorized_observation``/``device``/``set_training_mode``, evaluation mode when acting
and training mode only inside ``train()``, ``model.policy = ...`` (another policy, or
``torch.compile``'s wrapper), and a policy saved and loaded alone (no pickle; SB3's pickled
policy files refused unread). Each checked side by side with stable-baselines3 on the same
weights."""

from __future__ import annotations

import pickle
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from torch import nn

from palaestra import spaces
from palaestra.algos import DDPG, DQN, PPO, SAC, TD3
from palaestra.algos.callbacks import BaseCallback
from palaestra.algos.common.base_policy import BasePolicy
from palaestra.algos.common.model_io import ModelFileError
from palaestra.algos.networks import BaseFeaturesExtractor
from palaestra.algos.policies import BasePolicy as PublicBasePolicy
from palaestra.core import Env

sb3 = pytest.importorskip("stable_baselines3")

# Our state_dict key prefix -> SB3's, for the actor-critic (SAC/TD3 keys are SB3's already).
_PPO_KEYS = {
    "pi_net.": "mlp_extractor.policy_net.",
    "vf_net.": "mlp_extractor.value_net.",
    "action_head.net.": "action_net.",
    "action_head.log_std": "log_std",
    "value_head.": "value_net.",
}


def _sb3_state(algo: str, ours: nn.Module, theirs: nn.Module) -> dict[str, torch.Tensor]:
    """``ours``' weights under ``theirs``' keys."""
    state = {k: v for k, v in ours.state_dict().items() if not k.startswith("ent_coef")}
    if algo == "PPO":
        out = {}
        for key, value in state.items():
            prefix = next(p for p in _PPO_KEYS if key.startswith(p))
            out[_PPO_KEYS[prefix] + key[len(prefix) :]] = value
        return out
    if algo == "DQN":  # the same layers in the same order, SB3 names them q_net.q_net.i
        keys = list(theirs.state_dict())
        assert [v.shape for v in state.values()] == [theirs.state_dict()[k].shape for k in keys]
        return dict(zip(keys, state.values()))
    return state


CASES = [
    ("PPO", "CartPole-v1"),
    ("PPO", "Pendulum-v1"),
    ("DQN", "CartPole-v1"),
    ("SAC", "Pendulum-v1"),
    ("TD3", "Pendulum-v1"),
]
ARCH = {"net_arch": [16, 16]}


def _pair(algo: str, env_id: str) -> tuple[Any, Any]:
    ours = {"PPO": PPO, "DQN": DQN, "SAC": SAC, "TD3": TD3}[algo](
        "MlpPolicy", env_id, seed=1, policy_kwargs=dict(ARCH)
    )
    theirs = getattr(sb3, algo)("MlpPolicy", env_id, seed=2, policy_kwargs=dict(ARCH), device="cpu")
    theirs.policy.load_state_dict(_sb3_state(algo, ours.policy, theirs.policy))
    return ours, theirs


def _observations(space: spaces.Space[Any], n: int) -> np.ndarray:
    space.seed(0)
    return np.stack([space.sample() for _ in range(n)])


@pytest.mark.parametrize(("algo", "env_id"), CASES)
def test_policy_predict_equals_sb3_for_the_same_weights(algo: str, env_id: str) -> None:
    ours, theirs = _pair(algo, env_id)
    policy, their_policy = ours.policy, theirs.policy
    assert isinstance(policy, PublicBasePolicy) and PublicBasePolicy is BasePolicy
    obs = _observations(ours.observation_space, 5)
    for given in (obs, obs[0]):  # a batch, and one observation
        a, state = policy.predict(given, deterministic=True)
        b, their_state = their_policy.predict(given, deterministic=True)
        assert state is None and their_state is None
        assert a.shape == b.shape and a.dtype == b.dtype, (a.shape, b.shape, a.dtype, b.dtype)
        np.testing.assert_allclose(a, b, atol=1e-6)
        # the model's predict acts through its learner: the same actions
        np.testing.assert_allclose(ours.predict(given, deterministic=True)[0], a, atol=1e-6)
        assert policy.is_vectorized_observation(given) == their_policy.is_vectorized_observation(
            given
        )
        t, vec = policy.obs_to_tensor(given)
        u, their_vec = their_policy.obs_to_tensor(given)
        assert vec == their_vec and t.shape == u.shape and t.dtype == u.dtype
        state_in = (np.zeros(3),)
        assert policy.predict(given, state=state_in, episode_start=np.ones(1))[1] is state_in
    assert policy.device == their_policy.device == torch.device("cpu")
    sampled, _ = policy.predict(obs)  # stochastic: shape, dtype and bounds as SB3's
    their_sampled, _ = their_policy.predict(obs)
    assert sampled.shape == their_sampled.shape and sampled.dtype == their_sampled.dtype
    assert all(ours.action_space.contains(s) for s in sampled)
    if isinstance(ours.action_space, spaces.Box):
        scaled = np.array([[0.5]], dtype=np.float32)
        np.testing.assert_allclose(
            policy.unscale_action(scaled), their_policy.unscale_action(scaled)
        )
        np.testing.assert_allclose(policy.scale_action(scaled), their_policy.scale_action(scaled))


def test_policy_predict_refuses_what_sb3_refuses() -> None:
    ours, theirs = _pair("PPO", "CartPole-v1")
    obs = _observations(ours.observation_space, 1)[0]
    for policy in (ours.policy, theirs.policy):
        with pytest.raises(ValueError, match="mixing Gym API with SB3 VecEnv API"):
            policy.predict((obs, {}))
        with pytest.raises(ValueError, match="Unexpected observation shape"):
            policy.predict(np.zeros(7, np.float32))
    with pytest.raises(TypeError, match=r"needs a Box action space, got Discrete\(2\)"):
        ours.policy.unscale_action(np.zeros(1))


# -- evaluation mode when acting, training mode inside train() -------------------------------
PHASE = {"collecting": False}


def _extractor(base: type) -> type:
    """A features extractor with Dropout and BatchNorm (SB3's tests' case) that notes the
    mode of each forward, and whether it ran while collecting (between the callbacks'
    ``on_rollout_start`` and ``on_rollout_end``) or while training."""

    class ModeRecorder(base):  # type: ignore[misc, valid-type]
        seen: set[tuple[str, bool]] = set()

        def __init__(self, observation_space: Any, features_dim: int = 8) -> None:
            super().__init__(observation_space, features_dim)
            n = int(np.prod(observation_space.shape))
            self.net = nn.Sequential(
                nn.Flatten(),
                nn.Linear(n, features_dim),
                nn.BatchNorm1d(features_dim),
                nn.Dropout(0.5),
            )

        def forward(self, obs: torch.Tensor) -> torch.Tensor:
            phase = "collect" if PHASE["collecting"] else "train"
            ModeRecorder.seen.add((phase, self.training))
            return self.net(obs)

    return ModeRecorder


def _phases(base: type) -> Any:
    class Phases(base):  # type: ignore[misc, valid-type]
        def _on_rollout_start(self) -> None:
            PHASE["collecting"] = True

        def _on_rollout_end(self) -> None:
            PHASE["collecting"] = False

        def _on_step(self) -> bool:
            return True

    return Phases()


MODE_CASES = [
    ("PPO", "CartPole-v1", {"n_steps": 32, "batch_size": 16, "n_epochs": 1}),
    ("DQN", "CartPole-v1", {"learning_starts": 10, "batch_size": 8, "train_freq": 4}),
    ("SAC", "Pendulum-v1", {"learning_starts": 10, "batch_size": 8}),
    ("TD3", "Pendulum-v1", {"learning_starts": 10, "batch_size": 8}),
]


@pytest.mark.parametrize(("algo", "env_id", "kwargs"), MODE_CASES)
def test_dropout_and_batchnorm_follow_sb3s_modes(
    algo: str, env_id: str, kwargs: dict[str, Any]
) -> None:
    seen = []
    for lib in (None, sb3):
        if lib is sb3:
            cls, extra = getattr(sb3, algo), {"device": "cpu"}
            recorder = _extractor(sb3.common.torch_layers.BaseFeaturesExtractor)
            phases = _phases(sb3.common.callbacks.BaseCallback)
        else:
            cls, extra = {"PPO": PPO, "DQN": DQN, "SAC": SAC, "TD3": TD3}[algo], {}
            recorder, phases = _extractor(BaseFeaturesExtractor), _phases(BaseCallback)
        model = cls(
            "MlpPolicy",
            env_id,
            seed=0,
            policy_kwargs={"features_extractor_class": recorder, "net_arch": [8]},
            **kwargs,
            **extra,
        )
        model.learn(64, callback=phases)
        seen.append(recorder.seen)
        # acting (one env: a batch of one) in evaluation mode, updates in training mode
        assert ("collect", True) not in recorder.seen and ("train", True) in recorder.seen
        obs = _observations(model.observation_space, 1)[0]
        # BatchNorm on its running statistics takes one observation; dropout is off
        first = model.predict(obs, deterministic=True)[0]
        assert model.policy.training is False
        for _ in range(5):
            np.testing.assert_array_equal(model.predict(obs, deterministic=True)[0], first)
            np.testing.assert_array_equal(model.policy.predict(obs, deterministic=True)[0], first)
        model.policy.set_training_mode(True)
        assert model.policy.training is True
        model.policy.predict(obs)  # switches back, as SB3's
        assert model.policy.training is False
    assert seen[0] == seen[1]


def test_target_networks_stay_in_evaluation_mode() -> None:
    for model, targets in (
        (DQN("MlpPolicy", "CartPole-v1"), ["q_net_target"]),
        (SAC("MlpPolicy", "Pendulum-v1"), ["critic_target"]),
        (TD3("MlpPolicy", "Pendulum-v1"), ["actor_target", "critic_target"]),
    ):
        model.policy.set_training_mode(True)
        assert all(not getattr(model.policy, t).training for t in targets)
        assert model.policy.critic.training if hasattr(model.policy, "critic") else True


# -- model.policy = ... -----------------------------------------------------------------------
@pytest.mark.parametrize("backend", ["auto", "torch"])
@pytest.mark.parametrize(
    ("cls", "env_id"),
    [
        (PPO, "CartPole-v1"),
        (DQN, "CartPole-v1"),
        (SAC, "Pendulum-v1"),
        (TD3, "Pendulum-v1"),
        (DDPG, "Pendulum-v1"),
    ],
)
def test_assigning_another_policy_changes_predict(cls: Any, env_id: str, backend: str) -> None:
    kwargs = {"policy_kwargs": {"net_arch": [16], "backend": backend}}
    a, b = cls("MlpPolicy", env_id, seed=1, **kwargs), cls("MlpPolicy", env_id, seed=2, **kwargs)
    obs = _observations(a.observation_space, 20)
    before = a.predict(obs, deterministic=True)[0]
    wanted = b.predict(obs, deterministic=True)[0]
    assert not np.allclose(before, wanted)
    a.policy = b.policy
    assert a.policy is b.policy
    np.testing.assert_allclose(a.predict(obs, deterministic=True)[0], wanted, atol=1e-6)
    # a trains the policy it was given (SB3: model.policy is that object)
    learn = {"n_steps": 16} if cls is PPO else {}
    for name, value in learn.items():
        setattr(a, name, value)
    weights = [p.detach().clone() for p in b.policy.parameters()]
    a.learn(200 if cls is not PPO else 256)
    assert any(not torch.equal(w, p) for w, p in zip(weights, b.policy.parameters()))
    np.testing.assert_allclose(
        a.predict(obs, deterministic=True)[0],
        a.policy.predict(obs, deterministic=True)[0],
        atol=1e-5,
    )


def test_assigning_a_policy_is_checked() -> None:
    model = PPO("MlpPolicy", "CartPole-v1", policy_kwargs={"net_arch": [8]})
    with pytest.raises(TypeError, match=r"PPO.policy must be a ActorCritic.*got Linear"):
        model.policy = nn.Linear(4, 2)
    other = PPO("MlpPolicy", "Acrobot-v1", policy_kwargs={"net_arch": [8]})
    with pytest.raises(ValueError, match=r"observation_space .* differs from the model's"):
        model.policy = other.policy
    dqn = DQN("MlpPolicy", "CartPole-v1")
    with pytest.raises(TypeError, match=r"DQN\.policy must be a DQNPolicy"):
        dqn.policy = model.policy


def test_torch_compile_of_the_policy_is_accepted(tmp_path: Path) -> None:
    """SB3's documented ``model.policy = th.compile(model.policy)``."""
    model = PPO("MlpPolicy", "CartPole-v1", seed=0, policy_kwargs={"net_arch": [8]})
    obs = _observations(model.observation_space, 10)
    before = model.predict(obs, deterministic=True)[0]
    compiled = torch.compile(model.policy)
    model.policy = compiled
    assert model.policy is compiled
    np.testing.assert_array_equal(model.predict(obs, deterministic=True)[0], before)
    model.save(tmp_path / "m")
    loaded = PPO.load(tmp_path / "m")
    np.testing.assert_array_equal(loaded.predict(obs, deterministic=True)[0], before)
    model.set_parameters(model.get_parameters())
    model.learn(64)


# -- a policy saved and loaded alone ---------------------------------------------------------
@pytest.mark.parametrize(("algo", "env_id"), [*CASES, ("DDPG", "Pendulum-v1")])
def test_policy_save_load_round_trip(tmp_path: Path, algo: str, env_id: str) -> None:
    cls = {"PPO": PPO, "DQN": DQN, "SAC": SAC, "TD3": TD3, "DDPG": DDPG}[algo]
    model = cls("MlpPolicy", env_id, seed=3, policy_kwargs={"net_arch": [16, 8]})
    obs = _observations(model.observation_space, 6)
    path = tmp_path / "policy.zip"
    model.policy.save(path)
    with zipfile.ZipFile(path) as zf:
        names = zf.namelist()
        assert "palaestra.json" in names and not any(n.endswith(".pkl") for n in names)
    for loader in (type(model.policy), BasePolicy):
        loaded = loader.load(path)
        assert type(loaded) is type(model.policy)
        a = loaded.predict(obs, deterministic=True)[0]
        np.testing.assert_array_equal(a, model.policy.predict(obs, deterministic=True)[0])
        assert loaded.observation_space == model.observation_space
        assert loaded.action_space == model.action_space
        assert loaded.net_arch == [16, 8]


def test_policy_file_of_another_class_is_refused(tmp_path: Path) -> None:
    PPO("MlpPolicy", "CartPole-v1").policy.save(tmp_path / "ppo")
    from palaestra.algos.dqn import DQNPolicy

    with pytest.raises(ModelFileError, match=r"ActorCritic' policy, not a .*DQNPolicy"):
        DQNPolicy.load(tmp_path / "ppo.zip")
    model = DQN("MlpPolicy", "CartPole-v1")
    model.save(tmp_path / "model")
    with pytest.raises(ModelFileError, match="palaestra 'model' file, not a policy file"):
        DQNPolicy.load(tmp_path / "model.zip")


class _Marker:
    """Unpickling this creates a file: the proof that a loader unpickled."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __reduce__(self) -> Any:
        return (Path.touch, (self.path,))


def test_sb3_policy_files_are_refused_unread(tmp_path: Path) -> None:
    theirs = sb3.PPO("MlpPolicy", "CartPole-v1", device="cpu")
    theirs.policy.save(tmp_path / "sb3_policy.pth")
    from palaestra.algos.policies import ActorCriticPolicy

    for loader in (ActorCriticPolicy, BasePolicy):
        with pytest.raises(ModelFileError, match=r"PyTorch pickle .*palaestra.compat.from_sb3"):
            loader.load(tmp_path / "sb3_policy.pth")
    marker = tmp_path / "unpickled"
    torch.save({"data": _Marker(marker)}, tmp_path / "evil.pth")
    torch.save(
        {"data": _Marker(marker)}, tmp_path / "legacy.pth", _use_new_zipfile_serialization=False
    )
    (tmp_path / "plain.pkl").write_bytes(pickle.dumps(_Marker(marker)))
    for name in ("evil.pth", "legacy.pth", "plain.pkl"):
        with pytest.raises(ModelFileError, match="PyTorch pickle"):
            BasePolicy.load(tmp_path / name)
    assert not marker.exists()


# -- float64 Box actions with Dict observations (SAC/TD3/DDPG) --------------------------------
class _Float64Dict(Env[Any, Any]):
    """Dict observations, a float64 Box action space (SB3's tests' case)."""

    def __init__(self) -> None:
        self.observation_space = spaces.Dict(
            {"pos": spaces.Box(-1, 1, (2,), np.float32), "vel": spaces.Box(-1, 1, (1,), np.float64)}
        )
        self.action_space = spaces.Box(-2.0, 2.0, (2,), np.float64)
        self.t = 0

    def reset(self, *, seed: int | None = None, options: Any = None) -> Any:
        super().reset(seed=seed)
        self.t = 0
        return self.observation_space.sample(), {}

    def step(self, action: Any) -> Any:
        assert np.asarray(action).dtype == np.float64
        self.t += 1
        reward = -float(np.sum(np.square(action)))
        return self.observation_space.sample(), reward, False, self.t >= 20, {}


@pytest.mark.parametrize("cls", [SAC, TD3, DDPG])
def test_float64_actions_with_dict_observations_train(cls: Any) -> None:
    model = cls(
        "MultiInputPolicy",
        _Float64Dict(),
        learning_starts=16,
        batch_size=8,
        policy_kwargs={"net_arch": [8]},
        seed=0,
    )
    model.learn(48)
    obs = model.env.reset()
    actions = model.predict(obs, deterministic=True)[0]
    assert actions.dtype == np.float64 and actions.shape == (1, 2)  # SB3's dtype and shape
    assert model.policy.predict(obs, deterministic=True)[0].dtype == np.float64


def test_parameters_vector_round_trip_as_sb3() -> None:
    ours, theirs = _pair("PPO", "Pendulum-v1")
    vector = ours.policy.parameters_to_vector()
    assert vector.shape == theirs.policy.parameters_to_vector().shape
    assert vector.dtype == theirs.policy.parameters_to_vector().dtype
    ours.policy.load_from_vector(np.zeros_like(vector))
    assert not ours.policy.parameters_to_vector().any()
    assert not ours.predict(np.zeros(3, np.float32), deterministic=True)[0].any()  # the learner too
    ours.policy.load_from_vector(vector)
    np.testing.assert_array_equal(ours.policy.parameters_to_vector(), vector)
    with pytest.raises(
        ValueError, match=rf"expected a vector of {vector.size} values, got shape \(3,\)"
    ):
        ours.policy.load_from_vector(np.zeros(3))


def test_sb3s_save_load_policy_recipe(tmp_path: Path) -> None:
    """SB3's ``test_save_load_policy``: random weights set through ``model.policy``, the
    policy saved and loaded alone, the same deterministic actions."""
    for model in (
        SAC("MlpPolicy", "Pendulum-v1", policy_kwargs={"net_arch": [16]}, learning_starts=50),
        DQN("MlpPolicy", "CartPole-v1", policy_kwargs={"net_arch": [16]}, learning_starts=50),
    ):
        model.learn(100)
        obs = _observations(model.observation_space, 10)
        policy = model.policy
        policy.load_state_dict({k: torch.rand_like(v) for k, v in policy.state_dict().items()})
        params = {k: v.clone() for k, v in policy.state_dict().items()}
        selected = policy.predict(obs, deterministic=True)[0]
        np.testing.assert_allclose(model.predict(obs, deterministic=True)[0], selected, atol=1e-5)
        policy.save(tmp_path / "policy.pkl")  # SB3's test names it .pkl: it is not one here
        loaded = type(policy).load(tmp_path / "policy.pkl")
        for key, value in loaded.state_dict().items():
            assert torch.equal(value, params[key]), key
        np.testing.assert_allclose(loaded.predict(obs, deterministic=True)[0], selected, atol=1e-4)


@pytest.mark.parametrize("algo", ["DQN", "SAC", "TD3"])
@pytest.mark.parametrize("updates", [True, False], ids=["target-updated", "target-kept"])
def test_target_batch_norm_statistics_as_sb3(algo: str, updates: bool) -> None:
    """Target nets keep their running statistics in evaluation mode and take the online
    net's whole at each target update (SB3 copies them with tau 1.0)."""
    env_id = "CartPole-v1" if algo == "DQN" else "Pendulum-v1"
    kwargs: dict[str, Any] = {"learning_starts": 10, "batch_size": 8, "seed": 0}
    if algo == "DQN":
        kwargs |= {"target_update_interval": 4 if updates else 10**6, "tau": 1.0}
    elif algo == "SAC":
        # SB3 (and palaestra) update when gradient_step % interval == 0: with one gradient
        # step per train() that is every time, whatever the interval
        kwargs |= {"target_update_interval": 1 if updates else 10**6}
    else:
        kwargs |= {"policy_delay": 1 if updates else 10**6}
    target = {"DQN": "q_net_target", "SAC": "critic_target", "TD3": "critic_target"}[algo]
    changed = []
    for lib in ("ours", "sb3"):
        if lib == "sb3":
            cls, extra = getattr(sb3, algo), {"device": "cpu"}
            recorder = _extractor(sb3.common.torch_layers.BaseFeaturesExtractor)
        else:
            cls, extra = {"DQN": DQN, "SAC": SAC, "TD3": TD3}[algo], {}
            recorder = _extractor(BaseFeaturesExtractor)
        policy_kwargs = {"features_extractor_class": recorder, "net_arch": [8]}
        model = cls("MlpPolicy", env_id, policy_kwargs=policy_kwargs, **kwargs, **extra)
        stats = getattr(model.policy, target).features_extractor.net[2].running_mean
        before = stats.clone()
        model.learn(60)
        changed.append(not torch.equal(before, stats))
    expected = True if algo == "SAC" else updates
    assert changed == [expected, expected]
