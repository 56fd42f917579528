"""The rest of SB3's public names (issue #26) at their palaestra paths, side by side with
SB3 (and Gymnasium's ``EzPickle``): same results, same error types and words (where palaestra
raises a clearer type, the test names it)."""

from __future__ import annotations

import io
import os
import pickle

import gymnasium
import numpy as np
import pytest
import torch
from stable_baselines3.common import base_class as sb3_base
from stable_baselines3.common import env_util as sb3_env_util
from stable_baselines3.common import logger as sb3_logger
from stable_baselines3.common import preprocessing as sb3_pre
from stable_baselines3.common import torch_layers as sb3_layers
from stable_baselines3.common import type_aliases as sb3_types
from stable_baselines3.common import utils as sb3_utils
from stable_baselines3.common.vec_env import base_vec_env as sb3_base_vec_env
from stable_baselines3.common.vec_env import util as sb3_vec_util
from torch import nn

import palaestra
from palaestra import spaces
from palaestra.algos import utils
from palaestra.algos.common import base, logger, networks, preprocessing, type_aliases
from palaestra.compat import from_gymnasium_space
from palaestra.vec_env import base as vec_base
from palaestra.vec_env import env_util
from palaestra.vec_env import util as vec_util
from palaestra.wrappers.monitor import Monitor


def _raised(fn):
    try:
        fn()
    except Exception as exc:
        return exc
    raise AssertionError("did not raise")


# -- logger levels ------------------------------------------------------------------------
def test_logger_levels_are_sb3s():
    for name in ("DEBUG", "INFO", "WARN", "ERROR", "DISABLED"):
        assert getattr(logger, name) == getattr(sb3_logger, name)


def _both_loggers():
    ours_out, theirs_out = io.StringIO(), io.StringIO()
    ours = logger.Logger(None, [logger.HumanOutputFormat(ours_out)])
    theirs = sb3_logger.Logger(None, [sb3_logger.HumanOutputFormat(theirs_out)])
    return (ours, ours_out), (theirs, theirs_out)


@pytest.mark.parametrize("level", [10, 20, 30, 40, 50])
def test_log_level_filters_as_sb3(level):
    outputs = []
    for lg, out in _both_loggers():
        assert lg.level == 20  # INFO by default
        lg.set_level(level)
        lg.debug("d", 1)
        lg.info("i", 2.5)
        lg.warn("w")
        lg.error("e", None)
        lg.log("x", level=35)
        outputs.append(out.getvalue())
    assert outputs[0] == outputs[1]
    assert outputs[0].count("\n") == sum(lvl >= level for lvl in (10, 20, 30, 40, 35))


def test_disabled_level_stops_dump_and_keeps_values_as_sb3():
    outputs = []
    for lg, out in _both_loggers():
        lg.set_level(sb3_logger.DISABLED)
        lg.record("a", 1.0)
        lg.dump(3)
        assert out.getvalue() == ""
        lg.set_level(sb3_logger.INFO)
        lg.record("b", 2)
        lg.record_mean("m", None)  # ignored
        lg.dump(4)
        outputs.append(out.getvalue())
    assert outputs[0] == outputs[1] and "a " in outputs[0] and "m " not in outputs[0]


@pytest.mark.parametrize("fmt", ["stdout", "log", "csv", "json"])
def test_a_format_excluded_as_a_bare_string_is_excluded_as_sb3(tmp_path, fmt):
    # ("stdout") is the string "stdout": SB3's substring test excludes the format
    for side, module in (("ours", logger), ("theirs", sb3_logger)):
        writer = module.make_output_format(fmt, str(tmp_path / side))
        writer.write({"tag": 42}, {"tag": (fmt)}, 0)
        writer.write({"kept": 1}, {"kept": "tensorboard"}, 1)
        writer.close()
    for name in os.listdir(tmp_path / "ours"):
        ours = (tmp_path / "ours" / name).read_text()
        assert ours == (tmp_path / "theirs" / name).read_text()
        assert "tag" not in ours


def test_configure_says_where_it_logs_as_sb3(tmp_path, capsys):
    ours = logger.configure(str(tmp_path / "ours"), ["stdout", "csv"])
    assert ours.dir == ours.get_dir() == str(tmp_path / "ours")
    assert capsys.readouterr().out == f"Logging to {tmp_path / 'ours'}\n"
    sb3_logger.configure(str(tmp_path / "theirs"), ["stdout", "csv"])
    assert capsys.readouterr().out == f"Logging to {tmp_path / 'theirs'}\n"
    logger.configure(str(tmp_path / "quiet"), ["stdout"])
    assert capsys.readouterr().out == ""


# -- utils --------------------------------------------------------------------------------
@pytest.mark.parametrize("values", [[], [1.0, 2.0, 4.0], np.arange(5)])
def test_safe_mean(values):
    ours, theirs = utils.safe_mean(values), sb3_utils.safe_mean(values)
    assert type(ours) is float and (ours == theirs or (np.isnan(ours) and np.isnan(theirs)))


def test_get_latest_run_id(tmp_path):
    for name in ("PPO_1", "PPO_3", "PPO_x_9", "PPO_2b", "PPOX_7", "A2C_4", "f[1]_5", "PPO_"):
        os.makedirs(tmp_path / name)
    for log_name in ("PPO", "A2C", "f[1]", "DQN", "PPO_x", ""):
        assert utils.get_latest_run_id(str(tmp_path), log_name) == sb3_utils.get_latest_run_id(
            str(tmp_path), log_name
        ), log_name
    assert utils.get_latest_run_id(str(tmp_path), "PPO") == 3


@pytest.mark.parametrize("verbose", [0, 1])
@pytest.mark.parametrize("reset", [True, False])
@pytest.mark.parametrize("with_tb", [True, False])
def test_configure_logger(tmp_path, verbose, reset, with_tb):
    pytest.importorskip("tensorboard")
    results = []
    for side, fn in (("ours", utils.configure_logger), ("theirs", sb3_utils.configure_logger)):
        folder = tmp_path / side
        os.makedirs(folder / "run_2")
        lg = fn(verbose, str(folder) if with_tb else None, "run", reset)
        kinds = sorted(type(f).__name__ for f in lg.output_formats)
        where = os.path.relpath(lg.get_dir(), folder) if with_tb else None
        results.append((kinds, where))
        lg.close()
    assert results[0] == results[1]


def test_check_for_correct_spaces():
    env, their_env = palaestra.make("CartPole-v1"), gymnasium.make("CartPole-v1")
    obs, act = env.observation_space, env.action_space
    utils.check_for_correct_spaces(env, obs, act)
    sb3_utils.check_for_correct_spaces(
        their_env, their_env.observation_space, their_env.action_space
    )
    g = gymnasium.spaces
    for ours_args, their_args in (
        ((spaces.Discrete(3), act), (g.Discrete(3), their_env.action_space)),
        ((obs, spaces.Discrete(3)), (their_env.observation_space, g.Discrete(3))),
    ):
        ours = _raised(lambda a=ours_args: utils.check_for_correct_spaces(env, *a))
        theirs = _raised(lambda a=their_args: sb3_utils.check_for_correct_spaces(their_env, *a))
        assert type(ours) is type(theirs) is ValueError
        assert str(ours) == str(theirs)


def test_check_shape_equal_raises_what_sb3_raises_with_its_words():
    g = gymnasium.spaces
    cases = [
        (g.Box(0, 1, (2,)), g.Box(0, 1, (2,))),
        (g.Box(0, 1, (2,)), g.Box(0, 1, (3,))),
        (g.Dict({"a": g.Box(0, 1, (2,))}), g.Dict({"b": g.Box(0, 1, (2,))})),
        (g.Dict({"a": g.Box(0, 1, (2,))}), g.Dict({"a": g.Box(0, 1, (4,))})),
        (g.Dict({"a": g.Box(0, 1, (2,))}), g.Box(0, 1, (2,))),
        (g.Discrete(2), g.Discrete(5)),
    ]
    for one, two in cases:
        try:
            sb3_utils.check_shape_equal(one, two)
            theirs = None
        except AssertionError as exc:
            theirs = str(exc)
        a, b = from_gymnasium_space(one), from_gymnasium_space(two)
        if theirs is None:
            utils.check_shape_equal(a, b)
        else:
            ours = _raised(lambda a=a, b=b: utils.check_shape_equal(a, b))
            assert isinstance(ours, ValueError) and isinstance(ours, AssertionError)
            assert str(ours) == theirs.replace("gymnasium.spaces.", "palaestra.spaces.")


_SPACES = {
    "box": (spaces.Box(-1, 1, (2,)), gymnasium.spaces.Box(-1, 1, (2,))),
    "discrete": (spaces.Discrete(2), gymnasium.spaces.Discrete(2)),
    "multidiscrete": (spaces.MultiDiscrete([2, 3]), gymnasium.spaces.MultiDiscrete([2, 3])),
    "multibinary": (spaces.MultiBinary(3), gymnasium.spaces.MultiBinary(3)),
}
_SHAPES = [(), (1,), (2,), (3,), (1, 2), (4, 2), (2, 3), (1, 3), (2, 1), (1, 1), (1, 2, 2)]


@pytest.mark.parametrize("kind", sorted(_SPACES))
@pytest.mark.parametrize("shape", _SHAPES)
def test_is_vectorized_observation_matches_sb3(kind, shape):
    ours_space, their_space = _SPACES[kind]
    obs = np.ones(shape, dtype=np.int8)
    for ours_fn, theirs_fn in (
        (utils.is_vectorized_observation, sb3_utils.is_vectorized_observation),
        (
            getattr(utils, f"is_vectorized_{kind}_observation"),
            getattr(sb3_utils, f"is_vectorized_{kind}_observation"),
        ),
    ):
        try:
            theirs = theirs_fn(obs, their_space)
        except ValueError as exc:
            ours = _raised(lambda f=ours_fn: f(obs, ours_space))
            assert type(ours) is ValueError and str(ours) == str(exc)
        else:
            assert ours_fn(obs, ours_space) is theirs


@pytest.mark.parametrize(
    ("box_shape", "discrete_shape"),
    [((2,), ()), ((1, 2), (1,)), ((2,), (1,)), ((1, 2), ()), ((1, 1, 2), (1,)), ((1, 2), (1, 1))],
)
def test_is_vectorized_dict_observation_matches_sb3(box_shape, discrete_shape):
    ours_space = spaces.Dict({"box": _SPACES["box"][0], "discrete": _SPACES["discrete"][0]})
    their_space = gymnasium.spaces.Dict(
        {"box": _SPACES["box"][1], "discrete": _SPACES["discrete"][1]}
    )
    obs = {"box": np.ones(box_shape), "discrete": np.ones(discrete_shape, dtype=np.int8)}
    try:
        theirs = sb3_utils.is_vectorized_observation(obs, their_space)
    except ValueError as exc:
        ours = _raised(lambda: utils.is_vectorized_dict_observation(obs, ours_space))
        assert type(ours) is ValueError and str(ours) == str(exc)
    else:
        assert utils.is_vectorized_observation(obs, ours_space) is theirs


def test_is_vectorized_observation_of_an_unknown_space():
    ours = _raised(lambda: utils.is_vectorized_observation(0, spaces.Tuple([spaces.Discrete(2)])))
    theirs = _raised(
        lambda: sb3_utils.is_vectorized_observation(
            0, gymnasium.spaces.Tuple([gymnasium.spaces.Discrete(2)])
        )
    )
    assert type(ours) is type(theirs) is ValueError
    assert str(ours).split("space type")[0] == str(theirs).split("space type")[0]


def test_obs_as_tensor():
    obs = np.arange(6, dtype=np.float32).reshape(2, 3)
    ours, theirs = utils.obs_as_tensor(obs, "cpu"), sb3_utils.obs_as_tensor(obs, "cpu")
    assert torch.equal(ours, theirs) and ours.dtype == theirs.dtype
    ours = utils.obs_as_tensor({"a": obs, "b": obs[0]}, torch.device("cpu"))
    theirs = sb3_utils.obs_as_tensor({"a": obs, "b": obs[0]}, torch.device("cpu"))
    assert ours.keys() == theirs.keys() and all(torch.equal(ours[k], theirs[k]) for k in ours)
    for bad in ([1, 2], 3):
        ours_exc = _raised(lambda bad=bad: utils.obs_as_tensor(bad, "cpu"))
        theirs_exc = _raised(lambda bad=bad: sb3_utils.obs_as_tensor(bad, "cpu"))
        assert type(ours_exc) is type(theirs_exc) is TypeError
        assert str(ours_exc) == str(theirs_exc)


@pytest.mark.parametrize("unit", ["step", "episode"])
@pytest.mark.parametrize(("steps", "episodes"), [(0, 0), (3, 0), (4, 1), (5, 2), (1, 4)])
def test_should_collect_more_steps(unit, steps, episodes):
    ours = type_aliases.TrainFreq(4 if unit == "step" else 2, type_aliases.TrainFrequencyUnit(unit))
    theirs = sb3_types.TrainFreq(ours.frequency, sb3_types.TrainFrequencyUnit(unit))
    assert utils.should_collect_more_steps(
        ours, steps, episodes
    ) is sb3_utils.should_collect_more_steps(theirs, steps, episodes)


def test_should_collect_more_steps_refuses_another_unit():
    ours = _raised(lambda: utils.should_collect_more_steps(type_aliases.TrainFreq(1, "x"), 0, 0))
    theirs = _raised(lambda: sb3_utils.should_collect_more_steps(sb3_types.TrainFreq(1, "x"), 0, 0))
    assert type(ours) is type(theirs) is ValueError and str(ours) == str(theirs)


def test_update_learning_rate():
    params = [nn.Parameter(torch.zeros(2))]
    ours = torch.optim.Adam([{"params": params}, {"params": [nn.Parameter(torch.ones(1))]}])
    theirs = torch.optim.Adam([{"params": params}, {"params": [nn.Parameter(torch.ones(1))]}])
    utils.update_learning_rate(ours, 0.123)
    sb3_utils.update_learning_rate(theirs, 0.123)
    assert [g["lr"] for g in ours.param_groups] == [g["lr"] for g in theirs.param_groups]
    assert [g["lr"] for g in ours.param_groups] == [0.123, 0.123]


def test_model_set_env_checks_spaces_with_sb3s_words():
    from palaestra.algos import PPO

    model = PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=32)
    exc = _raised(lambda: model.set_env(palaestra.make("Acrobot-v1")))
    assert type(exc) is ValueError
    assert str(exc) == (
        f"Observation spaces do not match: {model.observation_space} != "
        f"{palaestra.make('Acrobot-v1').observation_space}"
    )


# -- torch_layers -------------------------------------------------------------------------
@pytest.mark.parametrize(
    "kwargs",
    [
        dict(input_dim=4, output_dim=2, net_arch=[8, 8]),
        dict(input_dim=4, output_dim=0, net_arch=[8]),
        dict(input_dim=4, output_dim=3, net_arch=[]),
        dict(input_dim=4, output_dim=0, net_arch=[]),
        dict(input_dim=4, output_dim=2, net_arch=[5, 6], activation_fn=nn.Tanh, squash_output=True),
        dict(input_dim=3, output_dim=1, net_arch=[4], with_bias=False),
        dict(
            input_dim=3,
            output_dim=2,
            net_arch=[4, 5],
            pre_linear_modules=[nn.BatchNorm1d],
            post_linear_modules=[nn.LayerNorm],
        ),
    ],
)
def test_create_mlp_matches_sb3(kwargs):
    torch.manual_seed(0)
    ours = nn.Sequential(*networks.create_mlp(**kwargs))
    torch.manual_seed(0)
    theirs = nn.Sequential(*sb3_layers.create_mlp(**kwargs))
    assert repr(ours) == repr(theirs)
    ours.load_state_dict(theirs.state_dict())
    ours.eval(), theirs.eval()
    x = torch.randn(5, kwargs["input_dim"])
    torch.testing.assert_close(ours(x), theirs(x), rtol=0, atol=1e-6)


@pytest.mark.parametrize(
    "net_arch", [[64, 64], [], dict(pi=[8], qf=[16, 16]), dict(pi=[8]), dict(qf=[8])]
)
def test_get_actor_critic_arch(net_arch):
    try:
        theirs = sb3_layers.get_actor_critic_arch(net_arch)
    except AssertionError as exc:
        ours = _raised(lambda: networks.get_actor_critic_arch(net_arch))
        assert type(ours) is ValueError  # SB3: AssertionError (docs/differences.md)
        assert str(ours).startswith(str(exc))
    else:
        assert networks.get_actor_critic_arch(net_arch) == theirs


# -- vec_env ------------------------------------------------------------------------------
def test_vec_env_type_aliases_and_cloudpickle_wrapper():
    assert vec_base.VecEnvIndices == vec_base.Indices
    assert vec_base.VecEnvStepReturn == vec_base.StepReturn
    assert str(vec_base.VecEnvObs).count("ndarray") == str(sb3_base_vec_env.VecEnvObs).count(
        "ndarray"
    )
    scale = 3

    class Local:
        def __init__(self) -> None:
            self.scale = scale

    for cls in (vec_base.CloudpickleWrapper, sb3_base_vec_env.CloudpickleWrapper):
        wrapped = pickle.loads(pickle.dumps(cls(lambda: scale * 2)))
        assert wrapped.var() == 6
        assert pickle.loads(pickle.dumps(cls(var=Local))).var().scale == 3
        wrapped.var = 5
        assert wrapped.var == 5
    from palaestra.vec_env import CloudpickleWrapper

    assert CloudpickleWrapper is vec_base.CloudpickleWrapper
    import threading

    exc = _raised(lambda: pickle.dumps(vec_base.CloudpickleWrapper(threading.Lock())))
    theirs = _raised(lambda: pickle.dumps(sb3_base_vec_env.CloudpickleWrapper(threading.Lock())))
    assert type(exc) is type(theirs) is TypeError and "lock" in str(exc)


_OBS_SPACES = [
    (spaces.Box(0, 1, (2, 3)), gymnasium.spaces.Box(0, 1, (2, 3))),
    (spaces.Discrete(4), gymnasium.spaces.Discrete(4)),
    (
        spaces.Dict({"a": spaces.Box(0, 1, (2,)), "b": spaces.Discrete(3)}),
        gymnasium.spaces.Dict(
            {"a": gymnasium.spaces.Box(0, 1, (2,)), "b": gymnasium.spaces.Discrete(3)}
        ),
    ),
    (
        spaces.Tuple([spaces.MultiBinary(2), spaces.Box(0, 1, (1,), np.float64)]),
        gymnasium.spaces.Tuple(
            [gymnasium.spaces.MultiBinary(2), gymnasium.spaces.Box(0, 1, (1,), np.float64)]
        ),
    ),
]


@pytest.mark.parametrize("pair", range(len(_OBS_SPACES)))
def test_obs_space_info_and_dict_to_obs(pair):
    ours_space, their_space = _OBS_SPACES[pair]
    ours, theirs = vec_util.obs_space_info(ours_space), sb3_vec_util.obs_space_info(their_space)
    assert ours == theirs
    keys, shapes, dtypes = ours
    arrays = {k: np.zeros((2, *shapes[k]), dtypes[k]) for k in keys}
    a, b = vec_util.dict_to_obs(ours_space, arrays), sb3_vec_util.dict_to_obs(their_space, arrays)
    assert type(a) is type(b)
    if isinstance(a, dict):
        assert a is arrays and b is arrays
    elif isinstance(a, tuple):
        assert all(x is y for x, y in zip(a, b, strict=True))
    else:
        assert a is b


def test_obs_space_info_and_dict_to_obs_errors():
    nested = spaces.Dict({"a": spaces.Dict({"b": spaces.Discrete(2)})})
    their_nested = gymnasium.spaces.Dict(
        {"a": gymnasium.spaces.Dict({"b": gymnasium.spaces.Discrete(2)})}
    )
    ours, theirs = (
        _raised(lambda: vec_util.obs_space_info(nested)),
        _raised(lambda: sb3_vec_util.obs_space_info(their_nested)),
    )
    assert type(ours) is type(theirs) is NotImplementedError
    two = {None: np.zeros(1), "x": np.zeros(1)}
    ours = _raised(lambda: vec_util.dict_to_obs(spaces.Discrete(2), two))
    theirs = _raised(lambda: sb3_vec_util.dict_to_obs(gymnasium.spaces.Discrete(2), two))
    assert type(ours) is ValueError and type(theirs) is AssertionError  # docs/differences.md
    assert str(ours).startswith(str(theirs))
    tup = _OBS_SPACES[3][0]
    assert "size of observation does not match" in str(
        _raised(lambda: vec_util.dict_to_obs(tup, {0: np.zeros(1)}))
    )


def test_is_wrapped_and_unwrap_wrapper():
    env = palaestra.Wrapper(palaestra.make("Pendulum-v1"))
    assert not env_util.is_wrapped(env, Monitor)
    assert env_util.unwrap_wrapper(env, Monitor) is None
    monitor_env = Monitor(env)
    outer = palaestra.Wrapper(monitor_env)
    assert env_util.is_wrapped(monitor_env, Monitor) and env_util.is_wrapped(outer, Monitor)
    assert env_util.unwrap_wrapper(outer, Monitor) is monitor_env
    # SB3's, on Gymnasium's envs: the same answers
    from stable_baselines3.common.monitor import Monitor as SB3Monitor

    genv = gymnasium.Wrapper(gymnasium.make("Pendulum-v1"))
    assert sb3_env_util.is_wrapped(genv, SB3Monitor) is env_util.is_wrapped(env, Monitor)
    gmon = SB3Monitor(genv)
    assert sb3_env_util.unwrap_wrapper(gymnasium.Wrapper(gmon), SB3Monitor) is gmon


# -- preprocessing, base_class -------------------------------------------------------------
@pytest.mark.parametrize("shape", [(3, 8, 6), (8, 6, 3), (2, 3, 8, 6), (2, 8, 6, 3), (5, 5)])
def test_maybe_transpose(shape):
    ours_space = spaces.Box(0, 255, (3, 8, 6), np.uint8)
    their_space = gymnasium.spaces.Box(0, 255, (3, 8, 6), np.uint8)
    obs = np.arange(int(np.prod(shape)), dtype=np.uint8).reshape(shape)
    if len(shape) == 2:  # neither one image nor a batch: numpy's error on both sides
        ours_exc = _raised(lambda: preprocessing.maybe_transpose(obs, ours_space))
        theirs_exc = _raised(lambda: sb3_pre.maybe_transpose(obs, their_space))
        assert type(ours_exc) is type(theirs_exc) is ValueError
        return
    ours = preprocessing.maybe_transpose(obs, ours_space)
    theirs = sb3_pre.maybe_transpose(obs, their_space)
    np.testing.assert_array_equal(ours, theirs)
    assert ours.shape == theirs.shape
    flat = spaces.Box(0, 1, (8, 6, 3))
    assert preprocessing.maybe_transpose(obs, flat) is obs


def test_maybe_make_env(capsys):
    env = base.maybe_make_env("CartPole-v1", verbose=1)
    theirs = sb3_base.maybe_make_env("CartPole-v1", verbose=1)
    out = capsys.readouterr().out
    assert out == "Creating environment from the given name 'CartPole-v1'\n" * 2
    assert env.render_mode == theirs.render_mode == "rgb_array"
    assert env.spec.id == theirs.spec.id
    assert base.maybe_make_env(env, verbose=1) is env and capsys.readouterr().out == ""


def test_get_system_info_at_sb3s_path():
    import stable_baselines3

    import palaestra.algos

    assert palaestra.algos.get_system_info is utils.get_system_info
    assert callable(stable_baselines3.get_system_info)


# -- Gymnasium's EzPickle ------------------------------------------------------------------
class _Ours(palaestra.utils.EzPickle):
    def __init__(self, a, b=2):
        palaestra.utils.EzPickle.__init__(self, a, b=b)
        self.a, self.b, self.later = a, b, None


class _Theirs(gymnasium.utils.EzPickle):
    def __init__(self, a, b=2):
        gymnasium.utils.EzPickle.__init__(self, a, b=b)
        self.a, self.b, self.later = a, b, None


def test_ezpickle_matches_gymnasium():
    assert "EzPickle" in palaestra.utils.__all__
    for cls in (_Ours, _Theirs):
        obj = cls([1], b="x")
        obj.later = "changed after __init__"
        back = pickle.loads(pickle.dumps(obj))
        assert (back.a, back.b, back.later) == ([1], "x", None)
        assert obj.__getstate__() == {"_ezpickle_args": ([1],), "_ezpickle_kwargs": {"b": "x"}}
