"""SAC's and TD3's ``model.actor`` as SB3's ``Actor`` (a ``BasePolicy``, issue 26): ``predict`` on
one observation or a batch, in the action space's bounds, equal to SB3's to 1e-6 for the same
weights; ``device``, ``set_training_mode``, ``obs_to_tensor``. Saving an actor alone is not
offered: the error says to save the policy (docs/differences.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from palaestra import spaces
from palaestra.algos import DDPG, SAC, TD3

sb3 = pytest.importorskip("stable_baselines3")

ALGOS = {"SAC": SAC, "TD3": TD3, "DDPG": DDPG}
ARCH = {"net_arch": [16, 16]}


def _pair(algo: str, env_id: str) -> tuple[Any, Any]:
    ours = ALGOS[algo]("MlpPolicy", env_id, seed=1, policy_kwargs=dict(ARCH))
    theirs = getattr(sb3, algo)("MlpPolicy", env_id, seed=2, policy_kwargs=dict(ARCH), device="cpu")
    theirs.policy.load_state_dict(
        {k: v for k, v in ours.policy.state_dict().items() if not k.startswith("ent_coef")}
    )
    return ours, theirs


@pytest.mark.parametrize("algo", list(ALGOS))
@pytest.mark.parametrize("env_id", ["Pendulum-v1", "MountainCarContinuous-v0"])
def test_actor_predict_equals_sb3s(algo: str, env_id: str) -> None:
    ours, theirs = _pair(algo, env_id)
    space = ours.observation_space
    space.seed(0)
    batch = np.stack([space.sample() for _ in range(5)])
    for obs in (batch[0], batch):
        got, state = ours.actor.predict(obs, deterministic=True)
        want, their_state = theirs.actor.predict(obs, deterministic=True)
        assert state is their_state is None
        assert got.shape == want.shape and got.dtype == want.dtype
        np.testing.assert_allclose(got, want, atol=1e-6)
        # the policy's predict is the actor's (SB3's SACPolicy/TD3Policy._predict)
        np.testing.assert_allclose(ours.policy.predict(obs, deterministic=True)[0], got, atol=1e-6)
    assert ours.actor.device == theirs.actor.device == torch.device("cpu")
    tensor, vectorized = ours.actor.obs_to_tensor(batch)
    their_tensor, their_vectorized = theirs.actor.obs_to_tensor(batch)
    assert vectorized is their_vectorized is True
    assert tensor.shape == their_tensor.shape and tensor.dtype == their_tensor.dtype


def test_sac_actor_samples_stay_in_the_bounds() -> None:
    ours, _ = _pair("SAC", "Pendulum-v1")
    obs = np.zeros((64, 3), np.float32)
    torch.manual_seed(0)
    actions, _ = ours.actor.predict(obs)
    assert actions.shape == (64, 1) and (np.abs(actions) <= 2.0).all()
    assert len(np.unique(actions)) > 1  # sampled, not the mean


@pytest.mark.parametrize("algo", ["SAC", "TD3"])
def test_actor_set_training_mode_as_sb3(algo: str) -> None:
    ours, theirs = _pair(algo, "Pendulum-v1")
    for mode in (True, False):
        ours.actor.set_training_mode(mode)
        theirs.actor.set_training_mode(mode)
        assert ours.actor.training is theirs.actor.training is mode
    ours.actor.set_training_mode(True)
    ours.actor.predict(np.zeros(3, np.float32))
    assert ours.actor.training is False  # predict acts in evaluation mode, as SB3's


def test_an_actor_built_alone_acts_in_minus_one_one() -> None:
    from palaestra.algos.common.continuous_policies import DeterministicActor
    from palaestra.algos.networks import FlattenExtractor

    obs_space = spaces.Box(-1.0, 1.0, (3,), np.float32)
    actor = DeterministicActor(obs_space, 2, FlattenExtractor(obs_space), [8], torch.nn.ReLU)
    assert actor.action_space == spaces.Box(-1.0, 1.0, (2,), np.float32)
    action, _ = actor.predict(np.zeros(3, np.float32))
    assert action.shape == (2,) and (np.abs(action) <= 1.0).all()


@pytest.mark.parametrize("algo", ["SAC", "TD3"])
def test_saving_an_actor_alone_names_the_policy_save(algo: str, tmp_path: Path) -> None:
    ours, _ = _pair(algo, "Pendulum-v1")
    with pytest.raises(NotImplementedError, match=r"use model\.policy\.save\(path\)"):
        ours.actor.save(tmp_path / "actor")
    assert not list(tmp_path.iterdir())
    # what the message points to round-trips, actor included
    ours.policy.save(tmp_path / "policy")
    loaded = type(ours.policy).load(tmp_path / "policy")
    obs = np.zeros((2, 3), np.float32)
    np.testing.assert_allclose(
        loaded.actor.predict(obs, deterministic=True)[0],
        ours.actor.predict(obs, deterministic=True)[0],
        atol=1e-6,
    )
