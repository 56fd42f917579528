"""Exact resume and training on Dict observations: ``VecNormalize``'s per-key statistics and
``VecFrameStack``'s per-key stacks in the run state, the eval-env sync, ``CheckpointCallback``
saving Dict statistics, and ``PPO("MultiInputPolicy")`` on a normalised Dict env."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from palaestra import spaces
from palaestra.error import RunStateError
from palaestra.vec_env import (
    VecEnv,
    VecEnvWrapper,
    VecFrameStack,
    VecNormalize,
    make_vec_env,
    sync_envs_normalization,
)


class SplitCartPole(VecEnvWrapper):
    """Native CartPole (which can save its run state) seen as a Dict: ``cart`` (position,
    velocity) and ``pole`` (angle, angular velocity)."""

    RUN_STATE = ("venv",)

    def __init__(self, venv: VecEnv) -> None:
        box = venv.observation_space
        assert isinstance(box, spaces.Box)
        split = {
            "cart": spaces.Box(box.low[:2], box.high[:2], dtype=np.float32),
            "pole": spaces.Box(box.low[2:], box.high[2:], dtype=np.float32),
        }
        super().__init__(venv, observation_space=spaces.Dict(split))

    @staticmethod
    def split(obs: np.ndarray) -> dict[str, np.ndarray]:
        return {"cart": obs[..., :2].copy(), "pole": obs[..., 2:].copy()}

    def reset(self) -> Any:
        return self.split(self.venv.reset())

    def step_wait(self) -> Any:
        obs, rewards, dones, infos = self.venv.step_wait()
        for info in infos:
            if "terminal_observation" in info:
                info["terminal_observation"] = self.split(info["terminal_observation"])
        return self.split(obs), rewards, dones, infos


def _stack(seed: int = 5, **norm: Any) -> VecFrameStack:
    venv = SplitCartPole(make_vec_env("CartPole-v1", n_envs=3, seed=seed))
    orders = {"cart": "last", "pole": "first"}
    return VecFrameStack(VecNormalize(venv, **norm), 2, channels_order=orders)


def _same(x: dict[str, np.ndarray], y: dict[str, np.ndarray]) -> bool:
    return x.keys() == y.keys() and all(np.array_equal(x[k], y[k]) for k in x)


def test_restored_dict_stack_continues_identically() -> None:
    a, b = _stack(), _stack()
    rng = np.random.default_rng(0)
    actions = [rng.integers(0, 2, 3) for _ in range(400)]
    a.reset()
    for act in actions[:200]:
        a.step(act)
    meta, arrays = a.get_run_state()
    # the per-key statistics and stacks are in it, numbered, their keys in the metadata
    norm_meta = meta["venv"]["object"]
    assert [k for k, _ in norm_meta["obs_rms"]["objects"]] == ["cart", "pole"]
    assert {"venv/obs_rms/0/mean", "venv/obs_rms/1/var"} <= set(arrays)
    assert "stacked_obs/sub_stacked_observations/1/stacked_obs" in arrays
    b.set_run_state((meta, arrays))  # b was never reset: the state is all it needs
    ended = 0
    for act in actions[200:]:
        oa, ra, da, ia = a.step(act)
        ob, rb, db, ib = b.step(act)
        assert _same(oa, ob) and np.array_equal(ra, rb) and np.array_equal(da, db)
        for x, y in zip(ia, ib):
            assert x.keys() == y.keys()
            if "terminal_observation" in x:
                assert _same(x["terminal_observation"], y["terminal_observation"])
                ended += 1
    assert ended > 0  # the comparison crossed episode ends
    norm_a, norm_b = a.venv, b.venv
    assert isinstance(norm_a, VecNormalize) and isinstance(norm_b, VecNormalize)
    assert isinstance(norm_a.obs_rms, dict) and isinstance(norm_b.obs_rms, dict)
    for key, rms in norm_a.obs_rms.items():
        assert rms.mean.tobytes() == norm_b.obs_rms[key].mean.tobytes()
        assert rms.count == norm_b.obs_rms[key].count


def test_a_state_for_other_keys_is_refused_whole() -> None:
    a = _stack()
    a.reset()
    a.step(np.zeros(3, dtype=np.int64))
    state = a.get_run_state()
    b = _stack(norm_obs_keys=["pole"])
    before = b.get_run_state()
    other_keys = (
        r"state 'venv/obs_rms' holds the keys \['cart', 'pole'\], this object has \['pole'\]"
    )
    with pytest.raises(RunStateError, match=other_keys):
        b.set_run_state(state)
    after = b.get_run_state()  # nothing changed, the stacks included
    assert after[0] == before[0]
    assert all(np.array_equal(after[1][k], before[1][k]) for k in before[1])
    meta, arrays = a.get_run_state()
    meta["venv"]["object"]["obs_rms"] = {"objects": "cart"}
    with pytest.raises(RunStateError, match=r"'venv/obs_rms' holds the keys 'str'"):
        a.set_run_state((meta, arrays))
    meta, arrays = a.get_run_state()
    del arrays["venv/obs_rms/1/var"]
    with pytest.raises(RunStateError, match=r"lacks the array 'venv/obs_rms/1/var'"):
        a.set_run_state((meta, arrays))


def test_sync_copies_dict_statistics() -> None:
    train = VecNormalize(SplitCartPole(make_vec_env("CartPole-v1", n_envs=2, seed=1)))
    evaluation = VecNormalize(
        SplitCartPole(make_vec_env("CartPole-v1", n_envs=1, seed=2)), training=False
    )
    train.reset()
    for _ in range(30):
        train.step(np.ones(2, dtype=np.int64))
    sync_envs_normalization(train, evaluation)
    assert isinstance(train.obs_rms, dict) and isinstance(evaluation.obs_rms, dict)
    for key, rms in train.obs_rms.items():
        assert evaluation.obs_rms[key] is not rms  # a copy, not the training env's object
        assert np.array_equal(evaluation.obs_rms[key].mean, rms.mean)
        assert evaluation.obs_rms[key].count == rms.count == 62 + 1e-4
    train.step(np.ones(2, dtype=np.int64))
    assert evaluation.obs_rms["cart"].count == 62 + 1e-4


def test_ppo_multi_input_trains_and_checkpoints_dict_statistics(tmp_path: Path) -> None:
    from palaestra.algos import PPO
    from palaestra.algos.callbacks import CheckpointCallback, EvalCallback

    def env(seed: int, **kwargs: Any) -> VecNormalize:
        split = SplitCartPole(make_vec_env("CartPole-v1", n_envs=2, seed=seed))
        return VecNormalize(split, **kwargs)

    venv = env(0)
    eval_env = env(9, training=False, norm_reward=False)
    model = PPO("MultiInputPolicy", venv, n_steps=32, batch_size=32, n_epochs=1, seed=0)
    checkpoint = CheckpointCallback(16, str(tmp_path), save_vecnormalize=True)  # calls of 2 steps
    evaluation = EvalCallback(eval_env, n_eval_episodes=1, eval_freq=32, verbose=0)
    model.learn(128, callback=[checkpoint, evaluation])
    assert isinstance(venv.obs_rms, dict) and isinstance(eval_env.obs_rms, dict)
    assert venv.obs_rms["pole"].count > 128  # trained on normalised observations
    # the eval env saw the training statistics of the last evaluation (a copy)
    assert eval_env.obs_rms["pole"].count == venv.obs_rms["pole"].count == 130 + 1e-4
    assert eval_env.obs_rms["pole"] is not venv.obs_rms["pole"]
    saved = sorted(tmp_path.glob("rl_model_vecnormalize_*_steps.npz"))
    assert [p.name for p in saved] == [
        f"rl_model_vecnormalize_{n}_steps.npz" for n in (128, 32, 64, 96)
    ]
    loaded = VecNormalize.load(saved[0], SplitCartPole(make_vec_env("CartPole-v1", n_envs=2)))
    assert isinstance(loaded.obs_rms, dict)
    assert loaded.obs_rms["cart"].mean.tobytes() == venv.obs_rms["cart"].mean.tobytes()
    obs = loaded.normalize_obs(venv.get_original_obs())
    action, _ = model.predict(obs, deterministic=True)
    assert action.shape == (2,)
