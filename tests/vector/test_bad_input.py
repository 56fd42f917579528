"""Bad input to vector envs: clear errors, whichever engine runs the envs."""

from __future__ import annotations

import numpy as np
import pytest

import palaestra as gym
from palaestra.error import ClosedEnvironmentError, InvalidAction, ResetNeeded
from palaestra.vector import AutoresetMode

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


class _Unchecked(gym.Env):
    """Steps whatever it is given, as most users' envs do: the vector env must check."""

    def __init__(self, discrete: bool = False):
        self.observation_space = gym.spaces.Box(-1, 1, (1,), np.float32)
        box = gym.spaces.Box(-1, 1, (1,), np.float32)
        self.action_space = gym.spaces.Discrete(2) if discrete else box

    def reset(self, *, seed=None, options=None):
        return np.zeros(1, np.float32), {}

    def step(self, action):
        return np.zeros(1, np.float32), 0.0, False, False, {}


@pytest.mark.timeout(60)
@pytest.mark.parametrize("face", ["SyncVectorEnv", "AsyncVectorEnv", "DummyVecEnv", "native"])
@pytest.mark.parametrize(
    ("actions", "dtype"),
    [
        (np.array([[0.5 + 0j], [0.1 + 0j]]), "complex128"),
        (np.array([["0.5"], ["1"]]), "<U3"),
        (np.array([[0.5], [None]], dtype=object), "object"),
    ],
)
def test_complex_string_and_object_action_batches_are_refused(face, actions, dtype):
    from palaestra.vec_env import DummyVecEnv
    from palaestra.vector import AsyncVectorEnv, SyncVectorEnv

    if face == "native":
        envs = gym.make_vec("MountainCarContinuous-v0", 2)
        space = "Box(-1.0, 1.0, (1,), float32)"
        expected = (
            f"Invalid actions {actions!r}: not numeric, expected real values for action space "
            f"{space}, got dtype {dtype}"
        )
    else:
        cls = {"SyncVectorEnv": SyncVectorEnv, "DummyVecEnv": DummyVecEnv}.get(face)
        envs = cls([_Unchecked] * 2) if cls else AsyncVectorEnv([_Unchecked] * 2, context="fork")
        expected = (
            f"Invalid actions {actions!r} for action space Box(-1.0, 1.0, (2, 1), float32): "
            f"expected real values, got dtype {dtype}"
        )
    envs.reset()
    with pytest.raises(InvalidAction) as info:
        envs.step(actions)
    assert str(info.value) == expected
    envs.step(np.zeros((2, 1), np.float32))  # nothing was sent: the envs are still usable
    envs.close()


def test_object_and_ragged_batches_for_discrete_envs_are_refused():
    from palaestra.vector import SyncVectorEnv

    envs = SyncVectorEnv([lambda: _Unchecked(discrete=True)] * 2)
    envs.reset()
    expected = (
        r"^Invalid actions \[None, 1\] for action space MultiDiscrete\(\[2 2\]\): expected "
        r"integer values, got dtype object$"
    )
    with pytest.raises(InvalidAction, match=expected):
        envs.step([None, 1])
    expected = (
        r"^Invalid actions \[\[0\], 1\] for action space MultiDiscrete\(\[2 2\]\) \(2 envs\): "
        r"not a rectangular array of shape \(2,\)$"
    )
    with pytest.raises(InvalidAction, match=expected):
        envs.step([[0], 1])


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
    # the wrappers make() adds, and the spec's step limit
    assert (
        str(envs.envs[0]) == "<TimeLimit<OrderEnforcing<PassiveEnvChecker<CartPoleEnv instance>>>>"
    )
    assert envs.envs[0]._max_episode_steps == 500
    same_step = gym.make_vec(
        "CartPole-v1", 2, render_mode="rgb_array", vector_kwargs={"autoreset_mode": "SameStep"}
    )
    assert same_step.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 2 and frames[0].shape == (400, 600, 3)


def test_a_native_batch_refuses_a_render_mode():
    from palaestra.envs.classic_control.cartpole import CartPoleBatch, CartPoleEnv
    from palaestra.vector.native import batched_vector_env

    with pytest.raises(ValueError, match=r"native batches do not render \(render_mode='human'\)"):
        batched_vector_env(CartPoleBatch, CartPoleEnv, 2, render_mode="human")
