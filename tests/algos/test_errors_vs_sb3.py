"""Bad ``callback`` and ``predict`` input: a palaestra error that is also the builtin SB3 raises
there, naming the value and what was expected (see tests/test_errors_vs_references.py)."""

from __future__ import annotations

import importlib.util
from typing import Any

import numpy as np
import pytest
from tests.raised import raised

from palaestra import error
from palaestra.algos import DQN, PPO
from palaestra.algos.callbacks import BaseCallback, CheckpointCallback

HAS_SB3 = importlib.util.find_spec("stable_baselines3") is not None


def _compatible(ours: BaseException | None, theirs: BaseException | None) -> None:
    assert isinstance(ours, error.Error), ours
    if theirs is not None:
        assert isinstance(ours, type(theirs)), (type(ours).__mro__, type(theirs))


EXPECTED = "a BaseCallback instance, a function f(locals, globals) or a list of them"


@pytest.mark.parametrize(
    ("name", "wrap"),
    [("BaseCallback", False), ("BaseCallback", True), ("CheckpointCallback", False)],
)
def test_a_callback_class_instead_of_an_instance(name: str, wrap: bool) -> None:
    cls = {"BaseCallback": BaseCallback, "CheckpointCallback": CheckpointCallback}[name]
    model = PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=32, n_epochs=1)
    ours = raised(lambda: model.learn(32, callback=[cls] if wrap else cls))
    theirs = None
    if HAS_SB3:
        from stable_baselines3 import PPO as SB3PPO
        from stable_baselines3.common import callbacks

        sb3_cls = getattr(callbacks, name)
        sb3_model = SB3PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=32, n_epochs=1)
        theirs = raised(lambda: sb3_model.learn(32, callback=[sb3_cls] if wrap else sb3_cls))
        # BaseCallback: an abstract class or an argument count; CheckpointCallback: SB3 builds
        # one per step from (locals, globals) and never saves anything, silently
        assert type(theirs) is (None.__class__ if name == "CheckpointCallback" else TypeError)
    _compatible(ours, theirs)
    assert type(ours) is error.InvalidCallback
    assert str(ours) == (
        f"callback={cls!r} is a class: pass an instance, e.g. callback={name}(...) "
        f"(expected {EXPECTED})"
    )
    assert model.num_timesteps == 0  # refused before any step


@pytest.mark.parametrize("callback", [1, "x"])
def test_a_callback_that_is_not_callable(callback: Any) -> None:
    model = PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=32, n_epochs=1)
    ours = raised(lambda: model.learn(32, callback=callback))
    theirs = None
    if HAS_SB3:
        from stable_baselines3 import PPO as SB3PPO

        sb3_model = SB3PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=32, n_epochs=1)
        theirs = raised(lambda: sb3_model.learn(32, callback=callback))
    _compatible(ours, theirs)
    assert str(ours) == f"callback must be {EXPECTED}, got {callback!r}"


def test_function_and_instance_callbacks_still_run() -> None:
    calls: list[int] = []

    class Count(BaseCallback):
        def _on_step(self) -> bool:
            calls.append(self.num_timesteps)
            return True

    model = PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=32, n_epochs=1)
    model.learn(32, callback=[Count(), lambda _locals, _globals: True])
    assert calls == list(range(1, 33))


def test_predict_a_dict_on_a_discrete_observation_space() -> None:
    model = DQN("MlpPolicy", "FrozenLake-v1", learning_starts=0)
    obs = {"a": 1}
    ours = raised(lambda: model.predict(obs))
    theirs = None
    if HAS_SB3:
        import gymnasium
        from stable_baselines3 import DQN as SB3DQN

        sb3_model = SB3DQN("MlpPolicy", gymnasium.make("FrozenLake-v1"), learning_starts=0)
        theirs = raised(lambda: sb3_model.predict(obs))
        assert type(theirs) is AssertionError
    _compatible(ours, theirs)
    assert type(ours) is error.InvalidObservation and isinstance(ours, ValueError)
    assert str(ours) == (
        "The observation {'a': 1} is a dict, but the observation space is Discrete(16): pass an "
        "observation of that space (or a batch of them)"
    )
    action, _ = model.predict(3)  # the right kind still works
    assert model.action_space.contains(int(action))


def test_predict_a_dict_on_a_box_space_and_a_box_on_a_dict_space() -> None:
    model = PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=32)
    ours = raised(lambda: model.predict({"x": np.zeros(4)}))
    assert type(ours) is error.InvalidObservation and "{'x': array([0., 0., 0., 0.])}" in str(ours)
    assert "observation space is Box(" in str(ours)
    from palaestra import spaces
    from palaestra.algos.common.spaces_util import is_vectorized_observation

    space = spaces.Dict({"x": spaces.Box(-1, 1, (2,))})
    ours = raised(lambda: is_vectorized_observation(np.zeros(2), space))
    assert type(ours) is error.InvalidObservation
    assert str(ours) == f"Expected a dict observation for {space}, got array([0., 0.]) (ndarray)"
