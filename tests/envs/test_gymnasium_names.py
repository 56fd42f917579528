"""Gymnasium's env module paths and names under ``palaestra.envs`` (issue 26), side by side
with the installed gymnasium: package exports, Taxi's keyword names, a bare CartPole built with
``render_mode="rgb_array_list"``, and ``CartPoleVectorEnv``."""

from __future__ import annotations

import copy
import importlib
import pickle
import warnings

import numpy as np
import pytest

from palaestra import error
from palaestra.wrappers import OrderEnforcing

gymnasium = pytest.importorskip("gymnasium")


@pytest.mark.parametrize("package", ["box2d", "toy_text", "classic_control"])
def test_env_packages_export_gymnasiums_classes(package: str) -> None:
    ours = importlib.import_module(f"palaestra.envs.{package}")
    theirs = importlib.import_module(f"gymnasium.envs.{package}")
    assert set(theirs.__all__) <= set(ours.__all__)
    for name in theirs.__all__:
        assert getattr(ours, name).__name__ == name


def test_from_box2d_import_the_envs() -> None:
    pytest.importorskip("Box2D")
    from palaestra.envs.box2d import (
        BipedalWalker,
        BipedalWalkerHardcore,
        CarRacing,
        LunarLander,
        LunarLanderContinuous,
    )

    assert LunarLanderContinuous().continuous is True
    assert BipedalWalkerHardcore().hardcore is True
    assert LunarLander().continuous is False and BipedalWalker().hardcore is False
    assert CarRacing().continuous is True


def test_the_hardcore_and_continuous_names_refuse_the_other_variant() -> None:
    from palaestra.envs.box2d import BipedalWalkerHardcore, LunarLanderContinuous

    with pytest.raises(ValueError, match=r"continuous=False; use LunarLander"):
        LunarLanderContinuous(continuous=False)
    with pytest.raises(ValueError, match=r"hardcore=0; use BipedalWalker"):
        BipedalWalkerHardcore(hardcore=0)  # type: ignore[arg-type]


def test_taxi_encode_decode_take_gymnasiums_keywords() -> None:
    from palaestra.envs.toy_text import TaxiEnv

    ours, theirs = TaxiEnv(), gymnasium.envs.toy_text.TaxiEnv()
    for state in range(500):
        row, col, loc, dest = theirs.decode(i=state)
        assert ours.decode(i=state) == (row, col, loc, dest)
        kwargs = dict(taxi_row=row, taxi_col=col, pass_loc=loc, dest_idx=dest)
        assert ours.encode(**kwargs) == theirs.encode(**kwargs) == state
    assert type(ours.decode(np.int64(7))[0]) is type(theirs.decode(np.int64(7))[0])


def test_cartpole_with_rgb_array_list_is_built_as_gymnasium_builds_it() -> None:
    """Gymnasium's OrderEnforcing test, on both: the bare env takes the list mode."""
    from palaestra.envs.classic_control import CartPoleEnv

    with pytest.warns(UserWarning, match="RenderCollection's job"):
        env = CartPoleEnv(render_mode="rgb_array_list")
    theirs = gymnasium.envs.classic_control.CartPoleEnv(render_mode="rgb_array_list")
    assert env.render_mode == theirs.render_mode == "rgb_array_list"
    wrapped = OrderEnforcing(env)
    with pytest.raises(error.ResetNeeded):
        wrapped.step(0)
    with pytest.raises(error.ResetNeeded):
        wrapped.render()
    wrapped.reset(seed=0)
    wrapped.step(0)
    frame = wrapped.render()  # Gymnasium's returns None here; the frame is more use
    assert frame.shape == (400, 600, 3) and frame.dtype == np.uint8
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        unordered = OrderEnforcing(
            CartPoleEnv(render_mode="rgb_array_list"), disable_render_order_enforcing=True
        )
    with pytest.raises(error.ResetNeeded, match="Call reset before render"):
        unordered.render()  # no order error; the env itself has nothing to draw yet


def test_other_unknown_render_modes_are_still_refused() -> None:
    from palaestra.envs.classic_control import CartPoleEnv

    for mode in ("human_list", "depth_array_list", "rgb"):
        with pytest.raises(error.UnsupportedMode, match=repr(mode)):
            CartPoleEnv(render_mode=mode)


def test_make_with_rgb_array_list_still_collects_frames() -> None:
    import palaestra

    env = palaestra.make("CartPole-v1", render_mode="rgb_array_list")
    env.reset(seed=0)
    env.step(0)
    frames = env.render()
    assert isinstance(frames, list) and len(frames) == 2


def test_cartpole_vector_env_matches_gymnasiums_surface() -> None:
    from palaestra.envs.classic_control.cartpole import CartPoleVectorEnv

    theirs_cls = gymnasium.envs.classic_control.cartpole.CartPoleVectorEnv
    ours, theirs = CartPoleVectorEnv(num_envs=4), theirs_cls(num_envs=4)
    assert ours.single_observation_space.shape == theirs.single_observation_space.shape
    assert ours.observation_space.shape == theirs.observation_space.shape == (4, 4)
    assert ours.single_action_space.n == theirs.single_action_space.n == 2
    assert ours.metadata["autoreset_mode"].value == theirs.metadata["autoreset_mode"].value
    obs, info = ours.reset(seed=0)
    their_obs, their_info = theirs.reset(seed=0)
    assert obs.shape == their_obs.shape and obs.dtype == their_obs.dtype == np.float32
    assert info == their_info == {}
    actions = np.array([0, 1, 1, 0])
    step, their_step = ours.step(actions), theirs.step(actions)
    for got, want in zip(step[1:4], their_step[1:4]):
        assert got.shape == want.shape == (4,)
    assert step[2].dtype == step[3].dtype == np.bool_


def test_cartpole_vector_env_rows_are_single_cartpoles() -> None:
    import palaestra
    from palaestra.envs.classic_control.cartpole import CartPoleVectorEnv

    envs = CartPoleVectorEnv(num_envs=3, max_episode_steps=7, sutton_barto_reward=True)
    obs, _ = envs.reset(seed=10)
    single = palaestra.make("CartPole-v1", sutton_barto_reward=True)
    want, _ = single.reset(seed=11)
    np.testing.assert_array_equal(obs[1], want)
    truncated = None
    for _ in range(7):
        obs, reward, _, truncated, _ = envs.step(np.zeros(3, dtype=np.int64))
        want, want_reward, *_ = single.step(0)
        np.testing.assert_array_equal(obs[1], want)
        assert reward[1] == want_reward
    assert truncated is not None and truncated.all()  # max_episode_steps=7


def test_cartpole_vector_env_renders_each_row_and_refuses_other_modes() -> None:
    from palaestra.envs.classic_control.cartpole import CartPoleEnv, CartPoleVectorEnv

    envs = CartPoleVectorEnv(num_envs=2, render_mode="rgb_array")
    envs.reset(seed=0)
    frames = envs.render()
    single = CartPoleEnv(render_mode="rgb_array")
    single.reset(seed=1)
    assert len(frames) == 2 and frames[0].shape == (400, 600, 3)
    np.testing.assert_array_equal(frames[1], single.render())
    with pytest.warns(UserWarning, match="without specifying any render mode"):
        assert CartPoleVectorEnv(num_envs=2).render() is None
    with pytest.raises(error.UnsupportedMode, match="'human' is not one of"):
        CartPoleVectorEnv(render_mode="human")


def test_cartpole_vector_env_pickles_by_its_gymnasium_path() -> None:
    from palaestra.envs.classic_control import cartpole

    cls = cartpole.CartPoleVectorEnv
    assert cls is cartpole.CartPoleVectorEnv  # built once
    assert (cls.__module__, cls.__qualname__) == (cartpole.__name__, "CartPoleVectorEnv")
    envs = cls(num_envs=2)
    envs.reset(seed=0)
    for duplicate in (lambda e: pickle.loads(pickle.dumps(e)), copy.deepcopy):
        clone = duplicate(envs)
        assert type(clone) is cls
        np.testing.assert_array_equal(clone.step(np.array([1, 0]))[0], envs.step([1, 0])[0])
    with pytest.raises(AttributeError, match="no attribute 'Nope'"):
        _ = cartpole.Nope
