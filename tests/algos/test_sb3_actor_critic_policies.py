"""PPO's and A2C's policy classes at SB3's paths (``palaestra.algos.ppo.policies``...): the
aliases are SB3's, ``ActorCriticCnnPolicy``/``MultiInputActorCriticPolicy`` build SB3's
networks (same parameter shapes as SB3's for the same spaces), and the algorithms train and
save with a class given instead of a name."""

from __future__ import annotations

import numpy as np
import pytest
import stable_baselines3 as sb3
import stable_baselines3.common.envs as sb3_envs
import torch

from palaestra.algos import A2C, PPO, envs
from palaestra.algos.a2c import policies as a2c_policies
from palaestra.algos.networks import CombinedExtractor, FlattenExtractor, NatureCNN
from palaestra.algos.policies import (
    ActorCriticCnnPolicy,
    ActorCriticPolicy,
    MultiInputActorCriticPolicy,
)
from palaestra.algos.ppo import policies as ppo_policies


def test_the_aliases_are_sb3s() -> None:
    for module in (ppo_policies, a2c_policies):
        assert module.MlpPolicy is ActorCriticPolicy
        assert module.CnnPolicy is ActorCriticCnnPolicy
        assert module.MultiInputPolicy is MultiInputActorCriticPolicy
    for ours, theirs in ((PPO, sb3.PPO), (A2C, sb3.A2C)):
        names = {n: c.__name__ for n, c in ours.policy_aliases.items()}
        assert names == {n: c.__name__ for n, c in theirs.policy_aliases.items()}


def _shapes(module: object) -> list[tuple[int, ...]]:
    return sorted(tuple(p.shape) for p in module.parameters())  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("algo", "name", "env", "extractor"),
    [
        ("PPO", "CnnPolicy", "FakeImageEnv", NatureCNN),
        ("A2C", "MultiInputPolicy", "SimpleMultiObsEnv", CombinedExtractor),
        ("PPO", "MlpPolicy", "IdentityEnvBox", FlattenExtractor),
    ],
)
def test_a_policy_class_builds_sb3s_network(
    algo: str, name: str, env: str, extractor: type
) -> None:
    ours_algo, theirs_algo = {"PPO": (PPO, sb3.PPO), "A2C": (A2C, sb3.A2C)}[algo]
    policy_class = getattr(ppo_policies if algo == "PPO" else a2c_policies, name)
    kwargs = {"n_steps": 8, "device": "cpu", **({"batch_size": 8} if algo == "PPO" else {})}
    model = ours_algo(policy_class, getattr(envs, env)(), **kwargs)
    assert type(model.policy) is policy_class
    assert type(model.policy.features_extractor) is extractor
    reference = theirs_algo(name, getattr(sb3_envs, env)(), **kwargs)
    assert _shapes(model.policy) == _shapes(reference.policy)


def test_a_given_extractor_wins_over_the_class_default() -> None:
    env = envs.FakeImageEnv(screen_height=8, screen_width=8)
    kwargs = {"features_extractor_class": FlattenExtractor}
    model = PPO(ppo_policies.CnnPolicy, env, n_steps=8, batch_size=8, policy_kwargs=kwargs)
    assert type(model.policy.features_extractor) is FlattenExtractor
    assert model.policy.net_arch == {"pi": [64, 64], "vf": [64, 64]}  # SB3's default after it


def test_the_extractor_may_be_given_in_sb3s_position() -> None:
    env = envs.FakeImageEnv(screen_height=36, screen_width=36)
    spaces = (env.observation_space, env.action_space, lambda _: 1e-3)
    # net_arch, activation_fn, ortho_init, use_sde, log_std_init, full_std, use_expln,
    # squash_output, then features_extractor_class: SB3's order
    positional = (None, torch.nn.Tanh, True, False, 0.0, True, False, False, FlattenExtractor)
    policy = ActorCriticCnnPolicy(*spaces, *positional)
    assert type(policy.features_extractor) is FlattenExtractor
    assert type(ActorCriticCnnPolicy(*spaces, *positional[:3]).features_extractor) is NatureCNN


def test_a_class_trains_saves_and_loads(tmp_path: object) -> None:
    env = envs.SimpleMultiObsEnv(random_start=False)
    model = A2C(a2c_policies.MultiInputPolicy, env, n_steps=4, seed=0).learn(16)
    path = f"{tmp_path}/a2c"
    model.save(path)
    loaded = A2C.load(path, env=env)
    assert type(loaded.policy) is MultiInputActorCriticPolicy
    obs, _ = env.reset()
    np.testing.assert_array_equal(
        loaded.predict(obs, deterministic=True)[0], model.predict(obs, deterministic=True)[0]
    )
