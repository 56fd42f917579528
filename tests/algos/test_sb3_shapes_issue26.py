"""Issue 26, API shapes SB3 code calls, each side by side with stable-baselines3: ``net_arch=None``
and the pre-1.8 ``[dict(...)]``, CnnPolicy on float images, ``load_results`` of an empty monitor
file, ``load_replay_buffer``'s device, ``evaluate_policy``'s callback locals and Monitor warning,
``EvalCallback``'s env-type warning, ``train_freq`` and ``VectorizedActionNoise`` errors, and
``DummyVecEnv`` of a nested Dict env."""

from __future__ import annotations

import importlib.util
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

import palaestra
from palaestra import spaces
from palaestra.algos import DQN, PPO, TD3
from palaestra.algos.action_noise import NormalActionNoise, VectorizedActionNoise
from palaestra.algos.callbacks import EvalCallback
from palaestra.algos.evaluation import evaluate_policy
from palaestra.vec_env import DummyVecEnv, VecNormalize
from palaestra.wrappers.monitor import Monitor, load_results

HAS_SB3 = importlib.util.find_spec("stable_baselines3") is not None
pytestmark = pytest.mark.skipif(not HAS_SB3, reason="stable-baselines3 (dev dependency) missing")


def _raised(fn: Any) -> BaseException | None:
    try:
        fn()
    except BaseException as exc:  # the exception is the result
        return exc
    return None


# -- net_arch ----------------------------------------------------------------------------------
def test_net_arch_none_is_the_default_after_save_and_load(tmp_path: Path) -> None:
    """SB3's test_save_load_net_arch_none (GH#1928): the policy keeps the default net_arch."""
    from stable_baselines3 import PPO as SB3PPO

    archs = []
    for cls, path in ((PPO, tmp_path / "ours.zip"), (SB3PPO, tmp_path / "sb3.zip")):
        cls("MlpPolicy", "CartPole-v1", policy_kwargs={"net_arch": None}).save(path)
        model = cls.load(path)
        assert model.policy_kwargs == {"net_arch": None}  # the argument is kept as given
        archs.append(model.policy.net_arch)
    assert archs[0] == archs[1] == {"pi": [64, 64], "vf": [64, 64]}


def test_old_style_net_arch_warns_and_is_converted(tmp_path: Path) -> None:
    """SB3 < 1.8's ``[dict(vf=[8])]``: SB3's UserWarning, then the dict (no pi layers)."""
    from stable_baselines3 import PPO as SB3PPO

    nets = []
    for cls in (PPO, SB3PPO):
        with pytest.warns(UserWarning, match=r"instead of net_arch=\[dict\(pi=..., vf=...\)\]"):
            model = cls("MlpPolicy", "CartPole-v1", policy_kwargs={"net_arch": [{"vf": [8]}]})
        nets.append(model.policy.net_arch)
        shapes = sorted(tuple(p.shape) for p in model.policy.parameters())
        assert (8, 4) in shapes and (64, 4) not in shapes  # vf [8], no pi layer
    assert nets[0] == nets[1] == {"vf": [8]}
    with pytest.warns(UserWarning, match="As shared layers in the mlp_extractor are removed"):
        model = PPO("MlpPolicy", "CartPole-v1", policy_kwargs={"net_arch": [{"vf": [8]}]})
    model.save(tmp_path / "old")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the file holds SB3's converted form: no warning
        loaded = PPO.load(tmp_path / "old")
    assert loaded.policy.net_arch == {"vf": [8]}


# -- CnnPolicy and float images ----------------------------------------------------------------
class _FloatImages(palaestra.Env):  # type: ignore[type-arg]
    """Channel-first float images, as VecNormalize hands an image env's observations on."""

    observation_space = spaces.Box(-10.0, 10.0, (3, 40, 40), np.float32)
    action_space = spaces.Discrete(2)

    def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[Any, dict]:
        super().reset(seed=seed)
        return np.zeros((3, 40, 40), np.float32), {}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        return np.zeros((3, 40, 40), np.float32), 0.0, False, False, {}


def _sb3_float_images() -> Any:
    import gymnasium

    class FloatImages(gymnasium.Env):  # type: ignore[type-arg]
        observation_space = gymnasium.spaces.Box(-10.0, 10.0, (3, 40, 40), np.float32)
        action_space = gymnasium.spaces.Discrete(2)

        def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[Any, dict]:
            return np.zeros((3, 40, 40), np.float32), {}

        def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
            return np.zeros((3, 40, 40), np.float32), 0.0, False, False, {}

    return FloatImages()


@pytest.mark.parametrize("algo", ["PPO", "DQN", "TD3"])
def test_cnn_policy_refuses_float_images_unless_normalize_images_false(algo: str) -> None:
    """SB3's NatureCNN refuses them (an AssertionError); ours is a ValueError that says what
    to pass. With ``normalize_images=False`` both build the CNN on them."""
    import stable_baselines3 as sb3

    ours_cls, theirs_cls = {"PPO": (PPO, sb3.PPO), "DQN": (DQN, sb3.DQN), "TD3": (TD3, sb3.TD3)}[
        algo
    ]
    ours_env, theirs_env = _FloatImages(), _sb3_float_images()
    if algo == "TD3":  # a Box action space
        ours_env.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        import gymnasium

        theirs_env.action_space = gymnasium.spaces.Box(-1.0, 1.0, (1,), np.float32)
    small = {"buffer_size": 10} if algo != "PPO" else {}
    ours = _raised(lambda: ours_cls("CnnPolicy", ours_env, **small))
    theirs = _raised(lambda: theirs_cls("CnnPolicy", theirs_env, **small))
    assert type(theirs) is AssertionError and "normalize_images=False" in str(theirs)
    assert type(ours) is ValueError
    assert str(ours) == (
        "NatureCNN with normalize_images=True needs uint8 images with bounds 0..255, got "
        f"{_FloatImages.observation_space}; for images already normalised (VecNormalize, float "
        "images) pass policy_kwargs=dict(normalize_images=False)"
    )
    # (net_arch given: palaestra's TD3 CnnPolicy defaults to [400, 300], SB3's to [256, 256])
    kwargs = {"policy_kwargs": {"normalize_images": False, "net_arch": [64]}, **small}
    model = ours_cls("CnnPolicy", ours_env, **kwargs)
    sb3_model = theirs_cls("CnnPolicy", theirs_env, **kwargs)
    ours_shapes = [tuple(p.shape) for p in model.policy.parameters()]
    theirs_shapes = [tuple(p.shape) for p in sb3_model.policy.parameters()]
    assert sorted(ours_shapes) == sorted(theirs_shapes)


def test_vec_normalized_images_need_normalize_images_false() -> None:
    """SB3's test_image_like_input: VecNormalize makes an image env's observations floats
    (its space too, SB3 GH#1214), which CnnPolicy refuses unless normalize_images=False."""
    from stable_baselines3 import PPO as SB3PPO
    from stable_baselines3.common.envs import FakeImageEnv
    from stable_baselines3.common.vec_env import DummyVecEnv as SB3DummyVecEnv
    from stable_baselines3.common.vec_env import VecNormalize as SB3VecNormalize

    class Images(_FloatImages):
        observation_space = spaces.Box(0, 255, (1, 36, 36), np.uint8)

        def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[Any, dict]:
            return np.zeros((1, 36, 36), np.uint8), {}

        def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
            return np.zeros((1, 36, 36), np.uint8), 0.0, False, False, {}

    def sb3_env() -> Any:
        env = FakeImageEnv(screen_height=36, screen_width=36, n_channels=1, channel_first=True)
        return SB3VecNormalize(SB3DummyVecEnv([lambda: env]))

    ours_env, theirs_env = VecNormalize(DummyVecEnv([Images])), sb3_env()
    assert ours_env.observation_space == spaces.Box(-10.0, 10.0, (1, 36, 36), np.float32)
    assert theirs_env.observation_space.dtype == np.float32
    kwargs: dict[str, Any] = {"n_steps": 64, "batch_size": 32, "n_epochs": 1, "seed": 1}
    features = {"features_extractor_kwargs": {"features_dim": 32}}
    ours = _raised(lambda: PPO("CnnPolicy", ours_env, policy_kwargs=features, **kwargs))
    theirs = _raised(lambda: SB3PPO("CnnPolicy", theirs_env, policy_kwargs=features, **kwargs))
    assert type(theirs) is AssertionError and type(ours) is ValueError
    assert "pass policy_kwargs=dict(normalize_images=False)" in str(ours)
    features["normalize_images"] = False
    PPO("CnnPolicy", ours_env, policy_kwargs=features, **kwargs).learn(64)
    SB3PPO("CnnPolicy", theirs_env, policy_kwargs=features, **kwargs).learn(64)


# -- load_results ------------------------------------------------------------------------------
def test_load_results_of_a_monitor_file_without_episodes(tmp_path: Path) -> None:
    """A Monitor closed before its first episode ended: SB3's empty table, same columns."""
    import gymnasium
    from stable_baselines3.common.monitor import Monitor as SB3Monitor
    from stable_baselines3.common.monitor import load_results as sb3_load_results

    (tmp_path / "ours").mkdir()
    (tmp_path / "sb3").mkdir()
    env = Monitor(palaestra.make("CartPole-v1"), str(tmp_path / "ours"))
    env.reset(seed=0)
    env.step(0)
    env.close()
    sb3_env = SB3Monitor(gymnasium.make("CartPole-v1"), str(tmp_path / "sb3"))
    sb3_env.reset(seed=0)
    sb3_env.step(0)
    sb3_env.close()
    ours, theirs = load_results(str(tmp_path / "ours")), sb3_load_results(str(tmp_path / "sb3"))
    assert ours.empty and theirs.empty
    assert list(ours.columns) == list(theirs.columns) == ["index", "r", "l", "t"]
    assert ours.shape == theirs.shape == (0, 4)


# SB3's test_monitor_load_results data: hand-written files without a final line end.
DEMO_MONITOR = (
    '#{"t_start": 1771532779.9940808, "env_id": "Pendulum-v1"}\nr,l,t\n-1463.466035,200,1.622209'
)
EMPTY_MONITOR = '#{"t_start": 1771532779.9920808, "env_id": "Pendulum-v1"}\nr,l,t'


def test_load_results_of_files_without_a_final_line_end(tmp_path: Path) -> None:
    """A header and no episode: an empty table; with a whole last row, that row (a torn one,
    with fields missing, is still left out: tests/wrappers/test_monitor.py)."""
    from stable_baselines3.common.monitor import load_results as sb3_load_results

    (tmp_path / "empty_monitor.csv").write_text(EMPTY_MONITOR)
    frames = [load(tmp_path) for load in (load_results, sb3_load_results)]
    for frame in frames:
        assert frame.empty and list(frame.columns) == ["index", "r", "l", "t"]
    (tmp_path / "0.monitor.csv").write_text(DEMO_MONITOR)
    for load in (load_results, sb3_load_results):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # SB3 GH#2213: mixed empty/non-empty, no warning
            frame = load(tmp_path)
        assert list(frame.columns) == ["index", "r", "l", "t"] and len(frame) == 1
        assert frame["l"].tolist() == [200] and frame["r"].tolist() == [-1463.466035]


# -- replay buffer device ----------------------------------------------------------------------
def test_load_replay_buffer_follows_the_model_device(tmp_path: Path) -> None:
    """SB3's test_save_load_replay_buffer (GH#1561), with the meta device as the other one."""
    from stable_baselines3 import DQN as SB3DQN

    kwargs: dict[str, Any] = {"buffer_size": 1000, "learning_starts": 200}
    kwargs["policy_kwargs"] = {"net_arch": [64]}
    for cls in (DQN, SB3DQN):
        model = cls("MlpPolicy", "CartPole-v1", **kwargs).learn(300)
        model.save_replay_buffer(tmp_path / f"{cls.__module__}.pkl")
        for device in ("meta", "cpu"):
            model.device = torch.device(device)
            model.load_replay_buffer(tmp_path / f"{cls.__module__}.pkl")
            assert model.replay_buffer.device.type == device


# -- evaluate_policy and EvalCallback ----------------------------------------------------------
@pytest.mark.parametrize("vectorized", [False, True])
def test_evaluate_policy_callback_locals_and_monitor_warning(vectorized: bool) -> None:
    """SB3's test_evaluate_policy: the callback reads ``locals_["model"]``, once per step; an
    env without Monitor gets SB3's UserWarning."""
    import gymnasium
    from stable_baselines3 import A2C as SB3A2C
    from stable_baselines3.common.evaluation import evaluate_policy as sb3_evaluate
    from stable_baselines3.common.vec_env import DummyVecEnv as SB3DummyVecEnv

    from palaestra.algos import A2C

    def make(lib: str) -> Any:
        if lib == "sb3":
            env = gymnasium.make("Pendulum-v1")
            return SB3DummyVecEnv([lambda: env]) if vectorized else env
        env = palaestra.make("Pendulum-v1")
        return DummyVecEnv([lambda: env]) if vectorized else env

    for lib, cls, evaluate in (("ours", A2C, evaluate_policy), ("sb3", SB3A2C, sb3_evaluate)):
        model = cls("MlpPolicy", "Pendulum-v1", seed=0)
        calls: list[Any] = []

        def callback(locals_: dict[str, Any], _: dict[str, Any], calls: list = calls) -> None:
            calls.append(locals_["model"])

        with pytest.warns(UserWarning, match="not wrapped with a ``Monitor`` wrapper"):
            _, lengths = evaluate(
                model, make(lib), 2, callback=callback, return_episode_rewards=True
            )
        assert sum(lengths) == 400 == len(calls), lib
        assert all(m is model for m in calls)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            evaluate(model, make(lib), 1, warn=False)


def test_eval_callback_warns_when_the_eval_env_type_differs() -> None:
    """SB3 warns at the start of learn when the training and eval envs differ in type (a
    VecNormalize on one side only); a plain env or another engine face does not warn."""
    import gymnasium
    from stable_baselines3 import PPO as SB3PPO
    from stable_baselines3.common.callbacks import EvalCallback as SB3EvalCallback
    from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize as SB3VecNormalize

    from palaestra.vec_env import make_vec_env

    cases = [
        ("ours", PPO, EvalCallback, make_vec_env, VecNormalize, palaestra.make),
        ("sb3", SB3PPO, SB3EvalCallback, sb3_make_vec_env, SB3VecNormalize, gymnasium.make),
    ]
    for _, algo, callback, make_vec, normalize, make in cases:
        model = algo("MlpPolicy", normalize(make_vec("CartPole-v1")), n_steps=64, batch_size=64)
        eval_env = make_vec("CartPole-v1")
        with pytest.warns(UserWarning, match="Training and eval env are not of the same type"):
            model.learn(64, callback=callback(eval_env, eval_freq=10**6, warn=False))
        model = algo("MlpPolicy", make_vec("CartPole-v1"), n_steps=64, batch_size=64)
        for other in (make("CartPole-v1"), make_vec("CartPole-v1")):
            with warnings.catch_warnings():
                warnings.simplefilter("error", UserWarning)
                model.learn(64, callback=callback(other, eval_freq=10**6, warn=False))


# -- errors ------------------------------------------------------------------------------------
def test_train_freq_with_a_string_count_is_a_value_error() -> None:
    from stable_baselines3 import DQN as SB3DQN

    ours = _raised(lambda: DQN("MlpPolicy", "CartPole-v1", train_freq=("1", "episode")))
    theirs = _raised(lambda: SB3DQN("MlpPolicy", "CartPole-v1", train_freq=("1", "episode")))
    assert type(theirs) is ValueError and type(ours) is ValueError
    assert str(ours) == (
        "train_freq must be a positive int or (n, \"step\"|\"episode\"), got ('1', 'episode')"
    )


def test_vectorized_action_noise_of_none_is_a_value_error() -> None:
    from stable_baselines3.common.noise import VectorizedActionNoise as SB3Noise

    ours = _raised(lambda: VectorizedActionNoise(None, 2))
    theirs = _raised(lambda: SB3Noise(None, 2))
    assert type(ours) is type(theirs) is ValueError
    assert str(ours) == "Expected base_noise to be an instance of ActionNoise, not None"
    base = NormalActionNoise(np.zeros(1), np.ones(1))
    ours = _raised(lambda: VectorizedActionNoise(base, 0))
    theirs = _raised(lambda: SB3Noise(base, 0))
    assert type(ours) is type(theirs) is ValueError


class _NestedDict(palaestra.Env):  # type: ignore[type-arg]
    observation_space = spaces.Dict(
        {"a": spaces.Discrete(2), "nested": spaces.Dict({"b": spaces.Discrete(3)})}
    )
    action_space = spaces.Discrete(2)

    def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[Any, dict]:
        return self.observation_space.sample(), {}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        return self.observation_space.sample(), 0.0, False, False, {}


def test_dummy_vec_env_of_a_nested_dict_env_is_not_implemented() -> None:
    import gymnasium
    from stable_baselines3.common.vec_env import DummyVecEnv as SB3DummyVecEnv

    class NestedDict(gymnasium.Env):  # type: ignore[type-arg]
        inner = gymnasium.spaces.Dict({"b": gymnasium.spaces.Discrete(3)})
        observation_space = gymnasium.spaces.Dict(
            {"a": gymnasium.spaces.Discrete(2), "nested": inner}
        )
        action_space = gymnasium.spaces.Discrete(2)

    ours = _raised(lambda: DummyVecEnv([_NestedDict]))
    theirs = _raised(lambda: SB3DummyVecEnv([NestedDict]))
    assert type(ours) is type(theirs) is NotImplementedError
    assert str(ours).startswith(str(theirs)[:-1])  # SB3's words, then the space
    DummyVecEnv([lambda: _FloatImages()]).close()  # one level of keys (or none) is fine
