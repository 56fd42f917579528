"""Golden training runs: fixed seeds, a few hundred updates on the numpy learner, and a hash
of the final parameters and optimizer state. Recorded before the learners refactor (#13), so
any change to the numbers the numpy path computes (a reordered sum, a different rounding)
shows up here; a deliberate change must update the hash with the reason in the commit."""

from __future__ import annotations

import ctypes
import glob
import hashlib
import os

import numpy as np
import pytest
import torch

from palaestra.algos import DQN, PPO
from palaestra.vec_env import make_vec_env


def _digest(model: DQN | PPO) -> str:
    """SHA-256 over the policy's state_dict and the optimizer's tensors, in key order."""
    h = hashlib.sha256()
    params = model.get_parameters()
    for key, value in sorted(params["policy"].items()):
        h.update(key.encode())
        h.update(np.ascontiguousarray(value.detach().cpu().numpy()).tobytes())
    for index, state in sorted(params["policy.optimizer"]["state"].items()):
        for name in ("exp_avg", "exp_avg_sq", "step"):
            h.update(f"{index}.{name}".encode())
            h.update(np.ascontiguousarray(torch.as_tensor(state[name]).numpy()).tobytes())
    return h.hexdigest()[:16]


def _blas_core() -> str:
    """The CPU kernel family numpy's OpenBLAS picked: matmul bits depend on it, so the golden
    hashes are kept per kernel family (and skipped on one with none recorded)."""
    root = os.path.join(os.path.dirname(np.__file__), os.pardir, "numpy.libs", "*openblas*")
    for path in glob.glob(root):
        try:
            corename = ctypes.CDLL(path).scipy_openblas_get_corename64_
        except (OSError, AttributeError):
            continue
        corename.restype = ctypes.c_char_p
        return str(corename().decode())
    return "unknown"


# Recorded on the numpy learner before the learners refactor (#13).
GOLDEN = {
    "Haswell": {
        "dqn_cartpole": "27dd0f1b42ffa6b0",
        "ppo_cartpole": "61bb77e785f87aa0",
        "ppo_pendulum": "94cb1e0eb04108f8",
    },
}


def _dqn_cartpole() -> DQN:
    env = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    model = DQN(
        "MlpPolicy",
        env,
        learning_starts=200,
        train_freq=2,
        gradient_steps=1,
        target_update_interval=100,
        batch_size=64,
        seed=0,
    )
    model.learn(1400)  # 300 updates
    return model


def _ppo_cartpole() -> PPO:
    env = make_vec_env("CartPole-v1", n_envs=4, seed=0)
    model = PPO("MlpPolicy", env, n_steps=32, batch_size=32, n_epochs=4, ent_coef=0.01, seed=0)
    model.learn(2048)  # 16 rollouts x 4 epochs x 4 minibatches = 256 updates
    return model


def _ppo_pendulum() -> PPO:
    env = make_vec_env("Pendulum-v1", n_envs=2, seed=0)
    model = PPO(
        "MlpPolicy",
        env,
        n_steps=64,
        batch_size=32,
        n_epochs=4,
        ent_coef=0.01,
        clip_range_vf=0.2,
        seed=0,
    )
    model.learn(2048)  # 16 rollouts x 4 epochs x 4 minibatches = 256 updates
    return model


@pytest.mark.parametrize("name", ["dqn_cartpole", "ppo_cartpole", "ppo_pendulum"])
def test_golden_parameters(name: str) -> None:
    golden = GOLDEN.get(_blas_core())
    if golden is None:
        pytest.skip(f"no golden hashes recorded for OpenBLAS kernels {_blas_core()!r}")
    model = {
        "dqn_cartpole": _dqn_cartpole,
        "ppo_cartpole": _ppo_cartpole,
        "ppo_pendulum": _ppo_pendulum,
    }[name]()
    assert _digest(model) == golden[name]
