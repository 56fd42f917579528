"""Exact resume in Python: a run stopped anywhere and continued ends with the same bits."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from palaestra.algos import A2C, DQN, PPO, SAC, TD3, NormalActionNoise
from palaestra.algos.callbacks import BaseCallback, CheckpointCallback
from palaestra.vec_env import make_vec_env


class StopAt(BaseCallback):
    """Stops training once ``num_timesteps`` reaches ``at``."""

    def __init__(self, at: int) -> None:
        super().__init__()
        self.at = at

    def _on_step(self) -> bool:
        return self.num_timesteps < self.at


CASES: dict[str, tuple[Any, dict[str, Any], str, int]] = {
    # n_steps * n_envs = 256: stops fall inside rollouts and on their last step (512, 768).
    "ppo": (PPO, dict(n_steps=64, batch_size=64, n_epochs=2), "CartPole-v1", 1300),
    "ppo-box": (PPO, dict(n_steps=32, batch_size=64, n_epochs=2), "Pendulum-v1", 1000),
    # Rollouts of 5 * 4 = 20 steps: stops inside rollouts (4, 512, 768) and on their last
    # step (257 stops at 260, and 600).
    "a2c": (A2C, dict(ent_coef=0.01), "CartPole-v1", 900),
    "a2c-box": (A2C, dict(n_steps=8, normalize_advantage=True), "Pendulum-v1", 800),
    "dqn": (
        DQN,
        dict(learning_starts=100, train_freq=4, target_update_interval=200, buffer_size=5000),
        "MountainCar-v0",
        1300,
    ),
    "dqn-episodes": (
        DQN,
        dict(learning_starts=50, train_freq=(1, "episode"), gradient_steps=-1),
        "CartPole-v1",
        900,
    ),
    # n-step returns: the buffer file records where episodes ended, the windows resume
    "dqn-nstep": (
        DQN,
        dict(learning_starts=100, train_freq=4, n_steps=3, buffer_size=5000),
        "CartPole-v1",
        900,
    ),
    "sac-nstep": (
        SAC,
        dict(learning_starts=100, batch_size=32, n_steps=3, policy_kwargs={"net_arch": [32]}),
        "Pendulum-v1",
        900,
    ),
    "sac": (
        SAC,
        dict(learning_starts=100, train_freq=2, batch_size=32, policy_kwargs={"net_arch": [32]}),
        "Pendulum-v1",
        900,
    ),
    # gSDE: the exploration matrices of an open rollout/collection are in the run state
    "ppo-sde": (
        PPO,
        dict(n_steps=32, batch_size=64, n_epochs=2, use_sde=True, sde_sample_freq=12),
        "Pendulum-v1",
        1000,
    ),
    "a2c-sde": (A2C, dict(n_steps=8, use_sde=True), "Pendulum-v1", 800),
    "sac-sde": (
        SAC,
        dict(
            learning_starts=100,
            train_freq=4,
            batch_size=32,
            use_sde=True,
            sde_sample_freq=3,
            policy_kwargs={"net_arch": [32]},
        ),
        "Pendulum-v1",
        900,
    ),
    "td3": (
        TD3,
        dict(
            learning_starts=100,
            batch_size=32,
            policy_kwargs={"net_arch": [32]},
            action_noise=NormalActionNoise(np.zeros(1), np.full(1, 0.1)),
        ),
        "Pendulum-v1",
        900,
    ),
}
OFF_POLICY = (DQN, SAC, TD3)


def _run(case: str, stops: list[int], tmp: Path | None) -> tuple[dict[str, torch.Tensor], Any]:
    algo, kwargs, env_id, total = CASES[case]
    model = algo("MlpPolicy", make_vec_env(env_id, n_envs=4, seed=1), seed=0, **kwargs)
    for i, stop in enumerate([*stops, total]):
        cb = StopAt(stop) if stop < total else None
        model.learn(total - model.num_timesteps, callback=cb, reset_num_timesteps=i == 0)
        if stop < total and tmp is not None:  # save, drop the model, load it with its env
            env = model.get_env()
            model.save(tmp / f"m{i}.zip")
            if algo in OFF_POLICY:
                model.save_replay_buffer(tmp / f"rb{i}.zip")
            del model
            model = algo.load(tmp / f"m{i}.zip", env=env)
            if algo in OFF_POLICY:
                model.load_replay_buffer(tmp / f"rb{i}.zip")
    return model.policy.state_dict(), model


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("through_files", [False, True])
def test_stopped_runs_end_bit_identical(case: str, through_files: bool, tmp_path: Path) -> None:
    full, model_a = _run(case, [], None)
    stops = [4, 257, 512, 600, 768]
    cut, model_b = _run(case, stops, tmp_path if through_files else None)
    assert model_a.num_timesteps == model_b.num_timesteps
    for key, value in full.items():
        assert torch.equal(value, cut[key]), key
    assert model_a._rng.bit_generator.state == model_b._rng.bit_generator.state


def test_partial_rollout_is_in_the_model_file(tmp_path: Path) -> None:
    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    model = PPO("MlpPolicy", venv, n_steps=16, batch_size=32, seed=0)
    model.learn(100, callback=StopAt(10))
    assert model.rollout_buffer.pos == 5  # 10 steps of 2 envs
    model.save(tmp_path / "m.zip")
    loaded = PPO.load(tmp_path / "m.zip", env=venv)
    assert loaded.rollout_buffer.pos == 5
    np.testing.assert_array_equal(
        loaded.rollout_buffer.observations[:5], model.rollout_buffer.observations[:5]
    )
    assert loaded._last_obs is not None and np.array_equal(loaded._last_obs, model._last_obs)


def test_another_env_starts_new_episodes(tmp_path: Path) -> None:
    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    model = PPO("MlpPolicy", venv, n_steps=16, batch_size=32, seed=0)
    model.learn(100, callback=StopAt(10))
    model.save(tmp_path / "m.zip")
    other = PPO.load(tmp_path / "m.zip", env=make_vec_env("CartPole-v1", n_envs=2, seed=3))
    assert other._last_obs is None  # the saved observations belong to venv
    other.learn(64, reset_num_timesteps=False)  # resets its env and trains
    assert other.num_timesteps >= 74
    stepped = PPO.load(tmp_path / "m.zip", env=venv)
    model.learn(32, reset_num_timesteps=False)  # venv moves on: the file no longer fits it
    assert PPO.load(tmp_path / "m.zip", env=venv)._last_obs is None
    assert stepped._last_obs is not None


def test_checkpoint_saved_inside_learn_keeps_no_observations(tmp_path: Path) -> None:
    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    model = PPO("MlpPolicy", venv, n_steps=16, batch_size=32, seed=0)
    model.learn(64, callback=CheckpointCallback(8, str(tmp_path)))
    loaded = PPO.load(tmp_path / "rl_model_16_steps.zip", env=venv)
    assert loaded._last_obs is None and loaded.rollout_buffer.pos == 0


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("num_timesteps", "many", "counter num_timesteps='many' is not a non-negative integer"),
        ("num_timesteps", -5, "counter num_timesteps=-5 is not a non-negative integer"),
        ("_progress_remaining", 3.0, r"counter _progress_remaining=3.0 is not in \[0, 1\]"),
        ("_n_updates", True, "counter _n_updates=True is not a non-negative integer"),
    ],
)
def test_bad_counters_in_a_model_file(
    name: str, value: object, message: str, tmp_path: Path
) -> None:
    from palaestra.algos import ModelFileError
    from palaestra.algos.common.model_io import read_archive, write_archive

    PPO("MlpPolicy", "CartPole-v1", n_steps=16, batch_size=16).save(tmp_path / "m.zip")
    meta, arrays = read_archive(tmp_path / "m.zip", "model")
    meta["counters"][name] = value
    write_archive(tmp_path / "m.zip", "model", meta, arrays)
    with pytest.raises(ModelFileError, match=message):
        PPO.load(tmp_path / "m.zip")


def test_malformed_run_state_in_a_model_file(tmp_path: Path) -> None:
    from palaestra.algos import ModelFileError
    from palaestra.algos.common.model_io import read_archive, write_archive

    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    model = PPO("MlpPolicy", venv, n_steps=16, batch_size=32, seed=0)
    model.learn(100, callback=StopAt(10))
    model.save(tmp_path / "m.zip")
    meta, arrays = read_archive(tmp_path / "m.zip", "model")
    meta["run"]["loop"]["pos"] = 99
    write_archive(tmp_path / "m.zip", "model", meta, arrays)
    with pytest.raises(ModelFileError, match=r"malformed run state.*rollout position 99"):
        PPO.load(tmp_path / "m.zip", env=venv)
    meta["run"]["loop"]["pos"] = 5
    arrays["run/torch_rng"] = arrays["run/torch_rng"][:7]
    write_archive(tmp_path / "m.zip", "model", meta, arrays)
    with pytest.raises(ModelFileError, match="malformed run state"):
        PPO.load(tmp_path / "m.zip", env=venv)


def test_load_with_another_number_of_envs(tmp_path: Path) -> None:
    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    model = PPO("MlpPolicy", venv, n_steps=16, batch_size=32, seed=0)
    model.learn(100, callback=StopAt(10))  # a partial rollout and the observations of 2 envs
    model.save(tmp_path / "m.zip")
    other = PPO.load(tmp_path / "m.zip", env=make_vec_env("CartPole-v1", n_envs=3, seed=1))
    assert other._last_obs is None and other.rollout_buffer.pos == 0
    other.learn(96, reset_num_timesteps=False)
    assert other.num_timesteps >= 106
