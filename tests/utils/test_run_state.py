"""Run state of the native vector stack: capture, restore, continue to the same bits."""

from __future__ import annotations

import numpy as np
import pytest

import palaestra
from palaestra.error import RunStateError
from palaestra.utils import run_state
from palaestra.vec_env import DummyVecEnv, VecFrameStack, VecNormalize, make_vec_env

IDS = ["CartPole-v1", "MountainCar-v0", "MountainCarContinuous-v0", "Pendulum-v1", "Acrobot-v1"]


def _actions(venv, n: int, seed: int) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
    space = venv.action_space
    space.seed(seed)
    return [np.stack([space.sample() for _ in range(venv.num_envs)]) for _ in range(n)]


@pytest.mark.parametrize("env_id", IDS)
def test_restored_env_continues_identically(env_id: str) -> None:
    # Episodes end and reset (time limits, terminations) on both sides of the cut.
    make = lambda: VecFrameStack(VecNormalize(make_vec_env(env_id, n_envs=3, seed=5)), 2)  # noqa: E731
    a, b = make(), make()
    actions = _actions(a, 1300, 0)  # past MountainCarContinuous's 999-step limit
    a.reset()
    for act in actions[:600]:
        a.step(act)
    state = a.get_run_state()
    b.set_run_state(state)  # b was never reset: the state is all it needs
    ended = 0
    for act in actions[600:]:
        oa, ra, da, ia = a.step(act)
        ob, rb, db, ib = b.step(act)
        assert np.array_equal(oa, ob) and np.array_equal(ra, rb) and np.array_equal(da, db)
        for x, y in zip(ia, ib):
            assert x.keys() == y.keys()
            if "terminal_observation" in x:
                assert np.array_equal(x["terminal_observation"], y["terminal_observation"])
                assert x["episode"]["r"] == y["episode"]["r"]
                ended += 1
    assert ended > 0  # the comparison crossed resets


def test_state_is_json_and_arrays() -> None:
    import json

    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    venv.reset()
    meta, arrays = venv.get_run_state()
    json.dumps(meta)  # generators and counters are plain JSON
    assert all(isinstance(v, np.ndarray) for v in arrays.values())
    assert "venv/_driver/engine/batch/_state" in arrays


def test_wrong_size_refused_and_nothing_changes() -> None:
    small, big = make_vec_env("CartPole-v1", n_envs=3, seed=0), make_vec_env("CartPole-v1", 4)
    small.reset()
    before = small.get_run_state()
    big.reset()
    with pytest.raises(RunStateError, match=r"_state' is float64\[4, 4\].*float64\[3, 4\]"):
        small.set_run_state(big.get_run_state())
    after = small.get_run_state()
    assert after[0] == before[0]
    assert all(np.array_equal(after[1][k], v) for k, v in before[1].items())


def test_other_env_refused() -> None:
    cart, car = make_vec_env("CartPole-v1", n_envs=2), make_vec_env("MountainCar-v0", n_envs=2)
    cart.reset()
    with pytest.raises(RunStateError):
        car.set_run_state(cart.get_run_state())


def test_malformed_generator_and_values_refused() -> None:
    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    venv.reset()
    meta, arrays = venv.get_run_state()
    driver = meta["venv"]["object"]["_driver"]["object"]
    batch = driver["engine"]["object"]["batch"]["object"]
    batch["_rngs"]["generators"][0]["bit_generator"] = "MT19937"
    with pytest.raises(RunStateError, match=r"_rngs\[0\]' holds a 'MT19937' generator"):
        venv.set_run_state((meta, arrays))
    meta, arrays = venv.get_run_state()
    engine = meta["venv"]["object"]["_driver"]["object"]["engine"]["object"]
    engine["_steps"] = {"value": "many"}
    with pytest.raises(RunStateError, match="_steps' is 'many', expected a int"):
        venv.set_run_state((meta, arrays))
    meta, arrays = venv.get_run_state()
    del arrays["episode_returns"]  # the VecMonitor's, the outermost layer
    with pytest.raises(RunStateError, match="lacks the array 'episode_returns'"):
        venv.set_run_state((meta, arrays))


def test_envs_of_python_objects_cannot_save() -> None:
    venv = DummyVecEnv([lambda: palaestra.make("CartPole-v1")])
    with pytest.raises(RunStateError, match="DummyVecEnv cannot save its envs' state"):
        venv.get_run_state()
    assert not run_state.supports_run_state(object())
