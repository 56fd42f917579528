"""Single envs against the installed Gymnasium: identical bytes, rewards and flags."""

from __future__ import annotations

import numpy as np
import pytest
from tests.envs.cases import CLASSIC_IDS, POLICIES

import palaestra

gymnasium = pytest.importorskip("gymnasium")

STEPS = 1000
# make("CartPole-v0") warns that v1 exists, as Gymnasium does.
pytestmark = pytest.mark.filterwarnings("ignore:.*is out of date")


def _run_both(env_id: str, steps: int = STEPS) -> int:
    """Step both libraries in lockstep; return how many episodes terminated."""
    ours = palaestra.make(env_id)
    ref = gymnasium.make(env_id)
    obs, _ = ours.reset(seed=42)
    ref_obs, _ = ref.reset(seed=42)
    assert obs.dtype == ref_obs.dtype == np.float32
    assert obs.tobytes() == ref_obs.tobytes()
    rng = np.random.default_rng(7)
    policy = POLICIES[env_id]
    terminations = 0
    for t in range(steps):
        action = policy(rng, obs)
        obs, reward, term, trunc, info = ours.step(action)
        ref_obs, ref_reward, ref_term, ref_trunc, ref_info = ref.step(action)
        where = f"{env_id} step {t}"
        assert obs.dtype == np.float32, where
        assert obs.tobytes() == ref_obs.tobytes(), f"{where}: {obs} != {ref_obs}"
        assert float(reward) == float(ref_reward), where  # bit-equal, not approx
        assert (term, trunc) == (ref_term, ref_trunc), where
        assert type(term) is bool and type(trunc) is bool
        assert info == ref_info == {}
        if term or trunc:
            terminations += term
            # Alternate: continue the generator, reseed, and custom reset bounds.
            kwargs: dict = [{}, {"seed": t}, {"options": _options(env_id)}][t % 3]
            obs, _ = ours.reset(**kwargs)
            ref_obs, _ = ref.reset(**kwargs)
            assert obs.tobytes() == ref_obs.tobytes(), f"{where}: reset {kwargs}"
    # The unwrapped state agrees too (dtype included: Gymnasium keeps float32 in some envs).
    state, ref_state = ours.unwrapped.state, ref.unwrapped.state
    np.testing.assert_array_equal(np.asarray(state), np.asarray(ref_state))
    return terminations


def _options(env_id: str) -> dict:
    if env_id == "Pendulum-v1":
        return {"x_init": 1.5, "y_init": 0.5}
    if env_id.startswith("MountainCar"):
        return {"low": -0.7, "high": -0.3}
    return {"low": -0.08, "high": 0.08}


@pytest.mark.parametrize("env_id", CLASSIC_IDS)
def test_same_trajectory_as_gymnasium(env_id: str) -> None:
    terminations = _run_both(env_id)
    if env_id != "Pendulum-v1":  # Pendulum never terminates; the others must, to test resets
        assert terminations >= 2


@pytest.mark.parametrize("env_id", ["CartPole-v1", "MountainCar-v0", "Pendulum-v1"])
def test_reset_options_same_draw_as_gymnasium(env_id: str) -> None:
    options = _options(env_id)
    for seed in range(20):
        obs, _ = palaestra.make(env_id).reset(seed=seed, options=options)
        ref, _ = gymnasium.make(env_id).reset(seed=seed, options=options)
        assert obs.tobytes() == ref.tobytes()


def test_cartpole_steps_after_termination_match_gymnasium() -> None:
    """Reward 0 after termination (1 on it), with a warning; Sutton-Barto gives -1 / -1."""
    for kwargs in ({}, {"sutton_barto_reward": True}):
        ours = palaestra.envs.classic_control.CartPoleEnv(**kwargs)
        ref = gymnasium.envs.classic_control.CartPoleEnv(**kwargs)
        ours.reset(seed=1)
        ref.reset(seed=1)
        rewards, ref_rewards = [], []
        with pytest.warns(UserWarning):
            for _ in range(60):  # always push right: falls within ~10 steps
                rewards.append(ours.step(1)[1])
                ref_rewards.append(ref.step(1)[1])
        assert rewards == ref_rewards


@pytest.mark.slow
@pytest.mark.parametrize("env_id", CLASSIC_IDS)
def test_long_trajectory_as_gymnasium(env_id: str) -> None:
    _run_both(env_id, steps=50_000)


def test_cartpole_semi_implicit_integrator_matches_gymnasium() -> None:
    ours = palaestra.envs.classic_control.CartPoleEnv()
    ref = gymnasium.envs.classic_control.CartPoleEnv()
    ours.kinematics_integrator = ref.kinematics_integrator = "semi-implicit euler"
    ours.reset(seed=5)
    ref.reset(seed=5)
    for t in range(8):
        assert ours.step(t % 2)[0].tobytes() == ref.step(t % 2)[0].tobytes()
