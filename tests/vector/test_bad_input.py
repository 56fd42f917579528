"""Bad input to vector envs: clear errors, whichever engine runs the envs."""

from __future__ import annotations

import numpy as np
import pytest

import palaestra as gym
from palaestra.error import ClosedEnvironmentError, InvalidAction, ResetNeeded

MODES = ["vector_entry_point", "sync", "async"]


def _make(mode: str, env_id: str = "CartPole-v1", n: int = 3):
    kwargs = {"vector_kwargs": {"context": "fork"}} if mode == "async" else {}
    return gym.make_vec(env_id, n, vectorization_mode=mode, **kwargs)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("mode", MODES)
def test_wrong_action_batches(mode):
    envs = _make(mode)
    envs.reset(seed=0)
    with pytest.raises(InvalidAction, match=r"shape|\(3,\)"):
        envs.step(np.array([1, 0]))  # 2 actions for 3 envs
    with pytest.raises(InvalidAction, match=r"shape|\(3,\)"):
        envs.step(np.ones((3, 1), dtype=np.int64))
    with pytest.raises(InvalidAction, match=r"integer|int"):
        envs.step(np.array([0.5, 1.0, 0.0]))
    with pytest.raises(InvalidAction):
        envs.step(np.array([0, 1, 7]))  # out of range for Discrete(2)
    # After all that, a good step still works.
    obs = envs.step(np.array([0, 1, 1]))[0]
    assert obs.shape == (3, 4)
    envs.close()


@pytest.mark.timeout(60)
@pytest.mark.parametrize("mode", MODES)
def test_closed_envs_refuse_everything(mode):
    envs = _make(mode)
    envs.reset(seed=0)
    envs.close()
    envs.close()
    for call in (
        lambda: envs.step(np.array([0, 1, 1])),
        lambda: envs.reset(),
        lambda: envs.get_attr("spec"),
    ):
        with pytest.raises(ClosedEnvironmentError, match="after a call to `close\\(\\)`"):
            call()


def test_native_step_before_reset():
    envs = _make("vector_entry_point")
    with pytest.raises(ResetNeeded, match="never reset"):
        envs.step(np.array([0, 1, 1]))


def test_continuous_actions_of_the_wrong_shape():
    envs = gym.make_vec("Pendulum-v1", 2)
    envs.reset(seed=0)
    with pytest.raises(InvalidAction, match=r"\(2, 1\)"):
        envs.step(np.zeros(2, dtype=np.float32))
    with pytest.raises(InvalidAction, match="not finite"):
        envs.step(np.array([[0.0], [np.nan]], dtype=np.float32))


def test_bad_constructor_arguments():
    from palaestra.vector import SyncVectorEnv

    with pytest.raises(ValueError, match="at least one"):
        SyncVectorEnv([])
    with pytest.raises(ValueError, match="Invalid `observation_mode`"):
        SyncVectorEnv([lambda: gym.make("CartPole-v1")], observation_mode="nope")
    with pytest.raises(ValueError, match="'Sometimes' is not a valid AutoresetMode"):
        SyncVectorEnv([lambda: gym.make("CartPole-v1")], autoreset_mode="Sometimes")
    with pytest.raises(ValueError, match="Invalid vectorization mode"):
        gym.make_vec("CartPole-v1", 2, vectorization_mode="threads")
    with pytest.raises(TypeError, match=r"not a palaestra\.Env"):
        SyncVectorEnv([lambda: object()])


def test_render_mode_falls_back_to_real_envs():
    from palaestra.vector import SyncVectorEnv

    envs = gym.make_vec("CartPole-v1", 2, render_mode="rgb_array")
    assert isinstance(envs, SyncVectorEnv)
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 2 and frames[0].shape == (400, 600, 3)
