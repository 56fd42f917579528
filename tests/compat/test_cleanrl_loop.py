"""A CleanRL-style DQN loop runs on palaestra with the same episode returns as on Gymnasium
(issue 16, item 13).

CleanRL's ``dqn.py`` (ported to Gymnasium 1.x) builds SB3's ``ReplayBuffer`` from
``envs.single_observation_space``; SB3 checks Gymnasium's space types, so palaestra's spaces are
handed over with ``palaestra.compat.to_gymnasium_space`` (what the README says). Everything
else in the loop (vector env, ``RecordEpisodeStatistics``, seeding, sampling) is palaestra's,
and the returns equal the loop run on gymnasium itself, episode for episode.
"""

from __future__ import annotations

import random

import gymnasium
import numpy as np
import pytest
import torch
from stable_baselines3.common.buffers import ReplayBuffer

import palaestra
from palaestra.compat import to_gymnasium_space


def _run(lib, buffer_space, steps=800, seed=1):
    random.seed(seed)
    np.random.seed(seed)  # noqa: NPY002 - SB3's ReplayBuffer samples from it
    torch.manual_seed(seed)

    def make_env():
        return lib.wrappers.RecordEpisodeStatistics(lib.make("CartPole-v1"))

    envs = lib.vector.SyncVectorEnv([make_env])
    envs.single_action_space.seed(seed)
    q_network = torch.nn.Sequential(torch.nn.Linear(4, 32), torch.nn.ReLU(), torch.nn.Linear(32, 2))
    optimizer = torch.optim.Adam(q_network.parameters(), lr=2.5e-3)
    rb = ReplayBuffer(
        1000,
        buffer_space(envs.single_observation_space),
        buffer_space(envs.single_action_space),
        "cpu",
        handle_timeout_termination=False,
    )
    obs, _ = envs.reset(seed=seed)
    returns = []
    for global_step in range(steps):
        epsilon = max(0.05, 1.0 - global_step / 500)
        if random.random() < epsilon:
            actions = np.array([envs.single_action_space.sample() for _ in range(envs.num_envs)])
        else:
            actions = torch.argmax(q_network(torch.Tensor(obs)), dim=1).numpy()
        next_obs, rewards, terminations, _truncations, infos = envs.step(actions)
        if "episode" in infos:
            returns.extend(infos["episode"]["r"][infos["_episode"]].tolist())
        rb.add(obs, next_obs.copy(), actions, rewards, terminations, [{}])
        obs = next_obs
        if global_step > 200 and global_step % 10 == 0:
            data = rb.sample(32)
            with torch.no_grad():
                target_max, _ = q_network(data.next_observations).max(dim=1)
                td_target = data.rewards.flatten() + 0.99 * target_max * (1 - data.dones.flatten())
            old_val = q_network(data.observations).gather(1, data.actions).squeeze()
            loss = torch.nn.functional.mse_loss(td_target, old_val)
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
    envs.close()
    return returns


@pytest.mark.slow
def test_cleanrl_dqn_loop_has_gymnasiums_episode_returns():
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # same arithmetic both runs, and no thread contention
    try:
        ours = _run(palaestra, to_gymnasium_space)
        theirs = _run(gymnasium, lambda space: space)
    finally:
        torch.set_num_threads(threads)
    assert len(theirs) > 20
    assert ours == theirs


def test_sb3_buffer_refuses_palaestra_spaces_without_the_adapter():
    # What the README's hand-over paragraph is for: SB3 checks Gymnasium's types.
    with pytest.raises(NotImplementedError):
        ReplayBuffer(10, palaestra.spaces.Box(-1, 1, (4,)), palaestra.spaces.Discrete(2))
    buffer = ReplayBuffer(
        10,
        to_gymnasium_space(palaestra.spaces.Box(-1, 1, (4,))),
        to_gymnasium_space(palaestra.spaces.Discrete(2)),
    )
    assert buffer.observations.shape == (10, 1, 4)


@pytest.mark.parametrize(
    "helper",
    ["batch_space", "create_empty_array", "flatten_space", "flatdim"],
)
def test_palaestra_helpers_name_the_adapter_for_a_gymnasium_space(helper):
    import palaestra.spaces
    import palaestra.vector.utils

    function = getattr(palaestra.vector.utils, helper, None) or getattr(palaestra.spaces, helper)
    args = (gymnasium.spaces.Discrete(3),) + ((2,) if helper == "batch_space" else ())
    with pytest.raises((TypeError, NotImplementedError), match="from_gymnasium_space"):
        function(*args)


def test_vec_env_of_a_gymnasium_env_names_the_adapter():
    from palaestra.vec_env import DummyVecEnv

    with pytest.raises(TypeError, match=r"palaestra\.compat\.from_gymnasium\(env\)"):
        DummyVecEnv([lambda: gymnasium.make("CartPole-v1")])
