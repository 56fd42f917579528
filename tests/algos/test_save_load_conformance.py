"""SB3's ``save(exclude=, include=)``, ``set_parameters(exact_match=)`` and
``load_replay_buffer`` with no buffer (issue 16, item 4), side by side with the installed
stable-baselines3 (ported in spirit from SB3's ``tests/test_save_load.py``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from palaestra import algos

sb3 = pytest.importorskip("stable_baselines3")
gymnasium = pytest.importorskip("gymnasium")

DEFAULT_LR = {"DQN": 1e-4, "PPO": 3e-4}
SMALL = {
    "DQN": {"learning_starts": 10, "buffer_size": 500, "batch_size": 8},
    "PPO": {"n_steps": 16, "batch_size": 8, "n_epochs": 1},
}


def _pair(name: str, **kw: Any) -> list[Any]:
    """The same model in palaestra and in SB3 (CartPole-v1, small settings)."""
    settings = {**SMALL[name], "seed": 0, "policy_kwargs": {"net_arch": [16]}, **kw}
    ours = getattr(algos, name)("MlpPolicy", "CartPole-v1", **settings)
    theirs = getattr(sb3, name)("MlpPolicy", gymnasium.make("CartPole-v1"), **settings)
    return [ours, theirs]


@pytest.mark.parametrize("name", ["DQN", "PPO"])
def test_exclude_and_include_as_sb3(tmp_path: Path, name: str) -> None:
    for lib, model in zip(["pal", "sb3"], _pair(name, verbose=2, learning_rate=1e-2)):
        cls = type(model)
        model.learn(32)
        model.save(tmp_path / lib, exclude=["verbose", "learning_rate", "num_timesteps"])
        loaded = cls.load(tmp_path / lib)
        assert loaded.verbose == 0, lib  # the constructor's default
        assert loaded.lr_schedule(1.0) == pytest.approx(DEFAULT_LR[name]), lib
        assert loaded.num_timesteps == 0, lib
        loaded.verbose = 2
        loaded.save(tmp_path / lib, exclude=["verbose", "not_an_attribute"], include=["verbose"])
        again = cls.load(tmp_path / lib)
        assert again.verbose == 2, lib
        # the parameters are always written
        for (key, a), b in zip(
            model.policy.state_dict().items(), again.policy.state_dict().values()
        ):
            assert torch.equal(a, b), (lib, key)


def test_exclude_spaces_fails_at_load_as_sb3(tmp_path: Path) -> None:
    for lib, model in zip(["pal", "sb3"], _pair("DQN")):
        model.save(tmp_path / lib, exclude=["observation_space"])
        with pytest.raises(KeyError, match="observation_space and action_space were not"):
            type(model).load(tmp_path / lib)


def test_excluded_run_state_and_counters_load(tmp_path: Path) -> None:
    model = algos.PPO("MlpPolicy", "CartPole-v1", **SMALL["PPO"], seed=1).learn(64)
    assert len(model.ep_info_buffer) > 0 and model._last_obs is not None
    model.save(tmp_path / "m", exclude=["_last_obs", "n_envs", "ep_info_buffer", "_rng"])
    loaded = algos.PPO.load(tmp_path / "m", env=model.get_env())
    assert loaded._last_obs is None and len(loaded.ep_info_buffer) == 0
    assert loaded.num_timesteps == model.num_timesteps
    loaded.learn(16, reset_num_timesteps=False)  # starts new episodes
    assert loaded.num_timesteps == model.num_timesteps + 16


def test_exclude_include_bad_values() -> None:
    model = algos.DQN("MlpPolicy", "CartPole-v1", buffer_size=100)
    with pytest.raises(TypeError, match="exclude must be a list of attribute names, got 'verb"):
        model.save("never_written", exclude="verbose")
    with pytest.raises(ValueError, match=r"never hold the replay buffer \(use save_replay_buffer"):
        model.save("never_written", include=["replay_buffer"])
    with pytest.raises(ValueError, match="never hold the env"):
        model.save("never_written", exclude=["env"], include=["env"])
    assert not Path("never_written.zip").exists()


@pytest.mark.parametrize("name", ["DQN", "PPO"])
def test_set_parameters_exact_match_as_sb3(name: str) -> None:
    for lib, model in zip(["pal", "sb3"], _pair(name)):
        params = model.get_parameters()
        assert set(params) == {"policy", "policy.optimizer"}, lib
        # an object the model does not have: always refused
        for exact in (True, False):
            with pytest.raises(ValueError, match="invalid object name"):
                model.set_parameters({**params, "weights": {}}, exact_match=exact)
        # a missing object: refused only with exact_match
        with pytest.raises(ValueError, match="Names of parameters do not match"):
            model.set_parameters({"policy": params["policy"]}, exact_match=True)
        model.set_parameters({"policy": params["policy"]}, exact_match=False)
        # a module's missing keys: torch's strict load (RuntimeError), lenient without
        partial = dict(params["policy"])
        partial.pop(next(iter(partial)))
        with pytest.raises(RuntimeError, match="state_dict"):
            model.set_parameters({**params, "policy": partial}, exact_match=True)
        model.set_parameters({"policy": partial}, exact_match=False)


def test_set_parameters_refuses_before_changing_anything() -> None:
    a = algos.DQN("MlpPolicy", "CartPole-v1", seed=1, buffer_size=100)
    b = algos.DQN("MlpPolicy", "CartPole-v1", seed=2, buffer_size=100)
    before = {k: v.clone() for k, v in b.policy.state_dict().items()}
    source = a.get_parameters()
    source["policy"].popitem()
    with pytest.raises(RuntimeError, match="missing keys"):
        b.set_parameters(source)
    for key, value in b.policy.state_dict().items():
        assert torch.equal(value, before[key]), key
    # a module by its attribute name, as SB3's recursive_getattr reads it
    b.set_parameters({"q_net": a.q_net.state_dict()}, exact_match=False)
    obs = np.zeros((1, 4), dtype=np.float32)
    np.testing.assert_array_equal(a.predict(obs, deterministic=True)[0], b.predict(obs)[0])


def test_load_replay_buffer_when_none_as_sb3(tmp_path: Path) -> None:
    for lib, model in zip(["pal", "sb3"], _pair("DQN")):
        model.learn(40)
        size = model.replay_buffer.size()
        model.save_replay_buffer(tmp_path / f"{lib}_rb")
        model.replay_buffer = None
        suffix = ".zip" if lib == "pal" else ".pkl"
        model.load_replay_buffer(tmp_path / f"{lib}_rb{suffix}")
        assert model.replay_buffer is not None and model.replay_buffer.size() == size, lib
        model.learn(8, reset_num_timesteps=False)  # trains on the loaded buffer


def test_get_vec_normalize_env_as_sb3(tmp_path: Path) -> None:
    from stable_baselines3.common.vec_env import DummyVecEnv as SB3DummyVecEnv
    from stable_baselines3.common.vec_env import VecNormalize as SB3VecNormalize

    import palaestra
    from palaestra.vec_env import DummyVecEnv, VecNormalize, make_vec_env

    normalized = VecNormalize(make_vec_env("CartPole-v1", n_envs=2))
    sb3_normalized = SB3VecNormalize(SB3DummyVecEnv([lambda: gymnasium.make("CartPole-v1")] * 2))
    cases = [
        (algos.PPO, normalized, DummyVecEnv([lambda: palaestra.make("CartPole-v1")] * 2)),
        (sb3.PPO, sb3_normalized, SB3DummyVecEnv([lambda: gymnasium.make("CartPole-v1")] * 2)),
    ]
    for cls, layer, plain in cases:
        model = cls("MlpPolicy", layer, n_steps=16, batch_size=16)
        assert model.get_vec_normalize_env() is layer
        model.save(tmp_path / "m")
        assert cls.load(tmp_path / "m").get_vec_normalize_env() is None  # no env
        assert cls.load(tmp_path / "m", env=layer).get_vec_normalize_env() is layer
        model.set_env(plain)
        assert model.get_vec_normalize_env() is None
