"""Callbacks as SB3 has them (issue 16, items 8 and 11, and the missing callback names).

The stopping rules run side by side with SB3's own classes on the same inputs; ``EvalCallback``
syncs ``VecNormalize`` statistics into the evaluation env and hands a ``CallbackList`` its
parent; ``CheckpointCallback(save_vecnormalize=True)`` writes the statistics.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from stable_baselines3.common import callbacks as sb3_callbacks

from palaestra.algos import PPO
from palaestra.algos.callbacks import (
    BaseCallback,
    CallbackList,
    CheckpointCallback,
    EvalCallback,
    EveryNTimesteps,
    StopTrainingOnMaxEpisodes,
    StopTrainingOnNoModelImprovement,
    StopTrainingOnRewardThreshold,
)
from palaestra.vec_env import VecNormalize, make_vec_env

SMALL = {"n_steps": 16, "batch_size": 16, "n_epochs": 1, "seed": 0}


def _drive(callback, parent_rewards):
    """Call ``callback.on_step`` once per evaluation with the parent's best mean reward."""
    parent = SimpleNamespace(best_mean_reward=-np.inf)
    callback.parent = parent
    callback.model = SimpleNamespace(num_timesteps=0)
    results = []
    for reward in parent_rewards:
        parent.best_mean_reward = max(parent.best_mean_reward, reward)
        results.append(callback.on_step())
    return results


@pytest.mark.parametrize(("max_no_improvement", "min_evals"), [(0, 0), (1, 0), (2, 3), (3, 1)])
def test_stop_on_no_model_improvement_matches_sb3(max_no_improvement, min_evals):
    rewards = [1, 2, 2, 2, 3, 3, 3, 3, 3, 4, 4, 4, 4, 4, 4]
    ours = StopTrainingOnNoModelImprovement(max_no_improvement, min_evals=min_evals)
    theirs = sb3_callbacks.StopTrainingOnNoModelImprovement(max_no_improvement, min_evals)
    # _drive sets a fake parent; our class checks for an EvalCallback parent, so relax it here.
    ours_results = _drive_ours(ours, rewards)
    assert ours_results == _drive(theirs, rewards)
    assert False in ours_results  # the rule did stop somewhere
    assert ours.no_improvement_evals == theirs.no_improvement_evals


def _drive_ours(callback, rewards):
    parent = EvalCallback.__new__(EvalCallback)  # an EvalCallback without an env
    parent.best_mean_reward = -np.inf
    callback.parent = parent
    callback.model = SimpleNamespace(num_timesteps=0)
    results = []
    for reward in rewards:
        parent.best_mean_reward = max(parent.best_mean_reward, reward)
        results.append(callback.on_step())
    return results


def test_stop_on_no_model_improvement_needs_an_eval_callback():
    callback = StopTrainingOnNoModelImprovement(1)
    callback.model = SimpleNamespace(num_timesteps=0)
    with pytest.raises(TypeError, match="must be used with an EvalCallback"):
        callback.on_step()


def test_stop_on_max_episodes_matches_sb3():
    dones = [[False, True], [True, True], [False, False], [True, False], [True, True]]
    outcomes = []
    for cls in (StopTrainingOnMaxEpisodes, sb3_callbacks.StopTrainingOnMaxEpisodes):
        callback = cls(max_episodes=2)
        callback.model = SimpleNamespace(
            num_timesteps=0, get_env=lambda: SimpleNamespace(num_envs=2)
        )
        callback.init_callback(callback.model)
        got = []
        for step in dones:
            callback.locals = {"dones": np.array(step)}
            got.append(callback.on_step())
        outcomes.append((got, callback.n_episodes))
    assert outcomes[0] == outcomes[1] == ([True, True, True, False, False], 6)


class _Count(BaseCallback):
    def _on_step(self) -> bool:
        return True


def test_every_n_timesteps_matches_sb3():
    fired = []
    for cls, inner_cls in (
        (EveryNTimesteps, _Count),
        (
            sb3_callbacks.EveryNTimesteps,
            type("C", (sb3_callbacks.BaseCallback,), {"_on_step": lambda s: True}),
        ),
    ):
        inner = inner_cls()
        callback = cls(n_steps=5, callback=inner)
        model = SimpleNamespace(num_timesteps=0)
        callback.model = inner.model = model
        steps = []
        for t in range(0, 40, 3):
            model.num_timesteps = t
            callback.on_step()
            steps.append(inner.n_calls)
        fired.append((steps, callback.last_time_trigger))
    assert fired[0] == fired[1]


def _normalized(seed, training=True):
    return VecNormalize(make_vec_env("CartPole-v1", n_envs=2, seed=seed), training=training)


class _CheckSynced(BaseCallback):
    """Run after each evaluation: the eval env must hold the training statistics."""

    def __init__(self) -> None:
        super().__init__()
        self.checked = 0

    def _on_step(self) -> bool:
        train, evaluation = self.model.get_env(), self.parent.eval_env
        np.testing.assert_array_equal(evaluation.obs_rms.mean, train.obs_rms.mean)
        assert evaluation.obs_rms.count == train.obs_rms.count > 1
        self.checked += 1
        return True


def test_eval_callback_syncs_vec_normalize_statistics():
    eval_env = _normalized(seed=1, training=False)
    check = _CheckSynced()
    eval_cb = EvalCallback(
        eval_env, callback_after_eval=check, eval_freq=16, n_eval_episodes=1, verbose=0
    )
    PPO("MlpPolicy", _normalized(seed=0), **SMALL).learn(64, callback=eval_cb)
    assert check.checked == 2
    assert eval_env.obs_rms.count > 1  # without the sync it stays at its initial 1e-4


def test_callback_list_as_new_best_callback_gets_the_eval_callback_as_parent():
    stop = StopTrainingOnRewardThreshold(reward_threshold=-1.0)  # any mean return passes
    seen = []

    class Parent(BaseCallback):
        def _on_step(self) -> bool:
            seen.append(self.parent)
            return True

    parent_check = Parent()
    eval_cb = EvalCallback(
        make_vec_env("CartPole-v1", n_envs=1, seed=1),
        callback_on_new_best=CallbackList([parent_check, stop]),
        eval_freq=16,
        n_eval_episodes=1,
        verbose=0,
    )
    model = PPO("MlpPolicy", make_vec_env("CartPole-v1", n_envs=2, seed=0), **SMALL)
    model.learn(256, callback=eval_cb)
    assert seen == [eval_cb]
    assert model.num_timesteps == 32  # stopped at the first evaluation (16 calls x 2 envs)


def test_eval_callback_records_success_rate(tmp_path):
    import palaestra as gym

    class Succeed(gym.Wrapper):
        def step(self, action):
            obs, reward, terminated, truncated, info = self.env.step(action)
            if terminated or truncated:
                info["is_success"] = True
            return obs, reward, terminated, truncated, info

    eval_cb = EvalCallback(
        make_vec_env("CartPole-v1", n_envs=1, seed=1, wrapper_class=Succeed),
        eval_freq=16,
        n_eval_episodes=2,
        log_path=str(tmp_path),
        verbose=0,
    )
    PPO("MlpPolicy", make_vec_env("CartPole-v1", n_envs=2, seed=0), **SMALL).learn(
        32, callback=eval_cb
    )
    with np.load(tmp_path / "evaluations.npz") as data:
        assert data["successes"].tolist() == [[True, True]]


def test_checkpoint_callback_saves_vec_normalize(tmp_path):
    callback = CheckpointCallback(16, str(tmp_path), name_prefix="m", save_vecnormalize=True)
    env = _normalized(seed=0)
    PPO("MlpPolicy", env, **SMALL).learn(32, callback=callback)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "m_32_steps.zip",
        "m_vecnormalize_32_steps.npz",
    ]
    loaded = VecNormalize.load(
        str(tmp_path / "m_vecnormalize_32_steps.npz"), make_vec_env("CartPole-v1", 2)
    )
    np.testing.assert_array_equal(loaded.obs_rms.mean, env.obs_rms.mean)


def test_event_callback_triggers_its_child_as_sb3():
    from stable_baselines3.common.callbacks import EventCallback as SB3EventCallback

    from palaestra.algos.callbacks import EventCallback

    class Fire(EventCallback):
        def _on_step(self) -> bool:
            return self._on_event()

    class SB3Fire(SB3EventCallback):
        def _on_step(self) -> bool:
            return self._on_event()

    for outer_cls, inner in ((Fire, _Count()), (SB3Fire, _sb3_count())):
        outer = outer_cls(inner)
        assert inner.parent is outer
        outer.model = inner.model = SimpleNamespace(num_timesteps=0)
        assert outer.on_step() and outer.on_step()
        assert inner.n_calls == 2


def _sb3_count():
    return type("C", (sb3_callbacks.BaseCallback,), {"_on_step": lambda self: True})()


@pytest.mark.parametrize("algo", ["PPO", "DQN"])
def test_log_every_n_timesteps_dumps_as_sb3(tmp_path, algo):
    """SB3's ``LogEveryNTimesteps``: ``model.dump_logs()`` every n env steps (the rows of a
    CSV logger with the algorithm's own dumps switched off)."""
    import csv

    import gymnasium
    import stable_baselines3 as sb3
    from stable_baselines3.common.callbacks import LogEveryNTimesteps as SB3Log
    from stable_baselines3.common.logger import configure as sb3_configure

    from palaestra import algos
    from palaestra.algos.callbacks import LogEveryNTimesteps
    from palaestra.algos.logger import configure

    kwargs = (
        {"n_steps": 32, "batch_size": 32, "n_epochs": 1}
        if algo == "PPO"
        else {"learning_starts": 50, "buffer_size": 500}
    )
    rows = []
    for lib, env, callback, make_logger in [
        (algos, "CartPole-v1", LogEveryNTimesteps(50), configure),
        (sb3, gymnasium.make("CartPole-v1"), SB3Log(50), sb3_configure),
    ]:
        model = getattr(lib, algo)("MlpPolicy", env, seed=0, **kwargs)
        folder = tmp_path / lib.__name__
        model.set_logger(make_logger(str(folder), ["csv"]))
        model.learn(256, callback=callback, log_interval=None)
        with open(folder / "progress.csv") as f:
            table = list(csv.DictReader(f))
        rows.append((len(table), [int(r["time/total_timesteps"]) for r in table]))
    assert rows[0] == rows[1]
    assert rows[0][0] >= 4
