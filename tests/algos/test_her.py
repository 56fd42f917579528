"""Hindsight Experience Replay (``palaestra.algos.her``): the buffer side by side with SB3's
``HerReplayBuffer`` (the same samples after the same ``np.random.seed``), relabelling checked
by hand, SB3's episode bookkeeping, errors, and DQN/SAC/TD3/DDPG training, saving, loading and
resuming exactly with it (ported in spirit from SB3's ``tests/test_her.py``)."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from palaestra.algos import DDPG, DQN, SAC, TD3
from palaestra.algos.callbacks import BaseCallback
from palaestra.algos.common.model_io import ModelFileError
from palaestra.algos.her import GoalSelectionStrategy, HerReplayBuffer
from palaestra.envs.goal import BitFlippingEnv
from palaestra.vec_env import make_vec_env

STRATEGIES = ["future", "final", "episode"]


def _venv(n_envs: int = 2, **kwargs: Any) -> Any:
    return make_vec_env(lambda: BitFlippingEnv(n_bits=4, **kwargs), n_envs=n_envs, seed=0)


def _fill(buffers: list[Any], venv: Any, steps: int, seed: int = 0) -> Any:
    """Step ``venv`` with random actions, adding each step to every buffer as SB3's algorithms
    do (terminal observations as next observations). Returns the last observation."""
    obs = venv.reset()
    venv.action_space.seed(seed)
    for _ in range(steps):
        actions = np.array([venv.action_space.sample() for _ in range(venv.num_envs)])
        new_obs, rewards, dones, infos = venv.step(actions)
        next_obs = {k: v.copy() for k, v in new_obs.items()}
        for i in np.flatnonzero(dones):
            for k in next_obs:
                next_obs[k][i] = infos[i]["terminal_observation"][k]
        for buffer in buffers:
            buffer.add(obs, next_obs, actions, rewards, dones, infos)
        obs = new_obs
    return obs


# -- side by side with SB3 ---------------------------------------------------------------------
@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize(
    "env_kwargs",
    [{"continuous": True}, {}, {"discrete_obs_space": True}, {"image_obs_space": True}],
)
def test_samples_equal_sb3s(strategy: str, env_kwargs: dict[str, Any]) -> None:
    """Same transitions in, the same np.random seed: every sampled field is equal (shapes,
    dtypes, values), also after the ring wraps around and overwrites old episodes."""
    sb3 = pytest.importorskip("stable_baselines3")
    sb3_envs = pytest.importorskip("stable_baselines3.common.envs")
    sb3_vec = pytest.importorskip("stable_baselines3.common.vec_env")
    venv = sb3_vec.DummyVecEnv([lambda: sb3_envs.BitFlippingEnv(n_bits=4, **env_kwargs)] * 2)
    venv.seed(0)
    kwargs = dict(n_envs=2, goal_selection_strategy=strategy, n_sampled_goal=3)
    theirs = sb3.HerReplayBuffer(
        40, venv.observation_space, venv.action_space, venv, copy_info_dict=True, **kwargs
    )
    ours = HerReplayBuffer(
        40, venv.observation_space, venv.action_space, venv, device="cpu", **kwargs
    )
    obs = venv.reset()
    venv.action_space.seed(0)
    for step in range(45):
        obs = _fill_one([theirs, ours], venv, obs)
        if step >= 6:  # after the first episodes ended
            np.random.seed(step)  # noqa: NPY002 - SB3's buffer draws from it
            expected = theirs.sample(16)
            np.random.seed(step)  # noqa: NPY002 - SB3's buffer draws from it
            got = ours.sample(16)
            for field in ("observations", "actions", "next_observations", "dones", "rewards"):
                _assert_equal(getattr(got, field), getattr(expected, field), field)
    assert ours.full and theirs.full
    np.testing.assert_array_equal(ours.ep_length, theirs.ep_length)
    np.testing.assert_array_equal(ours.ep_start, theirs.ep_start)
    np.testing.assert_array_equal(ours._current_ep_start, theirs._current_ep_start)


def _fill_one(buffers: list[Any], venv: Any, obs: Any) -> Any:
    actions = np.array([venv.action_space.sample() for _ in range(venv.num_envs)])
    new_obs, rewards, dones, infos = venv.step(actions)
    next_obs = {k: v.copy() for k, v in new_obs.items()}
    for i in np.flatnonzero(dones):
        for k in next_obs:
            next_obs[k][i] = infos[i]["terminal_observation"][k]
    for buffer in buffers:
        buffer.add(obs, next_obs, actions, rewards, dones, infos)
    return new_obs


def _assert_equal(got: Any, expected: Any, field: str) -> None:
    pairs = (
        [(got[k], expected[k]) for k in expected]
        if isinstance(expected, dict)
        else [(got, expected)]
    )
    if isinstance(expected, dict):
        assert list(got) == list(expected), field
    for x, y in pairs:
        assert x.shape == y.shape and x.dtype == y.dtype, (
            field,
            x.shape,
            y.shape,
            x.dtype,
            y.dtype,
        )
        assert torch.equal(x, y), field


def test_truncate_last_trajectory_as_sb3(recwarn: pytest.WarningsRecorder) -> None:
    """SB3's test_truncate_last_trajectory on both buffers fed the same steps: the same
    warning, dones, timeouts and episode bookkeeping, before and after more steps."""
    sb3 = pytest.importorskip("stable_baselines3")
    to_gym = pytest.importorskip("palaestra.compat").to_gymnasium_space
    venv = _venv(2, continuous=True)
    ours = HerReplayBuffer(10_000, venv.observation_space, venv.action_space, venv, n_envs=2)
    theirs = sb3.HerReplayBuffer(
        10_000, to_gym(venv.observation_space), to_gym(venv.action_space), venv, n_envs=2
    )
    _fill([ours, theirs], venv, 5)
    pos = ours.pos
    open_envs = np.flatnonzero(ours._current_ep_start != pos)
    assert len(open_envs)  # 5 steps of 4-step episodes leave some open
    assert len(recwarn) == 0
    message = "The last trajectory in the replay buffer will be truncated"
    with pytest.warns(UserWarning, match=message):
        ours.truncate_last_trajectory()
    with pytest.warns(UserWarning, match=message):
        theirs.truncate_last_trajectory()
    assert (ours._current_ep_start == pos).all()
    assert (ours.dones[pos - 1] == 1).all() and (ours.timeouts[pos - 1, open_envs] == 1).all()
    for name in ("dones", "timeouts", "ep_length", "ep_start", "_current_ep_start"):
        np.testing.assert_array_equal(getattr(ours, name), getattr(theirs, name), name)
    _fill([ours, theirs], venv, 10, seed=1)
    for name in ("dones", "timeouts", "ep_length", "ep_start", "rewards", "_current_ep_start"):
        np.testing.assert_array_equal(getattr(ours, name), getattr(theirs, name), name)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing open: no warning
        HerReplayBuffer(
            100, venv.observation_space, venv.action_space, venv
        ).truncate_last_trajectory()


# -- relabelling by hand ---------------------------------------------------------------------
class _Recorder:
    """A VecEnv stand-in whose compute_reward records its arguments (SB3's env_method)."""

    def __init__(self) -> None:
        self.calls: list[tuple[Any, ...]] = []
        self.env = BitFlippingEnv(n_bits=3)

    def env_method(self, name: str, *args: Any, indices: Any = None) -> list[Any]:
        assert name == "compute_reward" and indices == [0]
        self.calls.append(args)
        return [self.env.compute_reward(*args)]


def _episode_buffer(
    strategy: str,
    n_sampled_goal: int = 4,
    lengths: tuple[int, ...] = (3, 2, 1),
    size: int = 100,
    buffer_class: Any = HerReplayBuffer,
) -> tuple[Any, Any]:
    """One env and episodes of ``lengths`` steps, all finished but the last; the state after
    step t of episode e is the bits of ``3 * e + t`` (episode starts differ by 3, so the
    first two episodes' achieved goals are told apart) and the action stored is t."""
    env = _Recorder()
    space, actions = env.env.observation_space, env.env.action_space
    if buffer_class is HerReplayBuffer:
        extra: dict[str, Any] = {"device": "cpu"}
    else:  # SB3's, on Gymnasium spaces
        to_gym = pytest.importorskip("palaestra.compat").to_gymnasium_space
        space, actions, extra = to_gym(space), to_gym(actions), {}
    buffer = buffer_class(
        size,
        space,
        actions,
        env,
        n_sampled_goal=n_sampled_goal,
        goal_selection_strategy=strategy,
        **extra,
    )

    def bits(code: int) -> np.ndarray:
        return ((code >> np.arange(3)) & 1).astype(np.int8)[None]

    for episode, length in enumerate(lengths):
        for t in range(length):
            obs = {
                "observation": bits(episode * 3 + t),
                "achieved_goal": bits(episode * 3 + t),
                "desired_goal": np.ones((1, 3), np.int8),
            }
            nxt = {**obs, "achieved_goal": bits(episode * 3 + t + 1)}
            done = np.array([t == length - 1 and episode < len(lengths) - 1])
            buffer.add(obs, nxt, np.array([t]), np.array([-1.0]), done, [{}])
    return buffer, env


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_relabelled_goals_come_from_the_transitions_episode(strategy: str) -> None:
    buffer, env = _episode_buffer(strategy)
    np.testing.assert_array_equal(buffer.ep_length[:6, 0], [3, 3, 3, 2, 2, 0])
    np.testing.assert_array_equal(buffer.ep_start[:6, 0], [0, 0, 0, 3, 3, 5])
    rng = np.random.default_rng(0)
    obs, actions, next_obs, rewards, terminated = buffer.sample_arrays(500, rng)
    n_real = 500 - int(buffer.her_ratio * 500)
    assert n_real == 100
    codes = lambda g: g @ (1 << np.arange(3))  # noqa: E731
    row = actions  # each stored action is its step in the episode: t
    start = np.where(codes(obs["observation"]) >= 3, 3, 0)  # which episode
    t = codes(obs["observation"]) - start
    length = np.where(start == 0, 3, 2)
    assert (t < length).all()  # never the open third episode
    # real transitions keep their goal and reward
    assert (obs["desired_goal"][:n_real] == 1).all() and (rewards[:n_real] == -1).all()
    goal = codes(obs["desired_goal"][n_real:])
    assert (goal == codes(next_obs["desired_goal"][n_real:])).all()
    step = goal - start[n_real:] - 1  # the relabelled goal was achieved after this step
    if strategy == "final":
        np.testing.assert_array_equal(step, length[n_real:] - 1)
    elif strategy == "future":
        assert (step >= row[n_real:]).all() and (step < length[n_real:]).all()
        assert (step == row[n_real:]).any()  # inclusive of the transition's own step (SB3)
    else:
        assert (step >= 0).all() and (step < length[n_real:]).all()
        assert (step < row[n_real:]).any()
    # rewards: 0 where the next achieved goal is the new goal, from one batched call
    achieved = codes(next_obs["achieved_goal"][n_real:])
    np.testing.assert_array_equal(rewards[n_real:], np.where(achieved == goal, 0.0, -1.0))
    (call,) = env.calls
    assert call[0].shape == call[1].shape == (400, 3) and len(call[2]) == 400
    # the last step of each finished episode terminated (no time limit in its info)
    np.testing.assert_array_equal(terminated, (row == length - 1).astype(np.float32))
    assert terminated.dtype == np.float32


def test_n_sampled_goal_sets_the_relabelled_share() -> None:
    for n_sampled_goal, real in [(0, 64), (1, 32), (4, 13), (7, 8)]:
        buffer, env = _episode_buffer("future", n_sampled_goal)
        obs, *_ = buffer.sample_arrays(64, np.random.default_rng(0))
        assert len(obs["desired_goal"]) == 64
        assert len(env.calls) == (0 if n_sampled_goal == 0 else 1)
        if env.calls:
            assert len(env.calls[0][0]) == 64 - real


@pytest.mark.parametrize("buffer_class", ["ours", "sb3"])
def test_an_overwritten_episode_is_no_longer_sampled(buffer_class: str) -> None:
    """A ring of 5 rows: episode A (rows 0-2), episode B (rows 3, 4, 0) overwrites A's first
    row, so all of A stops being sampled; then the open episode C (rows 1, 2)."""
    cls = (
        HerReplayBuffer
        if buffer_class == "ours"
        else pytest.importorskip("stable_baselines3").HerReplayBuffer
    )
    buffer, _ = _episode_buffer("future", lengths=(3, 3, 0), size=5, buffer_class=cls)
    np.testing.assert_array_equal(buffer.ep_length[:, 0], [3, 0, 0, 3, 3])
    np.testing.assert_array_equal(buffer.ep_start[:, 0], [3, 0, 0, 3, 3])
    assert buffer.full and buffer.pos == 1
    buffer, _ = _episode_buffer("future", lengths=(3, 3, 2), size=5, buffer_class=cls)
    np.testing.assert_array_equal(buffer.ep_length[:, 0], [3, 0, 0, 3, 3])  # C is open
    if buffer_class == "ours":
        obs, *_ = buffer.sample_arrays(200, np.random.default_rng(0))
        codes = obs["observation"] @ (1 << np.arange(3))
        assert set(codes.tolist()) == {3, 4, 5}  # only episode B


def test_sampling_before_the_first_episode_ends_is_sb3s_error() -> None:
    venv = _venv(1)
    buffer = HerReplayBuffer(100, venv.observation_space, venv.action_space, venv)
    _fill([buffer], venv, 1)
    with pytest.raises(RuntimeError, match="Unable to sample before the end of the first episode"):
        buffer.sample(4)


# -- errors ---------------------------------------------------------------------------------------
def test_bad_arguments() -> None:
    venv = _venv(1)
    spaces = (venv.observation_space, venv.action_space, venv)
    with pytest.raises(
        ValueError,
        match=r"goal_selection_strategy must be one of \['episode', 'final', 'future'\] or a "
        r"GoalSelectionStrategy, got 'later'",
    ):
        HerReplayBuffer(10, *spaces, goal_selection_strategy="later")
    with pytest.raises(ValueError, match=r"n_sampled_goal must be an integer >= 0, got -1"):
        HerReplayBuffer(10, *spaces, n_sampled_goal=-1)
    with pytest.raises(
        ValueError, match="HerReplayBuffer does not support optimize_memory_usage=True"
    ):
        HerReplayBuffer(10, *spaces, optimize_memory_usage=True)
    assert (
        HerReplayBuffer(10, *spaces, goal_selection_strategy="FINAL").goal_selection_strategy
        is GoalSelectionStrategy.FINAL
    )
    from palaestra import spaces as sp

    no_goal = sp.Dict({"observation": sp.MultiBinary(3), "goal": sp.MultiBinary(3)})
    with pytest.raises(ValueError, match=r"lacks \['achieved_goal', 'desired_goal'\]"):
        HerReplayBuffer(10, no_goal, venv.action_space, venv)
    with pytest.raises(ValueError, match="HerReplayBuffer cannot store MultiBinary"):
        HerReplayBuffer(10, sp.MultiBinary(3), venv.action_space, venv)


def test_relabelling_needs_an_env() -> None:
    venv = _venv(1)
    buffer = HerReplayBuffer(100, venv.observation_space, venv.action_space, None)
    _fill([buffer], venv, 5)
    with pytest.raises(ValueError, match=r"no env to compute rewards .*set_env\(env\)"):
        buffer.sample(4)
    buffer.set_env(venv)
    assert buffer.sample(4).rewards.shape == (4, 1)
    with pytest.raises(ValueError, match=r"Trying to set env of already initialized environment\."):
        buffer.set_env(venv)


def test_other_buffer_classes_are_refused() -> None:
    from palaestra.algos.buffers import DictReplayBuffer

    with pytest.raises(
        NotImplementedError,
        match=r"replay_buffer_class=<class .*DictReplayBuffer'> is not supported: "
        r".*None .*or HerReplayBuffer",
    ):
        DQN("MultiInputPolicy", _venv(1), replay_buffer_class=DictReplayBuffer)
    with pytest.raises(NotImplementedError, match="replay_buffer_class='her' is not supported"):
        DQN("MultiInputPolicy", _venv(1), replay_buffer_class="her")


def test_n_steps_is_ignored_with_a_buffer_class_as_sb3() -> None:
    with pytest.warns(
        UserWarning,
        match=r"`n_steps=3` is ignored because a custom `replay_buffer_class` "
        r"\(`HerReplayBuffer`\)",
    ):
        model = DQN(
            "MultiInputPolicy",
            _venv(1),
            replay_buffer_class=HerReplayBuffer,
            n_steps=3,
            learning_starts=10,
        )
    model.learn(40)  # one-step targets: the HER buffer samples no discounts
    assert len(model._sample_batch(4)) == 5


def test_optimize_memory_usage_is_refused() -> None:
    with pytest.raises(
        ValueError, match="HerReplayBuffer does not support optimize_memory_usage=True"
    ):
        DQN(
            "MultiInputPolicy",
            _venv(1),
            replay_buffer_class=HerReplayBuffer,
            optimize_memory_usage=True,
        )


# -- the algorithms --------------------------------------------------------------------------
@pytest.mark.parametrize("algo", [DQN, SAC, TD3, DDPG])
# image observations (NatureCNN) train on the torch learner only
@pytest.mark.parametrize(
    ("backend", "image"), [("numpy", False), ("torch", False), ("torch", True)]
)
def test_algorithms_learn_with_her(algo: Any, backend: str, image: bool) -> None:
    venv = _venv(2, continuous=algo is not DQN, image_obs_space=image)
    model = algo(
        "MultiInputPolicy",
        venv,
        replay_buffer_class=HerReplayBuffer,
        replay_buffer_kwargs=dict(
            n_sampled_goal=2, goal_selection_strategy="future", copy_info_dict=True
        ),
        train_freq=4,
        gradient_steps=2,
        policy_kwargs=dict(net_arch=[32], backend=backend),
        learning_starts=40,
        buffer_size=2000,
        batch_size=16,
        seed=0,
    )
    assert type(model.learner).__name__.lower().startswith(backend)
    model.learn(100)
    assert isinstance(model.replay_buffer, HerReplayBuffer)
    assert model.replay_buffer.env is model.env
    assert model._n_updates > 0
    assert model.replay_buffer.infos is not None and "is_success" in model.replay_buffer.infos[0, 0]


@pytest.mark.parametrize("algo", [DQN, SAC, TD3, DDPG])
def test_same_bits_on_both_learners(algo: Any) -> None:
    params = []
    for backend in ("numpy", "torch"):
        model = algo(
            "MultiInputPolicy",
            _venv(2, continuous=algo is not DQN),
            replay_buffer_class=HerReplayBuffer,
            policy_kwargs=dict(net_arch=[16], backend=backend),
            learning_starts=20,
            batch_size=8,
            seed=3,
        )
        model.learn(60)
        params.append(model.policy.state_dict())
    for key, value in params[0].items():
        torch.testing.assert_close(value, params[1][key], rtol=1e-4, atol=1e-5)


def test_model_file_keeps_the_buffer_class(tmp_path: Path) -> None:
    venv = _venv(2)
    model = DQN(
        "MultiInputPolicy",
        venv,
        replay_buffer_class=HerReplayBuffer,
        replay_buffer_kwargs=dict(
            n_sampled_goal=2, goal_selection_strategy=GoalSelectionStrategy.FINAL
        ),
        learning_starts=20,
        seed=0,
    )
    model.learn(50)
    model.save(tmp_path / "m.zip")
    loaded = DQN.load(tmp_path / "m.zip", env=venv)
    assert loaded.replay_buffer_class is HerReplayBuffer
    assert loaded.replay_buffer_kwargs == {"n_sampled_goal": 2, "goal_selection_strategy": "final"}
    assert (
        isinstance(loaded.replay_buffer, HerReplayBuffer) and loaded.replay_buffer.env is loaded.env
    )
    assert loaded.replay_buffer.goal_selection_strategy is GoalSelectionStrategy.FINAL
    loaded.learn(40)
    predict_only = DQN.load(tmp_path / "m.zip")  # no env: it predicts; relabelling needs one
    obs = venv.reset()
    np.testing.assert_array_equal(
        predict_only.predict(obs, deterministic=True)[0], model.predict(obs, deterministic=True)[0]
    )


@pytest.mark.parametrize("n_envs", [1, 2])
@pytest.mark.parametrize("truncate", [False, True])
def test_save_and_load_replay_buffer(n_envs: int, truncate: bool, tmp_path: Path) -> None:
    venv = _venv(n_envs, continuous=True)
    model = SAC(
        "MultiInputPolicy",
        venv,
        replay_buffer_class=HerReplayBuffer,
        replay_buffer_kwargs=dict(n_sampled_goal=2, copy_info_dict=True),
        policy_kwargs=dict(net_arch=[16]),
        learning_starts=20,
        buffer_size=2000,
        seed=0,
    )
    model.learn(61)
    old = model.replay_buffer
    model.save_replay_buffer(tmp_path / "rb.zip")
    model.replay_buffer = None
    open_episode = (old._current_ep_start != old.pos).any()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model.load_replay_buffer(tmp_path / "rb.zip", truncate_last_traj=truncate)
    truncated = [w for w in caught if "will be truncated" in str(w.message)]
    assert len(truncated) == int(truncate and open_episode)
    new = model.replay_buffer
    assert isinstance(new, HerReplayBuffer) and new.env is model.env and new.pos == old.pos
    for key in old.observations:
        np.testing.assert_array_equal(
            new.observations[key][: old.pos], old.observations[key][: old.pos]
        )
        np.testing.assert_array_equal(
            new.next_observations[key][: old.pos], old.next_observations[key][: old.pos]
        )
    for name in ("actions", "rewards"):
        np.testing.assert_array_equal(getattr(new, name), getattr(old, name))
    np.testing.assert_array_equal(new.dones[: old.pos - 1], old.dones[: old.pos - 1])
    if not truncate:
        for name in ("dones", "timeouts", "ep_start", "ep_length", "_current_ep_start"):
            np.testing.assert_array_equal(getattr(new, name), getattr(old, name), name)
    assert new.infos is not None
    for a, b in zip(new.infos[: old.pos].ravel(), old.infos[: old.pos].ravel()):
        assert a.keys() == b.keys()
        for key in a:
            np.testing.assert_array_equal(
                a[key] if key != "terminal_observation" else list(a[key].values()),
                b[key] if key != "terminal_observation" else list(b[key].values()),
            )
    model.learn(40, reset_num_timesteps=truncate)


def test_buffer_files_do_not_mix(tmp_path: Path) -> None:
    venv = _venv(1)
    her = DQN("MultiInputPolicy", venv, replay_buffer_class=HerReplayBuffer, learning_starts=10)
    plain = DQN("MultiInputPolicy", venv, learning_starts=10)
    her.learn(20)
    plain.learn(20)
    her.save_replay_buffer(tmp_path / "her.zip")
    plain.save_replay_buffer(tmp_path / "plain.zip")
    with pytest.raises(
        ModelFileError, match="holds a HerReplayBuffer; this model has no replay_buffer_class"
    ):
        plain.load_replay_buffer(tmp_path / "her.zip")
    with pytest.raises(
        ModelFileError, match="without hindsight relabelling; this model uses HerReplayBuffer"
    ):
        her.load_replay_buffer(tmp_path / "plain.zip")


def test_infos_that_a_file_cannot_hold_are_refused(tmp_path: Path) -> None:
    venv = _venv(1)
    buffer = HerReplayBuffer(
        50, venv.observation_space, venv.action_space, venv, copy_info_dict=True
    )
    _fill([buffer], venv, 2)
    buffer.infos[0, 0] = {"callback": print}
    with pytest.raises(
        ValueError,
        match=r"cannot save info value <built-in function print> of type "
        r"builtin_function_or_method",
    ):
        buffer.state()


class _StopAt(BaseCallback):
    def __init__(self, at: int) -> None:
        super().__init__()
        self.at = at

    def _on_step(self) -> bool:
        return self.num_timesteps < self.at


def _resume_run(algo: Any, stops: list[int], tmp: Path | None) -> tuple[Any, Any]:
    total = 400
    kwargs: dict[str, Any] = dict(
        replay_buffer_class=HerReplayBuffer,
        replay_buffer_kwargs=dict(n_sampled_goal=3, copy_info_dict=True),
        learning_starts=50,
        train_freq=4,
        batch_size=16,
        buffer_size=150,  # wraps: overwritten episodes are forgotten
        policy_kwargs=dict(net_arch=[16]),
        seed=0,
    )
    if algo is DQN:
        kwargs["target_update_interval"] = 50
    model = algo("MultiInputPolicy", _venv(2, continuous=algo is not DQN), **kwargs)
    for i, stop in enumerate([*stops, total]):
        cb = _StopAt(stop) if stop < total else None
        model.learn(total - model.num_timesteps, callback=cb, reset_num_timesteps=i == 0)
        if stop < total and tmp is not None:
            env = model.get_env()
            model.save(tmp / f"m{i}.zip")
            model.save_replay_buffer(tmp / f"rb{i}.zip")
            del model
            model = algo.load(tmp / f"m{i}.zip", env=env)
            model.load_replay_buffer(tmp / f"rb{i}.zip", truncate_last_traj=False)
    return model.policy.state_dict(), model


@pytest.mark.parametrize("algo", [DQN, SAC])
@pytest.mark.parametrize("through_files", [False, True])
def test_exact_resume_with_her(algo: Any, through_files: bool, tmp_path: Path) -> None:
    full, model_a = _resume_run(algo, [], None)
    cut, model_b = _resume_run(algo, [3, 101, 230, 317], tmp_path if through_files else None)
    assert model_a.num_timesteps == model_b.num_timesteps
    for key, value in full.items():
        assert torch.equal(value, cut[key]), key
    assert model_a._rng.bit_generator.state == model_b._rng.bit_generator.state
    for name in ("ep_start", "ep_length", "_current_ep_start", "rewards", "dones"):
        np.testing.assert_array_equal(
            getattr(model_a.replay_buffer, name), getattr(model_b.replay_buffer, name)
        )


def test_set_env_relabels_with_the_new_env() -> None:
    model = DQN(
        "MultiInputPolicy", _venv(2), replay_buffer_class=HerReplayBuffer, learning_starts=10
    )
    model.learn(20)
    other = _venv(2)
    model.set_env(other)
    assert model.replay_buffer.env is model.env
    model.learn(20)


def test_a_new_env_episode_closes_the_open_ones() -> None:
    model = DQN(
        "MultiInputPolicy",
        _venv(1, max_steps=50),
        replay_buffer_class=HerReplayBuffer,
        learning_starts=1000,
    )
    model.learn(7)  # 8 steps (whole collections of train_freq=4) of one open episode
    buffer = model.replay_buffer
    last = buffer.pos - 1
    open_before = buffer._current_ep_start[0] != buffer.pos
    model.learn(3)  # reset_num_timesteps=True resets the env: the open episode ends there
    assert open_before  # seeded: no success in the first steps
    start = buffer.ep_start[last, 0]
    assert buffer.ep_length[last, 0] == last - start + 1
    assert buffer.dones[last, 0] == 1 and buffer.timeouts[last, 0] == 1
    assert buffer.ep_start[last + 1, 0] == last + 1  # the new episode starts after it


# -- the preset (slow: BENCHMARKS.md has all five seeds) ------------------------------------
def _preset_success(seed: int, her: bool) -> float:
    from palaestra import make, presets
    from palaestra.algos import evaluate_policy

    preset = presets.get_preset("dqn", "BitFlipping15-v0")
    hyper = presets.resolve(preset["hyperparams"])
    if not her:  # plain DQN, the same settings otherwise
        hyper["replay_buffer_class"] = hyper["replay_buffer_kwargs"] = None
    venv = make_vec_env("BitFlipping15-v0", n_envs=preset["n_envs"], seed=seed)
    model = DQN(preset["policy"], venv, seed=seed, **hyper)
    model.learn(preset["n_timesteps"])
    env = make("BitFlipping15-v0")
    env.reset(seed=10_000 + seed)
    ends: list[bool] = []

    def on_step(locals_: dict[str, Any], globals_: dict[str, Any]) -> None:
        if locals_["done"]:
            ends.append(bool(locals_["info"]["is_success"]))

    evaluate_policy(model, env, n_eval_episodes=100, deterministic=True, callback=on_step)
    assert len(ends) == 100
    return float(np.mean(ends))


@pytest.mark.slow
def test_the_preset_solves_15_bits_where_plain_dqn_does_not() -> None:
    assert _preset_success(0, her=True) >= 0.9
    assert _preset_success(0, her=False) < 0.1
