"""SB3's "custom policy" guide runs on palaestra (issue 16): a ``BaseFeaturesExtractor``
subclass in ``policy_kwargs`` (PPO, A2C, DQN, SAC) and an ``ActorCriticPolicy`` subclass
overriding ``_build_mlp_extractor`` (PPO, A2C) train on the torch learner, chosen
automatically. The guide's classes are written once over either library's base classes and
built side by side with the installed SB3 (ported in spirit from SB3's
``tests/test_custom_policy.py``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from torch import nn

from palaestra import algos
from palaestra.algos import ModelFileError
from palaestra.algos.networks import BaseFeaturesExtractor
from palaestra.algos.policies import ActorCriticPolicy

from .toys import Toy

sb3 = pytest.importorskip("stable_baselines3")
sb3_layers = pytest.importorskip("stable_baselines3.common.torch_layers")
sb3_policies = pytest.importorskip("stable_baselines3.common.policies")
compat = pytest.importorskip("palaestra.compat")
gymnasium = pytest.importorskip("gymnasium")


def guide_classes(extractor_base: type, policy_base: type) -> dict[str, type]:
    """The guide's examples, over the given base classes (SB3's or palaestra's)."""

    class CustomCNN(extractor_base):  # type: ignore[misc,valid-type]
        """The guide's CNN: assumes CxHxW images, as SB3's VecTransposeImage provides."""

        def __init__(self, observation_space: Any, features_dim: int = 256) -> None:
            super().__init__(observation_space, features_dim)
            n_input_channels = observation_space.shape[0]
            self.cnn = nn.Sequential(
                nn.Conv2d(n_input_channels, 8, kernel_size=8, stride=4, padding=0),
                nn.ReLU(),
                nn.Conv2d(8, 16, kernel_size=4, stride=2, padding=0),
                nn.ReLU(),
                nn.Flatten(),
            )
            with torch.no_grad():
                sample = torch.as_tensor(observation_space.sample()[None]).float()
                n_flatten = self.cnn(sample).shape[1]
            self.linear = nn.Sequential(nn.Linear(n_flatten, features_dim), nn.ReLU())

        def forward(self, observations: torch.Tensor) -> torch.Tensor:
            return self.linear(self.cnn(observations))

    class CustomCombinedExtractor(extractor_base):  # type: ignore[misc,valid-type]
        """The guide's Dict extractor: sets ``_features_dim`` after ``__init__``."""

        def __init__(self, observation_space: Any) -> None:
            super().__init__(observation_space, features_dim=1)
            extractors: dict[str, nn.Module] = {}
            total = 0
            for key, subspace in observation_space.spaces.items():
                if key == "img":
                    extractors[key] = nn.Sequential(nn.MaxPool2d(4), nn.Flatten())
                    total += subspace.shape[1] // 4 * subspace.shape[2] // 4
                elif key == "vec":
                    extractors[key] = nn.Linear(subspace.shape[0], 16)
                    total += 16
            self.extractors = nn.ModuleDict(extractors)
            self._features_dim = total

        def forward(self, observations: Any) -> torch.Tensor:
            return torch.cat([net(observations[k]) for k, net in self.extractors.items()], dim=1)

    class CustomNetwork(nn.Module):
        """The guide's actor/critic body."""

        def __init__(
            self, feature_dim: int, last_layer_dim_pi: int = 64, last_layer_dim_vf: int = 64
        ):
            super().__init__()
            self.latent_dim_pi = last_layer_dim_pi
            self.latent_dim_vf = last_layer_dim_vf
            self.policy_net = nn.Sequential(nn.Linear(feature_dim, last_layer_dim_pi), nn.ReLU())
            self.value_net = nn.Sequential(nn.Linear(feature_dim, last_layer_dim_vf), nn.ReLU())

        def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            return self.forward_actor(features), self.forward_critic(features)

        def forward_actor(self, features: torch.Tensor) -> torch.Tensor:
            return self.policy_net(features)

        def forward_critic(self, features: torch.Tensor) -> torch.Tensor:
            return self.value_net(features)

    class CustomActorCriticPolicy(policy_base):  # type: ignore[misc,valid-type]
        def __init__(
            self,
            observation_space: Any,
            action_space: Any,
            lr_schedule: Any,
            *args: Any,
            **kwargs: Any,
        ):
            kwargs["ortho_init"] = False  # as the guide: no orthogonal init
            super().__init__(observation_space, action_space, lr_schedule, *args, **kwargs)

        def _build_mlp_extractor(self) -> None:
            self.mlp_extractor = CustomNetwork(self.features_dim)

    class TinyMlp(extractor_base):  # type: ignore[misc,valid-type]
        """A features extractor for vector observations (DQN, SAC)."""

        def __init__(self, observation_space: Any, features_dim: int = 32) -> None:
            super().__init__(observation_space, features_dim)
            width = int(np.prod(observation_space.shape))
            self.net = nn.Sequential(nn.Flatten(), nn.Linear(width, features_dim), nn.Tanh())

        def forward(self, observations: torch.Tensor) -> torch.Tensor:
            return self.net(observations)

    return {
        "CustomCNN": CustomCNN,
        "CustomCombinedExtractor": CustomCombinedExtractor,
        "CustomActorCriticPolicy": CustomActorCriticPolicy,
        "TinyMlp": TinyMlp,
    }


OURS = guide_classes(BaseFeaturesExtractor, ActorCriticPolicy)
THEIRS = guide_classes(sb3_layers.BaseFeaturesExtractor, sb3_policies.ActorCriticPolicy)


def _shapes(module: nn.Module) -> list[tuple[int, ...]]:
    return sorted(tuple(p.shape) for p in module.parameters())


def _rollout(algo: str, n_steps: int) -> dict[str, int]:
    """A short rollout (PPO: one minibatch of it)."""
    return {"n_steps": n_steps, **({"batch_size": n_steps} if algo == "PPO" else {})}


def _torch_learner(model: Any) -> None:
    assert model.learner.describe().startswith("torch"), model.learner.describe()


@pytest.mark.parametrize("algo", ["PPO", "A2C"])
def test_custom_cnn_on_channel_last_images(algo: str) -> None:
    # Toy("image") is HWC: palaestra shows the extractor CHW, as SB3's VecTransposeImage does
    kwargs = dict(
        features_extractor_class=OURS["CustomCNN"], features_extractor_kwargs=dict(features_dim=32)
    )
    model = getattr(algos, algo)(
        "CnnPolicy", Toy("image"), **_rollout(algo, 16), policy_kwargs=kwargs
    )
    model.learn(32)
    _torch_learner(model)
    theirs_kwargs = {**kwargs, "features_extractor_class": THEIRS["CustomCNN"]}
    theirs = getattr(sb3, algo)(
        "CnnPolicy",
        compat.to_gymnasium(Toy("image")),
        **_rollout(algo, 16),
        policy_kwargs=theirs_kwargs,
    )
    assert _shapes(model.policy.features_extractor) == _shapes(theirs.policy.features_extractor)
    assert model.policy.features_extractor.observation_space.shape == (1, 36, 36)
    action, _ = model.predict(Toy("image").observation_space.sample())
    assert action in model.action_space


def test_custom_combined_extractor_sets_features_dim() -> None:
    kwargs = dict(features_extractor_class=OURS["CustomCombinedExtractor"])
    model = algos.PPO(
        "MultiInputPolicy", Toy("dict"), n_steps=16, batch_size=16, policy_kwargs=kwargs
    )
    theirs = sb3.PPO(
        "MultiInputPolicy",
        compat.to_gymnasium(Toy("dict")),
        n_steps=16,
        batch_size=16,
        policy_kwargs=dict(features_extractor_class=THEIRS["CustomCombinedExtractor"]),
    )
    assert model.policy.features_dim == theirs.policy.features_dim == 9 * 9 + 16
    assert _shapes(model.policy) == sorted(
        s
        for s in _shapes(theirs.policy)
        if s != ()  # SB3's (unused) log_std-free parts alike
    )
    model.learn(32)
    _torch_learner(model)


@pytest.mark.parametrize("algo", ["PPO", "A2C"])
def test_custom_actor_critic_policy_trains(tmp_path: Path, algo: str) -> None:
    cls = OURS["CustomActorCriticPolicy"]
    model = getattr(algos, algo)(cls, "CartPole-v1", **_rollout(algo, 32), seed=0)
    theirs = getattr(sb3, algo)(
        THEIRS["CustomActorCriticPolicy"], "CartPole-v1", **_rollout(algo, 32)
    )
    assert type(model.policy.mlp_extractor).__name__ == "CustomNetwork"
    mine = {k: v.shape for k, v in model.policy.state_dict().items() if "mlp_extractor" in k}
    sb3s = {k: v.shape for k, v in theirs.policy.state_dict().items() if "mlp_extractor" in k}
    assert mine == sb3s
    assert sum(p.numel() for p in model.policy.parameters()) == sum(
        p.numel() for p in theirs.policy.parameters()
    )
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(128)
    _torch_learner(model)
    assert model.learner.describe().endswith("the policy is a custom CustomActorCriticPolicy)")
    after = list(model.policy.parameters())
    assert all(not torch.equal(a, b) for a, b in zip(before, after))
    # save and load: the class comes back through custom_objects only (no import by name)
    model.save(tmp_path / "custom")
    with pytest.raises(ModelFileError, match="custom_objects"):
        type(model).load(tmp_path / "custom")
    loaded = type(model).load(tmp_path / "custom", custom_objects={"CustomActorCriticPolicy": cls})
    assert isinstance(loaded.policy, cls)
    obs = np.random.default_rng(0).normal(size=(8, 4)).astype(np.float32)
    np.testing.assert_array_equal(
        model.predict(obs, deterministic=True)[0], loaded.predict(obs, deterministic=True)[0]
    )


def test_actor_critic_policy_itself_is_sb3s_mlp_policy() -> None:
    model = algos.PPO(ActorCriticPolicy, "CartPole-v1", n_steps=16, batch_size=16)
    theirs = sb3.PPO(sb3_policies.ActorCriticPolicy, "CartPole-v1", n_steps=16, batch_size=16)
    mine = {k: v.shape for k, v in model.policy.state_dict().items() if "mlp_extractor" in k}
    sb3s = {k: v.shape for k, v in theirs.policy.state_dict().items() if "mlp_extractor" in k}
    assert mine == sb3s and len(mine) == 8
    model.learn(16)


@pytest.mark.parametrize(("algo", "env_id"), [("DQN", "CartPole-v1"), ("SAC", "Pendulum-v1")])
def test_custom_features_extractor_off_policy(algo: str, env_id: str) -> None:
    kwargs = dict(
        features_extractor_class=OURS["TinyMlp"], features_extractor_kwargs=dict(features_dim=8)
    )
    model = getattr(algos, algo)(
        "MlpPolicy", env_id, learning_starts=16, batch_size=8, buffer_size=200, policy_kwargs=kwargs
    )
    model.learn(40)
    _torch_learner(model)
    theirs = getattr(sb3, algo)(
        "MlpPolicy",
        env_id,
        buffer_size=200,
        policy_kwargs={**kwargs, "features_extractor_class": THEIRS["TinyMlp"]},
    )
    net = model.q_net if algo == "DQN" else model.actor
    theirs_net = theirs.q_net if algo == "DQN" else theirs.actor
    assert _shapes(net) == _shapes(theirs_net)


def test_bad_custom_policies() -> None:
    cls = OURS["CustomActorCriticPolicy"]
    with pytest.raises(ValueError, match=r"DQN takes a policy name .* got the class Custom"):
        algos.DQN(cls, "CartPole-v1", buffer_size=100)
    with pytest.raises(
        ValueError, match="PPO takes a policy name or an ActorCriticPolicy subclass"
    ):
        algos.PPO(nn.Linear, "CartPole-v1")

    class NoLatents(ActorCriticPolicy):
        def _build_mlp_extractor(self) -> None:
            self.mlp_extractor = nn.Linear(self.features_dim, 8)

    with pytest.raises(TypeError, match="has no latent_dim_pi"):
        algos.PPO(NoLatents, "CartPole-v1")
    with pytest.raises(ValueError, match="features_dim must be a positive integer, got 0"):
        OURS["TinyMlp"](Toy().observation_space, features_dim=0)
