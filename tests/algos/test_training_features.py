"""Callbacks during learn, logging outputs, progress bar, threads and device choice."""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

import palaestra as gym
from palaestra.algos import DQN, PPO
from palaestra.algos.callbacks import (
    BaseCallback,
    EvalCallback,
    EveryNTimesteps,
    StopTrainingOnMaxEpisodes,
    StopTrainingOnRewardThreshold,
)
from palaestra.algos.logger import configure
from palaestra.error import DependencyNotInstalled

SMALL = {"n_steps": 64, "batch_size": 32, "n_epochs": 1, "seed": 0}


class Hooks(BaseCallback):
    def __init__(self) -> None:
        super().__init__()
        self.events: list[str] = []

    def _on_training_start(self) -> None:
        self.events.append("start")

    def _on_rollout_start(self) -> None:
        self.events.append("rollout")

    def _on_step(self) -> bool:
        assert self.locals["rewards"].shape == (1,)
        return True

    def _on_training_end(self) -> None:
        self.events.append("end")


def test_hooks_order_and_counts() -> None:
    hooks = Hooks()
    PPO("MlpPolicy", "CartPole-v1", **SMALL).learn(128, callback=hooks)
    assert hooks.events == ["start", "rollout", "rollout", "end"] and hooks.n_calls == 128


def test_eval_callback_stops_on_threshold(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    stop = StopTrainingOnRewardThreshold(reward_threshold=-1e9, verbose=1)
    eval_cb = EvalCallback(
        gym.make("CartPole-v1"),
        callback_on_new_best=stop,
        eval_freq=50,
        n_eval_episodes=2,
        best_model_save_path=str(tmp_path),
        log_path=str(tmp_path),
    )
    model = DQN("MlpPolicy", "CartPole-v1", learning_starts=10, seed=0).learn(
        1000, callback=eval_cb
    )
    assert model.num_timesteps == 50 and eval_cb.best_mean_reward > 0
    assert (tmp_path / "best_model.zip").exists() and (tmp_path / "evaluations.npz").exists()
    with np.load(tmp_path / "evaluations.npz") as data:
        assert data["timesteps"].tolist() == [50]
    out = capsys.readouterr().out
    assert "Eval num_timesteps=50" in out and "New best mean reward!" in out


def test_every_n_and_max_episodes() -> None:
    hooks = Hooks()
    model = DQN("MlpPolicy", "CartPole-v1", learning_starts=10, seed=0)
    model.learn(2000, callback=[EveryNTimesteps(20, hooks), StopTrainingOnMaxEpisodes(5)])
    # The step that ends episode 5 stops training; unlike SB3 (which drops that step) it is
    # recorded first, so that a stopped run can resume exactly (see algos/__init__.py).
    assert hooks.n_calls >= 1 and model._episode_num == 5 and model.num_timesteps < 2000


def test_verbose_table_and_csv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    PPO("MlpPolicy", "CartPole-v1", verbose=1, **SMALL).learn(128)
    out = capsys.readouterr().out
    for key in [
        "rollout/",
        "ep_len_mean",
        "time/",
        "fps",
        "iterations",
        "total_timesteps",
        "train/",
        "approx_kl",
        "clip_fraction",
        "entropy_loss",
        "explained_variance",
        "policy_gradient_loss",
        "value_loss",
        "n_updates",
        "learning_rate",
    ]:
        assert key in out, key
    model = DQN("MlpPolicy", "CartPole-v1", learning_starts=10, seed=0)
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(400, log_interval=1)
    model.logger.close()
    with open(tmp_path / "progress.csv") as f:
        rows = list(csv.DictReader(f))
    assert rows and "rollout/exploration_rate" in rows[0] and "train/loss" in rows[-1]


def test_progress_bar(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("tqdm")
    PPO("MlpPolicy", "CartPole-v1", **SMALL).learn(64, progress_bar=True)
    assert "64/64" in capsys.readouterr().err


def test_tensorboard_missing_is_clear(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # tensorboard is a dev dependency: its absence is simulated (the import then fails)
    monkeypatch.setitem(sys.modules, "torch.utils.tensorboard", None)
    model = PPO("MlpPolicy", "CartPole-v1", tensorboard_log=str(tmp_path), **SMALL)
    with pytest.raises(DependencyNotInstalled, match="tensorboard"):
        model.learn(64)


def test_threads_and_device() -> None:
    torch.set_num_threads(2)
    model = DQN("MlpPolicy", "CartPole-v1")
    assert torch.get_num_threads() == 1 and model.device.type == "cpu"
    DQN("MlpPolicy", "CartPole-v1", num_threads=2)
    assert torch.get_num_threads() == 2
    torch.set_num_threads(1)


def test_episode_infos_and_success_only_at_episode_ends() -> None:
    model = PPO("MlpPolicy", "CartPole-v1", **SMALL)
    episode = {"r": 1.0, "l": 1, "t": 0.0}
    infos = [
        {"episode": episode, "is_success": True},
        {"is_success": False},  # not done: its success flag is not an episode's outcome
        {"is_success": 0.0},
        {"TimeLimit.truncated": False},
    ]
    model._update_info_buffer(infos, np.array([True, False, True, True]))
    assert list(model.ep_info_buffer) == [episode]
    assert list(model.ep_success_buffer) == [True, False]
