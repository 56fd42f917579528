"""A custom ActorCriticPolicy that overrides what SB3's on-policy loop calls (``forward``,
``evaluate_actions``, ...) is told that palaestra's learner does not call those methods,
instead of training silently otherwise than SB3 would."""

from __future__ import annotations

import warnings

import pytest
import torch

from palaestra.algos import A2C, PPO
from palaestra.algos.envs import FakeImageEnv
from palaestra.algos.policies import ActorCriticCnnPolicy, ActorCriticPolicy


class ConstantValuePolicy(ActorCriticPolicy):
    """SB3's test_gae policy: values forced to 0 in ``forward``."""

    def forward(self, obs, deterministic=False):  # type: ignore[no-untyped-def]
        actions, values, log_prob = super().forward(obs, deterministic)
        return actions, torch.zeros_like(values), log_prob


class ScaledValuePolicy(ActorCriticPolicy):
    def predict_values(self, obs):  # type: ignore[no-untyped-def]
        return 2 * super().predict_values(obs)

    def evaluate_actions(self, obs, actions):  # type: ignore[no-untyped-def]
        return super().evaluate_actions(obs, actions)


class WiderPolicy(ActorCriticPolicy):
    """Customises a module (SB3's guide), which palaestra runs: no warning."""

    def _build_mlp_extractor(self) -> None:
        super()._build_mlp_extractor()


@pytest.mark.parametrize("algo", [PPO, A2C])
def test_overriding_a_loop_method_warns_naming_it(algo: type) -> None:
    with pytest.warns(UserWarning, match=r"ConstantValuePolicy overrides forward: palaestra's"):
        algo(ConstantValuePolicy, "CartPole-v1", seed=0)
    with pytest.warns(UserWarning, match=r"overrides evaluate_actions, predict_values:"):
        algo(ScaledValuePolicy, "CartPole-v1", seed=0)


@pytest.mark.parametrize("policy", [ActorCriticPolicy, WiderPolicy, "MlpPolicy"])
def test_module_customisation_does_not_warn(policy: object) -> None:
    with warnings.catch_warnings():
        warnings.filterwarnings("error", message=".*overrides.*")
        PPO(policy, "CartPole-v1", seed=0)


def test_sb3s_own_policy_classes_do_not_warn() -> None:
    with warnings.catch_warnings():
        warnings.filterwarnings("error", message=".*overrides.*")
        PPO(ActorCriticCnnPolicy, FakeImageEnv(screen_height=36, screen_width=36), seed=0)
