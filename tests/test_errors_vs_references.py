"""Bad input that Gymnasium or SB3 reject (or mishandle) gets a palaestra error that is also the
builtin type they raise there, so ``except ValueError``/``TypeError`` written for them keeps
working, and whose message names the value (its repr) and what was expected.

Each case runs the same input through the reference library when it is installed and checks
that palaestra's exception is an instance of the reference's exception type.
"""

from __future__ import annotations

import importlib.util
from typing import Any

import numpy as np
import pytest
from tests.raised import raised

import palaestra as pal
from palaestra import error
from palaestra.vec_env import VecNormalize, make_vec_env


def _has(module: str) -> bool:
    return importlib.util.find_spec(module) is not None


def assert_compatible(ours: BaseException | None, theirs: BaseException | None) -> None:
    """palaestra raised a palaestra error that ``except type(theirs)`` catches."""
    assert isinstance(ours, error.Error), ours
    if theirs is not None:
        assert isinstance(ours, type(theirs)), (type(ours).__mro__, type(theirs))


# -- make(id) -------------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", ["::", ":", ":b", "::x", "x::", "a:b:c", ":CartPole-v1"])
def test_malformed_module_ids(env_id: str) -> None:
    ours = raised(lambda: pal.make(env_id))
    theirs = None
    if _has("gymnasium"):
        import gymnasium

        theirs = raised(lambda: gymnasium.make(env_id))
        assert type(theirs) is ValueError  # "too many values to unpack", "Empty module name"
    assert_compatible(ours, theirs)
    assert type(ours) is error.InvalidEnvId
    assert str(ours) == (
        f"{env_id!r} is not an environment id: expected 'Name-vN' or 'module:Name-vN' (one ':' "
        "after the name of a module to import, which registers the id)"
    )
    assert type(raised(lambda: pal.make_vec(env_id, 2))) is error.InvalidEnvId


def test_module_ids_still_import_the_module() -> None:
    assert pal.make("palaestra.envs:CartPole-v1").spec.id == "CartPole-v1"
    missing = raised(lambda: pal.make("no_such_module_24:X-v0"))
    assert type(missing) is ModuleNotFoundError and "'no_such_module_24'" in str(missing)


# -- VecEnv.set_options ---------------------------------------------------------------------
def _vec_envs() -> dict[str, Any]:
    return {
        "native": lambda: make_vec_env("CartPole-v1", n_envs=2),
        "dummy": lambda: make_vec_env("CartPole-v1", n_envs=2, wrapper_class=lambda e: e),
        "normalize": lambda: VecNormalize(make_vec_env("CartPole-v1", n_envs=2)),
    }


@pytest.mark.parametrize("face", ["native", "dummy", "normalize"])
@pytest.mark.parametrize(
    ("options", "kind", "detail"),
    [
        (-1, error.InvalidOptions, "got -1"),
        ("x", error.InvalidOptions, "got 'x'"),
        ([1, 2], error.InvalidOptions, "got [1, 2]: 1 is not a dict"),
        ([{}], error.OptionsCountError, "got a list of 1: [{}]"),
        ([{}, {}, {}], error.OptionsCountError, "got a list of 3: [{}, {}, {}]"),
    ],
)
def test_set_options_refuses_what_is_not_options(
    face: str, options: Any, kind: type, detail: str
) -> None:
    venv = _vec_envs()[face]()
    ours = raised(lambda: venv.set_options(options))
    venv.close()
    theirs = None
    if _has("stable_baselines3") and options != [{}, {}, {}]:  # SB3 ignores the third dict
        from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env

        def sb3() -> None:
            sb3_venv = sb3_make_vec_env("CartPole-v1", n_envs=2)
            sb3_venv.set_options(options)  # SB3 fails only at the next reset
            sb3_venv.reset()

        theirs = raised(sb3)
        assert theirs is not None
    if options != "x":  # SB3: IndexError ('x'[1]), by accident of indexing a string
        assert_compatible(ours, theirs)
    assert type(ours) is kind
    assert str(ours) == (
        "set_options expects a dict (the same options for every env) or a list of 2 dicts "
        f"(one per env), {detail}"
    )


def test_set_options_accepts_a_dict_a_list_and_none_entries() -> None:
    venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)
    venv.set_options([{"low": 0.2, "high": 0.2}, None])
    obs = venv.reset()
    np.testing.assert_allclose(obs[0], 0.2, rtol=1e-6)
    assert np.all(np.abs(obs[1]) <= 0.05)
    venv.set_options({"low": -0.3, "high": -0.3})
    np.testing.assert_allclose(venv.reset(), -0.3, rtol=1e-6)


# -- env.reset(options=...) -------------------------------------------------------------------
_READERS = {  # every built-in env that reads reset options, and the keys it reads
    "CartPole-v1": ("low", "high"),
    "MountainCar-v0": ("low", "high"),
    "MountainCarContinuous-v0": ("low", "high"),
    "Acrobot-v1": ("low", "high"),
    "Pendulum-v1": ("x_init", "y_init"),
}


def _make_pair(env_id: str) -> tuple[Any, Any]:
    kwargs: dict[str, Any] = {}
    if env_id == "CarRacing-v3":
        pytest.importorskip("Box2D")
        kwargs = {"domain_randomize": True}
    ours = pal.make(env_id, disable_env_checker=True, **kwargs)
    theirs = None
    if _has("gymnasium"):
        import gymnasium

        theirs = gymnasium.make(env_id, disable_env_checker=True, **kwargs)
    return ours, theirs


@pytest.mark.parametrize("env_id", [*_READERS, "CarRacing-v3"])
@pytest.mark.parametrize("options", ["x", -1, [1], 2.5])
def test_reset_options_that_are_not_a_dict(env_id: str, options: Any) -> None:
    ours_env, theirs_env = _make_pair(env_id)
    ours = raised(lambda: ours_env.reset(seed=0, options=options))
    # Gymnasium: TypeError for -1 and 2.5 ("in" on a number), silence for 'x' and [1]
    theirs = None if theirs_env is None else raised(lambda: theirs_env.reset(options=options))
    assert theirs is None or type(theirs) is TypeError
    assert_compatible(ours, theirs)
    keys = ", ".join(repr(k) for k in _READERS.get(env_id, ("randomize",)))
    assert type(ours) is error.InvalidOptions
    assert str(ours) == f"Reset options must be None or a dict (keys {keys}), got {options!r}"
    obs, _ = ours_env.reset(seed=0, options={})  # a dict still works after the refusal
    assert ours_env.observation_space.contains(obs)


VECTOR_OPTIONS = "Reset options must be None or a dict (of the sub-envs' options and 'reset_mask')"


@pytest.mark.parametrize("mode", [None, "sync", "async"])
def test_vector_reset_options_that_are_not_a_dict(mode: str | None) -> None:
    kwargs = {} if mode is None else {"vectorization_mode": mode}
    with pal.make_vec("Pendulum-v1", 2, **kwargs) as envs:
        ours = raised(lambda: envs.reset(seed=0, options=-1))
        assert envs.reset(seed=0, options={"x_init": 0.0, "y_init": 0.0})[0].shape == (2, 3)
    theirs = None
    if _has("gymnasium"):
        import gymnasium

        their_envs = gymnasium.make_vec("Pendulum-v1", 2, **kwargs)
        theirs = raised(lambda: their_envs.reset(seed=0, options=-1))
        their_envs.close()
        assert type(theirs) is TypeError
    assert_compatible(ours, theirs)
    assert type(ours) is error.InvalidOptions
    assert str(ours) == f"{VECTOR_OPTIONS}, got -1"


# -- vector env construction ----------------------------------------------------------------
@pytest.mark.parametrize("n_envs", [0, -1, "2", 2.0, None, True])
def test_make_vec_env_n_envs(n_envs: Any) -> None:
    ours = raised(lambda: make_vec_env("CartPole-v1", n_envs=n_envs))
    theirs = None
    if _has("stable_baselines3") and n_envs is not True:  # SB3 takes True as 1
        from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env

        theirs = raised(lambda: sb3_make_vec_env("CartPole-v1", n_envs=n_envs))
        assert type(theirs) in (TypeError, IndexError)
    assert_compatible(ours, theirs)
    assert type(ours) is error.InvalidNumEnvs and isinstance(ours, ValueError)
    assert str(ours) == f"make_vec_env: n_envs must be an int >= 1, got {n_envs!r}"


def _faces() -> dict[str, Any]:
    from palaestra.vec_env import DummyVecEnv, SubprocVecEnv
    from palaestra.vector import AsyncVectorEnv, SyncVectorEnv

    return {
        "DummyVecEnv": DummyVecEnv,
        "SubprocVecEnv": lambda fns: SubprocVecEnv(fns, start_method="fork"),
        "SyncVectorEnv": SyncVectorEnv,
        "AsyncVectorEnv": lambda fns: AsyncVectorEnv(fns, context="fork"),
    }


@pytest.mark.parametrize(
    "face", ["DummyVecEnv", "SubprocVecEnv", "SyncVectorEnv", "AsyncVectorEnv"]
)
def test_an_env_where_a_function_making_one_belongs(face: str) -> None:
    env = pal.make("CartPole-v1")
    ours = raised(lambda: _faces()[face]([env]))
    theirs = None
    if _has("gymnasium") and face in ("DummyVecEnv", "SyncVectorEnv"):
        import gymnasium

        their_env = gymnasium.make("CartPole-v1")
        if face == "SyncVectorEnv":
            theirs = raised(lambda: gymnasium.vector.SyncVectorEnv([their_env]))
        elif _has("stable_baselines3"):
            from stable_baselines3.common.vec_env import DummyVecEnv as SB3Dummy

            theirs = raised(lambda: SB3Dummy([their_env]))
        assert theirs is None or type(theirs) is TypeError  # "'TimeLimit' object is not callable"
    assert_compatible(ours, theirs)
    assert type(ours) is error.InvalidEnvFunction
    assert str(ours) == (
        f"{face}: env_fns[0] is {env!r}, not a function that makes an env: pass e.g. "
        "`lambda: palaestra.make(...)`, which makes a new env at each call"
    )


def test_a_vec_env_wrapper_around_something_else() -> None:
    ours = raised(lambda: VecNormalize(1))  # type: ignore[arg-type]
    theirs = None
    if _has("stable_baselines3"):
        from stable_baselines3.common.vec_env import VecNormalize as SB3VecNormalize

        theirs = raised(lambda: SB3VecNormalize(1))
        assert type(theirs) is AttributeError  # 'int' object has no attribute 'num_envs'
    assert_compatible(ours, theirs)
    assert type(ours) is error.NotAVecEnv and isinstance(ours, TypeError)
    assert str(ours) == (
        "VecNormalize expects a palaestra.vec_env.VecEnv to wrap, got 1 (<class 'int'>)"
    )
