"""``palaestra.algos.buffers`` against SB3's ``common.buffers`` on the same seeded data: the
same samples, the same GAE, the same minibatches (issue 16: CleanRL's ``dqn.py`` imports SB3's
``ReplayBuffer``; ported in spirit from SB3's ``tests/test_buffers.py`` and ``test_gae.py``)."""

from __future__ import annotations

import random
from typing import Any

import numpy as np
import pytest
import torch

import palaestra
from palaestra import spaces
from palaestra.algos import buffers as ours

sb3_buffers = pytest.importorskip("stable_baselines3.common.buffers")
to_gym = pytest.importorskip("palaestra.compat").to_gymnasium_space


def _assert_same(a: Any, b: Any) -> None:
    """Two samples (NamedTuples of tensors or dicts of tensors) hold equal tensors."""
    assert type(a).__name__ == type(b).__name__ and a._fields == b._fields
    for field, x, y in zip(a._fields, a, b):
        if isinstance(x, dict):
            assert x.keys() == y.keys(), field
            pairs = [(x[k], y[k]) for k in x]
        else:
            pairs = [(x, y)]
        for u, v in pairs:
            if u is None:
                assert v is None, field
                continue
            assert u.dtype == v.dtype and u.shape == v.shape, (field, u.dtype, v.dtype)
            assert torch.equal(u, v), field


def _cleanrl_dqn(rb_class: Any, space: Any, steps: int = 130, seed: int = 1) -> list[Any]:
    """CleanRL's ``dqn.py`` loop, shortened: the samples it draws and its losses."""
    random.seed(seed)
    np.random.seed(seed)  # noqa: NPY002 - the buffers sample from it, as CleanRL seeds it
    torch.manual_seed(seed)
    envs = palaestra.vector.SyncVectorEnv([lambda: palaestra.make("CartPole-v1")] * 2)
    envs.single_action_space.seed(seed)
    q_network = torch.nn.Sequential(torch.nn.Linear(4, 16), torch.nn.ReLU(), torch.nn.Linear(16, 2))
    optimizer = torch.optim.Adam(q_network.parameters(), lr=1e-3)
    rb = rb_class(
        100,  # 50 rows of 2 envs, fewer than the run's steps: the ring wraps
        space(envs.single_observation_space),
        space(envs.single_action_space),
        "cpu",
        n_envs=2,
        handle_timeout_termination=False,
    )
    obs, _ = envs.reset(seed=seed)
    drawn: list[Any] = []
    for global_step in range(steps):
        if random.random() < max(0.05, 1.0 - global_step / 100):
            actions = np.array([envs.single_action_space.sample() for _ in range(envs.num_envs)])
        else:
            actions = torch.argmax(q_network(torch.Tensor(obs)), dim=1).numpy()
        next_obs, rewards, terminations, _truncations, infos = envs.step(actions)
        real_next_obs = next_obs.copy()  # (autoreset: NEXT_STEP, the final obs is next_obs)
        rb.add(obs, real_next_obs, actions, rewards, terminations, infos)
        obs = next_obs
        if global_step > 20 and global_step % 4 == 0:
            data = rb.sample(16)
            with torch.no_grad():
                target_max, _ = q_network(data.next_observations).max(dim=1)
                td_target = data.rewards.flatten() + 0.99 * target_max * (1 - data.dones.flatten())
            old_val = q_network(data.observations).gather(1, data.actions).squeeze()
            loss = torch.nn.functional.mse_loss(td_target, old_val)
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            drawn.append((data, loss.item()))
    assert rb.full and rb.size() == 50 and rb.pos == (steps % 50)
    return drawn


def test_cleanrl_dqn_loop_draws_sb3s_samples() -> None:
    mine = _cleanrl_dqn(ours.ReplayBuffer, lambda s: s)  # palaestra's own spaces
    theirs = _cleanrl_dqn(sb3_buffers.ReplayBuffer, to_gym)
    assert len(mine) == len(theirs) > 25
    for (a, loss_a), (b, loss_b) in zip(mine, theirs):
        _assert_same(a, b)
        assert loss_a == loss_b


def _fill(buffer: Any, space: Any, n_envs: int, steps: int, seed: int) -> None:
    """The same transitions into either buffer (observations from ``space``, timeouts in
    the infos)."""
    rng = np.random.default_rng(seed)
    space.seed(seed)

    def batch() -> Any:
        samples = [space.sample() for _ in range(n_envs)]
        if isinstance(space, spaces.Dict):
            return {k: np.stack([s[k] for s in samples]) for k in space.spaces}
        return np.stack(samples)

    for _ in range(steps):
        dones = rng.random(n_envs) < 0.3
        infos = [{"TimeLimit.truncated": bool(d and rng.random() < 0.5)} for d in dones]
        actions = rng.uniform(-1, 1, (n_envs, 2)).astype(np.float64)  # cast to float32
        buffer.add(batch(), batch(), actions, rng.normal(size=n_envs), dones, infos)


DICT = spaces.Dict(
    {"pos": spaces.Box(-1, 1, (3,)), "cell": spaces.Discrete(5), "img": spaces.MultiBinary(4)}
)


@pytest.mark.parametrize(
    ("cls", "space", "kwargs"),
    [
        ("ReplayBuffer", spaces.Box(-1, 1, (3,)), {}),
        ("ReplayBuffer", spaces.Discrete(7), {}),
        ("ReplayBuffer", spaces.Box(0, 255, (4, 4, 1), np.uint8), {}),
        (
            "ReplayBuffer",
            spaces.Box(-1, 1, (3,)),
            {"optimize_memory_usage": True, "handle_timeout_termination": False},
        ),
        ("DictReplayBuffer", DICT, {}),
        ("DictReplayBuffer", DICT, {"handle_timeout_termination": False}),
    ],
)
def test_replay_samples_equal_sb3(cls: str, space: Any, kwargs: dict[str, Any]) -> None:
    action_space = spaces.Box(-1, 1, (2,), np.float64)
    made = [
        getattr(ours, cls)(50, space, action_space, "cpu", n_envs=3, **kwargs),
        getattr(sb3_buffers, cls)(50, to_gym(space), to_gym(action_space), "cpu", 3, **kwargs),
    ]
    drawn = []
    for buffer in made:
        assert buffer.buffer_size == 16 and buffer.actions.dtype == np.float32
        _fill(buffer, space, 3, 10, seed=4)
        sizes = [buffer.size(), buffer.pos, buffer.full]
        _fill(buffer, space, 3, 10, seed=5)  # wraps the ring
        sizes += [buffer.size(), buffer.pos, buffer.full]
        np.random.seed(0)  # noqa: NPY002
        drawn.append((sizes, [buffer.sample(8) for _ in range(4)]))
        buffer.reset()
        assert buffer.size() == 0 and not buffer.full
    (sizes_a, a), (sizes_b, b) = drawn
    assert sizes_a == sizes_b == [10, 10, False, 16, 4, True]
    for x, y in zip(a, b):
        _assert_same(x, y)


@pytest.mark.parametrize("space", [spaces.Box(-1, 1, (3,)), DICT])
@pytest.mark.parametrize("action_space", [spaces.Discrete(3), spaces.Box(-1, 1, (2,))])
def test_rollout_gae_and_minibatches_equal_sb3(space: Any, action_space: Any) -> None:
    name = "DictRolloutBuffer" if isinstance(space, spaces.Dict) else "RolloutBuffer"
    args = dict(device="cpu", gae_lambda=0.9, gamma=0.97, n_envs=2)
    made = [
        getattr(ours, name)(8, space, action_space, **args),
        getattr(sb3_buffers, name)(8, to_gym(space), to_gym(action_space), **args),
    ]
    results = []
    for buffer in made:
        rng = np.random.default_rng(7)
        space.seed(7)
        action_space.seed(7)
        for _ in range(8):
            obs = [space.sample() for _ in range(2)]
            obs = (
                {k: np.stack([o[k] for o in obs]) for k in space.spaces}
                if isinstance(space, spaces.Dict)
                else np.stack(obs)
            )
            buffer.add(
                obs,
                np.stack([action_space.sample() for _ in range(2)]),
                rng.normal(size=2).astype(np.float32),
                rng.random(2) < 0.2,
                torch.as_tensor(rng.normal(size=(2, 1)), dtype=torch.float32),
                torch.as_tensor(rng.normal(size=2), dtype=torch.float32),
            )
        assert buffer.full and buffer.pos == 8
        buffer.compute_returns_and_advantage(
            torch.as_tensor([[0.5], [-0.25]]), np.array([True, False])
        )
        gae = (buffer.advantages.copy(), buffer.returns.copy())
        np.random.seed(3)  # noqa: NPY002
        results.append((gae, list(buffer.get(5)) + list(buffer.get())))
    ((adv_a, ret_a), a), ((adv_b, ret_b), b) = results
    np.testing.assert_array_equal(adv_a, adv_b)
    np.testing.assert_array_equal(ret_a, ret_b)
    assert len(a) == len(b) == 5
    for x, y in zip(a, b):
        _assert_same(x, y)


def test_bad_input() -> None:
    box, dict_space = spaces.Box(-1, 1, (3,)), DICT
    with pytest.raises(ValueError, match=r"cannot store Dict.*use DictReplayBuffer"):
        ours.ReplayBuffer(10, dict_space, spaces.Discrete(2))
    with pytest.raises(ValueError, match="use ReplayBuffer"):
        ours.DictReplayBuffer(10, box, spaces.Discrete(2))
    with pytest.raises(ValueError, match="use DictRolloutBuffer"):
        ours.RolloutBuffer(10, dict_space, spaces.Discrete(2))
    with pytest.raises(ValueError, match="buffer_size must be a positive integer, got 0"):
        ours.ReplayBuffer(0, box, spaces.Discrete(2))
    with pytest.raises(ValueError, match="n_envs must be a positive integer, got -1"):
        ours.RolloutBuffer(4, box, spaces.Discrete(2), n_envs=-1)
    # Gymnasium spaces are taken as the palaestra spaces they describe
    converted = ours.ReplayBuffer(10, to_gym(dict_space["pos"]), to_gym(spaces.Discrete(2)))
    assert converted.observation_space == box and converted.action_space == spaces.Discrete(2)
    with pytest.raises(TypeError, match="must be a palaestra or Gymnasium space"):
        ours.ReplayBuffer(10, (3,), spaces.Discrete(2))
    message = "does not support optimize_memory_usage = True and handle_timeout_termination"
    for module in (ours, sb3_buffers):
        with pytest.raises(ValueError, match=message):
            module.ReplayBuffer(10, to_gym(box), to_gym(box), optimize_memory_usage=True)
    with pytest.raises(ValueError, match="DictReplayBuffer does not support optimize_memory"):
        ours.DictReplayBuffer(
            10, dict_space, box, optimize_memory_usage=True, handle_timeout_termination=False
        )
    rb = ours.ReplayBuffer(10, box, spaces.Discrete(2))
    with pytest.raises(TypeError, match="infos must be the list of per-env info dicts"):
        rb.add(np.zeros((1, 3)), np.zeros((1, 3)), np.zeros(1), np.zeros(1), np.zeros(1), {})
    rollout = ours.RolloutBuffer(2, box, spaces.Discrete(2))
    with pytest.raises(ValueError, match="not full yet"):
        next(rollout.get())
    for _ in range(2):
        rollout.add(np.zeros((1, 3)), np.zeros(1), np.zeros(1), np.zeros(1), *[torch.zeros(1)] * 2)
    with pytest.raises(ValueError, match="the rollout buffer is full"):
        rollout.add(np.zeros((1, 3)), np.zeros(1), np.zeros(1), np.zeros(1), *[torch.zeros(1)] * 2)


@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.int64, np.uint8, None])
def test_maybe_cast_dtype_as_sb3(dtype: Any) -> None:
    """SB3's tests call ``ReplayBuffer._maybe_cast_dtype``: offered, with SB3's answers."""
    assert ours.ReplayBuffer._maybe_cast_dtype(dtype) == sb3_buffers.ReplayBuffer._maybe_cast_dtype(
        dtype
    )
    box = spaces.Box(-1, 1, (2,), np.float64)
    for lib, space in ((ours, box), (sb3_buffers, to_gym(box))):
        buffer = lib.ReplayBuffer(4, to_gym(spaces.Box(-1, 1, (3,))), space, "cpu")
        assert buffer.actions.dtype == np.float32


@pytest.mark.parametrize(
    ("env_id", "n_envs"), [("CartPole-v1", 2), ("Pendulum-v1", 1)], ids=["discrete", "box"]
)
def test_model_rollout_buffer_answers_sb3s_calls(env_id: str, n_envs: int) -> None:
    """``model.rollout_buffer`` as callbacks see it: ``size()``, ``buffer_size``, ``full`` and
    ``get`` give what SB3's PPO's buffer gives (shapes, dtypes, sample types)."""
    import stable_baselines3 as sb3

    from palaestra.algos import PPO
    from palaestra.algos.callbacks import BaseCallback
    from palaestra.vec_env import make_vec_env

    seen = []
    for lib in (palaestra, sb3):

        class Probe(BaseCallback if lib is palaestra else sb3.common.callbacks.BaseCallback):  # type: ignore[misc]
            def _on_step(self) -> bool:
                buf = self.model.rollout_buffer
                if buf.size() == 3:
                    seen.append(("mid", buf.size(), buf.full))
                return True

            def _on_rollout_end(self) -> None:
                buf = self.locals["rollout_buffer"]
                samples = list(buf.get(10))
                fields = [
                    (f, tuple(getattr(s, f).shape), getattr(s, f).dtype)
                    for s in samples[:1]
                    for f in s._fields
                ]
                seen.append(
                    (
                        "end",
                        buf.size(),
                        buf.buffer_size,
                        buf.full,
                        len(samples),
                        fields,
                        type(samples[0]).__name__,
                    )
                )

        if lib is palaestra:
            env = make_vec_env(env_id, n_envs=n_envs, seed=0)
            PPO("MlpPolicy", env, n_steps=8, batch_size=8, n_epochs=1).learn(
                8 * n_envs, callback=Probe()
            )
        else:
            sb3_env = sb3.common.env_util.make_vec_env(env_id, n_envs=n_envs, seed=0)
            sb3.PPO("MlpPolicy", sb3_env, n_steps=8, batch_size=8, n_epochs=1, device="cpu").learn(
                8 * n_envs, callback=Probe()
            )
    ours_mid, ours_end, theirs_mid, theirs_end = seen
    assert ours_mid[1:] == theirs_mid[1:] == (3, False)
    assert ours_end == theirs_end
    assert ours_end[1:4] == (8, 8, True)
