"""n-step returns (``n_steps`` of DQN, QR-DQN, SAC, TD3, DDPG; SB3 2.x's ``NStepReplayBuffer``):
the sampled windows against SB3's buffer and against sums computed by hand, cut at
terminations, truncations and the newest transition; the objectives' per-sample discounts;
training on both learners, save/load, resume and bad values."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from palaestra import spaces
from palaestra.algos import DDPG, DQN, QRDQN, SAC, TD3, ModelFileError
from palaestra.algos import buffers as ours
from palaestra.algos.common.nstep import n_step_window
from palaestra.algos.common.transition_ring import TransitionRing
from palaestra.algos.dqn.objective import DQNObjective
from palaestra.algos.learners.xp import numpy_ops
from palaestra.algos.td3.objective import TD3CriticObjective
from palaestra.core import Env
from palaestra.vec_env import make_vec_env

from .toys import Toy

OBS = spaces.Box(-10, 10, (2,), np.float32)
ACT = spaces.Box(-1, 1, (1,), np.float32)


def _transitions(steps: int, n_envs: int, seed: int) -> list[tuple[Any, ...]]:
    """Random one-step transitions: ``(obs, next_obs, actions, rewards, dones, truncated)``
    with episodes ending often, by termination or by truncation (a truncation is a done)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(steps):
        dones = rng.random(n_envs) < 0.25
        truncated = dones & (rng.random(n_envs) < 0.5)
        out.append(
            (
                rng.normal(size=(n_envs, 2)).astype(np.float32),
                rng.normal(size=(n_envs, 2)).astype(np.float32),
                rng.uniform(-1, 1, size=(n_envs, 1)).astype(np.float32),
                rng.normal(size=n_envs).astype(np.float32),
                dones,
                truncated,
            )
        )
    return out


# -- the sampled windows against SB3's NStepReplayBuffer -----------------------------------------
@pytest.mark.parametrize("n_steps", [3, 10])
@pytest.mark.parametrize("steps", [13, 47])  # 20 rows: not full; wrapped twice, pos 7
@pytest.mark.parametrize("handle_timeout_termination", [True, False])
def test_same_windows_as_sb3(n_steps: int, steps: int, handle_timeout_termination: bool) -> None:
    sb3_buffers = pytest.importorskip("stable_baselines3.common.buffers")
    from palaestra.compat import to_gymnasium_space

    n_envs, gamma = 2, 0.9
    args = (40, to_gymnasium_space(OBS), to_gymnasium_space(ACT), "cpu", n_envs)
    kwargs = dict(handle_timeout_termination=handle_timeout_termination, n_steps=n_steps)
    theirs = sb3_buffers.NStepReplayBuffer(*args, gamma=gamma, **kwargs)
    face = ours.NStepReplayBuffer(40, OBS, ACT, "cpu", n_envs, gamma=gamma, **kwargs)
    ring = TransitionRing(40, OBS, ACT, n_envs, gamma=gamma, **kwargs)
    for obs, next_obs, actions, rewards, dones, truncated in _transitions(steps, n_envs, 1):
        infos = [{"TimeLimit.truncated": bool(t)} for t in truncated]
        theirs.add(obs, next_obs, actions, rewards, dones, infos)
        face.add(obs, next_obs, actions, rewards, dones, infos)
        ring.add(obs, next_obs, actions, rewards, dones, truncated)
    rows = np.repeat(np.arange(ring.size()), 4)  # every row, each env drawn several times
    # SB3's buffers draw each sample's env from numpy's global generator
    np.random.seed(3)  # noqa: NPY002
    expected = theirs._get_samples(rows)
    np.random.seed(3)  # noqa: NPY002
    cols = np.random.randint(0, n_envs, size=rows.shape)  # noqa: NPY002
    got_ring = ring.get(rows, cols)
    np.random.seed(3)  # noqa: NPY002
    got_face = face._get_samples(rows)
    assert len(set(cols.tolist())) == n_envs
    want = {
        "observations": expected.observations.numpy(),
        "actions": expected.actions.numpy(),
        "next_observations": expected.next_observations.numpy(),
        "rewards": expected.rewards.numpy().ravel(),
        "terminated": expected.dones.numpy().ravel(),
        "discounts": expected.discounts.numpy().ravel(),
    }
    assert len(np.unique(want["discounts"])) >= 3  # windows of several lengths
    # SB3 sums a window with numpy's pairwise summation: the same bits below 8 terms, the
    # same to 1e-6 above.
    close = functools.partial(np.testing.assert_allclose, rtol=1e-6, atol=1e-6)
    check = np.testing.assert_array_equal if n_steps < 8 else close
    for name, value in zip(want, got_ring):
        assert value.dtype == want[name].dtype, name
        if name == "rewards":
            check(value, want[name], err_msg=name)
        else:
            np.testing.assert_array_equal(value, want[name], err_msg=name)
    assert got_face._fields == expected._fields
    for name, x, y in zip(expected._fields, expected, got_face):
        assert x.dtype == y.dtype and x.shape == y.shape, name
        if name == "rewards":
            check(y.numpy(), x.numpy(), err_msg=name)
        else:
            assert torch.equal(x, y), name


def test_sb3_face_buffer_samples_and_normalizes_as_sb3() -> None:
    """``sample`` (rows from numpy's generator) and a VecNormalize's reward scaling, summed
    after scaling as SB3 sums them."""
    sb3_buffers = pytest.importorskip("stable_baselines3.common.buffers")
    from palaestra.compat import to_gymnasium_space

    class Halves:
        def normalize_obs(self, obs: Any) -> Any:
            return obs * 2.0

        def normalize_reward(self, reward: Any) -> Any:
            return np.clip(reward / 2.0, -0.3, 0.3)

    theirs = sb3_buffers.NStepReplayBuffer(
        30, to_gymnasium_space(OBS), to_gymnasium_space(ACT), "cpu", 1, n_steps=4, gamma=0.8
    )
    face = ours.NStepReplayBuffer(30, OBS, ACT, "cpu", 1, n_steps=4, gamma=0.8)
    for obs, next_obs, actions, rewards, dones, truncated in _transitions(25, 1, 2):
        infos = [{"TimeLimit.truncated": bool(t)} for t in truncated]
        theirs.add(obs, next_obs, actions, rewards, dones, infos)
        face.add(obs, next_obs, actions, rewards, dones, infos)
    np.random.seed(5)  # noqa: NPY002
    expected = theirs.sample(64, env=Halves())
    np.random.seed(5)  # noqa: NPY002
    got = face.sample(64, env=Halves())
    for name, x, y in zip(expected._fields, expected, got):
        assert torch.equal(x, y), name
    with pytest.raises(NotImplementedError, match="optimize_memory_usage"):
        ours.NStepReplayBuffer(30, OBS, ACT, optimize_memory_usage=True)
    with pytest.raises(ValueError, match=r"n_steps must be an integer >= 1, got 0"):
        ours.NStepReplayBuffer(30, OBS, ACT, n_steps=0)


# -- by hand ------------------------------------------------------------------------------------
def _hand_ring() -> TransitionRing:
    """One env, rewards 1..12: the episode terminates at row 3, is truncated at row 7, and row
    11 is the newest (its episode goes on); next observations are ``[row, 0]``."""
    ring = TransitionRing(16, OBS, ACT, 1, n_steps=3, gamma=0.9)
    for t in range(12):
        ring.add(
            np.array([[t - 1, 0]], np.float32),
            np.array([[t, 0]], np.float32),
            np.zeros((1, 1), np.float32),
            np.array([t + 1], np.float32),
            np.array([t in (3, 7)]),
            np.array([t == 7]),
        )
    return ring


# row: (discounted sum, discount, terminated, row of the next observation), gamma 0.9
BY_HAND = {
    0: (1 + 0.9 * 2 + 0.81 * 3, 0.729, 0.0, 2),  # a whole window
    1: (2 + 0.9 * 3 + 0.81 * 4, 0.729, 1.0, 3),  # ends at the termination, inclusive
    2: (3 + 0.9 * 4, 0.81, 1.0, 3),  # cut by the termination
    3: (4, 0.9, 1.0, 3),
    4: (5 + 0.9 * 6 + 0.81 * 7, 0.729, 0.0, 6),
    5: (6 + 0.9 * 7 + 0.81 * 8, 0.729, 0.0, 7),  # ends at the truncation: bootstraps
    6: (7 + 0.9 * 8, 0.81, 0.0, 7),  # cut by the truncation: bootstraps from its last obs
    7: (8, 0.9, 0.0, 7),
    9: (10 + 0.9 * 11 + 0.81 * 12, 0.729, 0.0, 11),
    10: (11 + 0.9 * 12, 0.81, 0.0, 11),  # cut by the newest transition (no successor yet)
    11: (12, 0.9, 0.0, 11),
}


def test_rewards_are_discounted_sums_cut_at_termination_and_truncation() -> None:
    ring = _hand_ring()
    rows = np.array(sorted(BY_HAND))
    _, _, next_obs, rewards, terminated, discounts = ring.get(rows, np.zeros_like(rows))
    sums, disc, term, last = (np.array(column) for column in zip(*(BY_HAND[r] for r in rows)))
    np.testing.assert_allclose(rewards, sums, rtol=1e-6)
    np.testing.assert_allclose(discounts, disc, rtol=1e-6)
    np.testing.assert_array_equal(terminated, term)
    np.testing.assert_array_equal(next_obs[:, 0], last)
    assert rewards.dtype == discounts.dtype == np.float32


def test_a_full_ring_never_joins_the_newest_to_the_oldest() -> None:
    """Wrapped around: the newest row (pos - 1) ends windows; windows of the oldest rows run
    on across the end of the array into the rows after it."""
    ring = TransitionRing(4, OBS, ACT, 1, n_steps=3, gamma=0.5)
    for t in range(6):  # rows hold t = 4, 5, 2, 3; pos = 2, newest row 1 (t = 5)
        ring.add(
            np.zeros((1, 2), np.float32),
            np.array([[t, 0]], np.float32),
            np.zeros((1, 1), np.float32),
            np.array([2.0**t], np.float32),
            np.array([False]),
            np.array([False]),
        )
    _, _, next_obs, rewards, _, discounts = ring.get(np.array([1, 2, 3]), np.zeros(3, int))
    np.testing.assert_array_equal(rewards, [32, 4 + 0.5 * 8 + 0.25 * 16, 8 + 0.5 * 16 + 0.25 * 32])
    np.testing.assert_array_equal(discounts, [0.5, 0.125, 0.125])
    np.testing.assert_array_equal(next_obs[:, 0], [5, 4, 5])


def test_window_stops_once_every_window_is_cut() -> None:
    """A huge n_steps costs only as many steps as the longest window (O(batch) memory)."""
    rewards = np.ones((5, 1), np.float32)
    ended = np.zeros((5, 1), np.float32)
    returns, discounts, last = n_step_window(
        rewards, (ended,), 4, np.array([0, 3]), np.array([0, 0]), 10**15, 0.5
    )
    np.testing.assert_array_equal(returns, [1.9375, 1.5])
    np.testing.assert_array_equal(discounts, [0.03125, 0.25])
    np.testing.assert_array_equal(last, [4, 4])


class Counting(Env[Any, Any]):
    """Observation ``[t, kind]``, reward ``t + 1`` at step ``t`` of an episode; episodes of kind
    0 terminate after 5 steps, of kind 1 are truncated after 7 (they alternate)."""

    LENGTH = {0: 5, 1: 7}

    def __init__(self, action: str = "discrete") -> None:
        self.observation_space = spaces.Box(0, 10, (2,), np.float32)
        self.action_space = spaces.Discrete(2) if action == "discrete" else ACT
        self.t, self.kind = 0, 1

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        self.t, self.kind = 0, 1 - self.kind
        return np.array([0, self.kind], np.float32), {}

    def step(self, action: Any) -> Any:
        reward = float(self.t + 1)
        self.t += 1
        end = self.t == self.LENGTH[self.kind]
        obs = np.array([self.t, self.kind], np.float32)
        return obs, reward, end and self.kind == 0, end and self.kind == 1, {}


def _expected_window(t: int, kind: int, n: int, gamma: float) -> tuple[float, float, float, int]:
    """By hand from the env's rules: ``(sum, discount, terminated, t of the next obs)``."""
    length = min(n, Counting.LENGTH[kind] - t)
    total = sum(gamma**k * (t + k + 1) for k in range(length))
    terminated = float(kind == 0 and t + length == Counting.LENGTH[kind])
    return total, gamma**length, terminated, t + length


@pytest.mark.parametrize(("cls", "action"), [(DQN, "discrete"), (SAC, "box"), (TD3, "box")])
def test_the_models_sampled_batch_holds_hand_computed_sums(cls: Any, action: str) -> None:
    """The batch ``train`` uses, from a model that collected 120 steps (10 pairs of episodes,
    so the newest transition ends an episode and only the env's ends cut windows)."""
    env = make_vec_env(lambda: Counting(action), n_envs=2, seed=0)
    model = cls(
        "MlpPolicy", env, n_steps=3, gamma=0.9, learning_starts=1000, buffer_size=1000, seed=0
    )
    model.learn(120)
    batch = model._sample_batch(256)
    assert set(batch) == {
        "observations",
        "actions",
        "next_observations",
        "rewards",
        "terminated",
        "discounts",
    }
    expected = [_expected_window(int(t), int(k), 3, 0.9) for t, k in batch["observations"]]
    sums, discounts, terminated, next_t = (np.array(c) for c in zip(*expected))
    np.testing.assert_allclose(batch["rewards"], sums, rtol=1e-6)
    np.testing.assert_allclose(batch["discounts"], discounts, rtol=1e-6)
    np.testing.assert_array_equal(batch["terminated"], terminated)
    np.testing.assert_array_equal(batch["next_observations"][:, 0], next_t)
    np.testing.assert_array_equal(batch["next_observations"][:, 1], batch["observations"][:, 1])
    assert {1.0, 0.0} <= set(batch["terminated"].tolist())
    assert len(set(np.round(batch["discounts"], 4).tolist())) == 3  # cut windows are sampled


def test_dict_observations_take_the_windows_last_next_observation() -> None:
    """SB3 asserts ``n_steps == 1`` for Dict observations; here each key is sampled as a
    Box is (``docs/differences.md``)."""
    space = spaces.Dict({"pos": OBS, "mode": spaces.Discrete(3)})
    ring = TransitionRing(16, space, ACT, 1, n_steps=3, gamma=0.9)
    plain = _hand_ring()
    rows = np.arange(12)
    for t in range(12):
        ring.add(
            {"pos": plain.observations[t], "mode": np.array([t % 3])},
            {"pos": plain.next_observations[t], "mode": np.array([(t + 1) % 3])},
            plain.actions[t],
            plain.rewards[t],
            plain.ended[t].astype(bool),
            np.array([t == 7]),
        )
    got, want = ring.get(rows, rows * 0), plain.get(rows, rows * 0)
    np.testing.assert_array_equal(got[2]["pos"], want[2])
    np.testing.assert_array_equal(got[2]["mode"], (want[2][:, 0].astype(int) + 1) % 3)
    for x, y in zip(got[3:], want[3:]):
        np.testing.assert_array_equal(x, y)
    model = DQN(
        "MultiInputPolicy", Toy("dict"), n_steps=3, learning_starts=40, buffer_size=500, seed=0
    )
    assert model.learn(80)._n_updates > 0


# -- the objectives discount each sample by its own ---------------------------------------------
def test_objectives_use_the_per_sample_discounts() -> None:
    q = np.array([[1.0, 2.0], [0.0, 0.0]], np.float32)
    next_q = np.array([[0.0, 4.0], [2.0, 0.0]], np.float32)
    batch = {
        "observations": np.zeros((2, 2), np.float32),
        "next_observations": np.ones((2, 2), np.float32),
        "actions": np.array([1, 0]),
        "rewards": np.array([1.0, 0.5], np.float32),
        "terminated": np.zeros(2, np.float32),
        "discounts": np.array([0.5, 0.25], np.float32),
    }
    run = lambda name, x: q if name == "q" else next_q  # noqa: E731
    _, _, (_, _, diff) = DQNObjective(0.99).loss(numpy_ops, run, {}, batch)
    np.testing.assert_allclose(diff, [2.0 - (1 + 0.5 * 4), 0.0 - (0.5 + 0.25 * 2)])

    def critic(name: str, x: Any) -> np.ndarray:
        if name == "actor_target":
            return np.zeros((2, 1), np.float32)
        return np.full((2, 1), 2.0 if name.endswith("_target") else 0.0, np.float32)

    batch["target_noise"] = np.zeros((2, 1), np.float32)
    batch["actions"] = np.zeros((2, 1), np.float32)
    _, _, (errors, _) = TD3CriticObjective(1, 0.99).loss(numpy_ops, critic, {}, batch)
    np.testing.assert_allclose(-errors[0], [1 + 0.5 * 2, 0.5 + 0.25 * 2])


# -- training, both learners, save/load ----------------------------------------------------------
ALGOS = [
    (DQN, "CartPole-v1", dict(learning_starts=100, train_freq=4, target_update_interval=100)),
    (QRDQN, "CartPole-v1", dict(learning_starts=100, policy_kwargs={"n_quantiles": 8})),
    (SAC, "Pendulum-v1", dict(learning_starts=100, batch_size=32)),
    (TD3, "Pendulum-v1", dict(learning_starts=100, batch_size=32)),
    (DDPG, "Pendulum-v1", dict(learning_starts=100, batch_size=32)),
]


@pytest.mark.parametrize(("cls", "env_id", "kwargs"), ALGOS, ids=[a[0].__name__ for a in ALGOS])
def test_training_with_n_steps_on_both_learners(cls: Any, env_id: str, kwargs: Any) -> None:
    def run(backend: str, n_steps: int) -> Any:
        policy_kwargs = {"net_arch": [32], **kwargs.get("policy_kwargs", {}), "backend": backend}
        others = {k: v for k, v in kwargs.items() if k != "policy_kwargs"}
        model = cls(
            "MlpPolicy", env_id, n_steps=n_steps, policy_kwargs=policy_kwargs, seed=0, **others
        )
        return model.learn(300)

    a, b, t, one = run("numpy", 3), run("numpy", 3), run("torch", 3), run("numpy", 1)
    assert a.n_steps == 3 and a.replay_buffer.n_steps == 3 and a._n_updates > 0
    changed = False
    for key, value in a.policy.state_dict().items():
        assert torch.equal(value, b.policy.state_dict()[key]), key
        torch.testing.assert_close(value, t.policy.state_dict()[key], atol=1e-4, rtol=1e-3)
        changed |= not torch.equal(value, one.policy.state_dict()[key])
    assert changed  # n_steps reaches the updates


def test_save_load_keeps_n_steps_and_the_buffer(tmp_path: Path) -> None:
    model = DQN("MlpPolicy", "CartPole-v1", n_steps=4, learning_starts=50, seed=0)
    model.learn(200)
    model.save(tmp_path / "m.zip")
    model.save_replay_buffer(tmp_path / "rb.zip")
    loaded = DQN.load(tmp_path / "m.zip", env="CartPole-v1")
    assert loaded.n_steps == 4 and loaded.replay_buffer.n_steps == 4
    loaded.load_replay_buffer(tmp_path / "rb.zip")
    rows = np.arange(model.replay_buffer.size())
    cols = np.zeros_like(rows)
    for x, y in zip(model.replay_buffer.get(rows, cols), loaded.replay_buffer.get(rows, cols)):
        np.testing.assert_array_equal(x, y)
    # the same transitions serve one-step returns ...
    plain = DQN("MlpPolicy", "CartPole-v1", seed=0)
    plain.load_replay_buffer(tmp_path / "rb.zip")
    np.testing.assert_array_equal(
        plain.replay_buffer.get(rows, cols)[3], model.replay_buffer.rewards[rows, cols]
    )
    # ... but a one-step buffer does not say where episodes ended
    plain.save_replay_buffer(tmp_path / "rb1.zip")
    with pytest.raises(ModelFileError, match="does not record where episodes ended"):
        loaded.load_replay_buffer(tmp_path / "rb1.zip")


# -- bad values ------------------------------------------------------------------------------
@pytest.mark.parametrize("value", [0, -1, 2.5, True, "3", None])
@pytest.mark.parametrize("cls", [DQN, SAC, TD3, DDPG])
def test_bad_n_steps_is_named(cls: Any, value: Any) -> None:
    env = "CartPole-v1" if cls is DQN else "Pendulum-v1"
    with pytest.raises(ValueError, match=rf"n_steps must be an integer >= 1, got {value!r}"):
        cls("MlpPolicy", env, n_steps=value)


def test_n_steps_conflicts() -> None:
    with pytest.raises(ValueError, match=r"replay_buffer_kwargs may not set 'n_steps' \(3\)"):
        DQN("MlpPolicy", "CartPole-v1", replay_buffer_kwargs={"n_steps": 3})
    with pytest.raises(NotImplementedError, match="n_steps=3 is not supported with optimize"):
        DQN("MlpPolicy", "CartPole-v1", n_steps=3, optimize_memory_usage=True)


def test_a_model_file_with_a_bad_n_steps_is_refused(tmp_path: Path) -> None:
    from palaestra.algos.common.model_io import read_archive, write_archive

    DQN("MlpPolicy", "CartPole-v1", n_steps=3).save(tmp_path / "m.zip")
    meta, arrays = read_archive(tmp_path / "m.zip", "model")
    assert meta["hyperparameters"]["n_steps"] == 3
    meta["hyperparameters"]["n_steps"] = 0
    write_archive(tmp_path / "m.zip", "model", meta, arrays)
    with pytest.raises(ModelFileError, match="n_steps"):
        DQN.load(tmp_path / "m.zip")


def test_an_sb3_dqn_file_keeps_its_n_steps(tmp_path: Path) -> None:
    sb3 = pytest.importorskip("stable_baselines3")
    from palaestra.compat import from_sb3

    sb3.DQN("MlpPolicy", "CartPole-v1", n_steps=3, learning_starts=10, seed=0).learn(20).save(
        tmp_path / "sb3.zip"
    )
    model = from_sb3(tmp_path / "sb3.zip", env="CartPole-v1")
    assert model.n_steps == 3 and model.replay_buffer.n_steps == 3


@pytest.mark.slow
def test_sac_learns_pendulum_with_n_steps() -> None:
    """The budget and bar of ``test_sac_td3``'s one-step check (random: about -1200)."""
    from palaestra import make
    from palaestra.algos import evaluate_policy

    model = SAC("MlpPolicy", "Pendulum-v1", n_steps=3, learning_rate=1e-3, seed=0)
    model.learn(8000)
    mean, _ = evaluate_policy(model, make("Pendulum-v1"), n_eval_episodes=10)
    assert mean > -400
