"""What a model file may hand ``DQN``/``PPO``: the saved hyperparameters only, within limits
(``palaestra.algos.common.hyperparams``), checked before anything is allocated."""

from __future__ import annotations

import inspect
import math
import tracemalloc
from pathlib import Path
from typing import Any

import pytest

from palaestra.algos import A2C, DQN, PPO, ModelFileError
from palaestra.algos.common import hyperparams as hp
from palaestra.algos.common.model_io import read_archive, write_archive
from palaestra.algos.common.off_policy import OffPolicyAlgorithm
from palaestra.algos.common.off_policy_actor_critic import ActorCriticOffPolicy
from palaestra.runs.algorithms import ALGO_CLASSES, REGISTRY, algo_class

DECLARED = [algo_class(entry.name) for entry in REGISTRY]
ACTOR_CRITICS = [cls for cls in DECLARED if issubclass(cls, ActorCriticOffPolicy)]


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A small DQN, PPO and A2C model file (untrained: only the metadata matters here)."""
    root = tmp_path_factory.mktemp("models")
    DQN("MlpPolicy", "CartPole-v1", buffer_size=1000, seed=0).save(root / "dqn.zip")
    PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=16, seed=0).save(root / "ppo.zip")
    A2C("MlpPolicy", "CartPole-v1", seed=0).save(root / "a2c.zip")
    return {"DQN": root / "dqn.zip", "PPO": root / "ppo.zip", "A2C": root / "a2c.zip"}


def _tamper(source: Path, target: Path, **changes: Any) -> Path:
    """A copy of ``source`` whose metadata got ``changes`` (``hyperparameters__x=1`` sets
    ``meta["hyperparameters"]["x"]``)."""
    meta, arrays = read_archive(source, "model")
    for key, value in changes.items():
        node, parts = meta, key.split("__")
        for part in parts[:-1]:
            node = node[part]
        node[parts[-1]] = value
    write_archive(target, "model", meta, arrays)
    return target


def test_every_declared_algorithm_has_rules() -> None:
    """The rule tables hold exactly the declared algorithms: a model file of any of them is
    checked, and no rules stay behind for an algorithm that left the registry."""
    declared = set(ALGO_CLASSES.values())
    assert set(hp.HYPERPARAMETERS) == declared
    assert set(hp.SCHEDULES) == declared
    assert set(hp.POLICY_KWARGS) == declared


@pytest.mark.parametrize("cls", ACTOR_CRITICS)
def test_every_saved_value_of_the_actor_critics_has_a_rule(cls: Any) -> None:
    model = cls("MlpPolicy", "Pendulum-v1", buffer_size=100)
    name = cls.__name__
    assert set(model._hyperparameters()) == set(hp.HYPERPARAMETERS[name])
    assert set(model._schedules()) == set(hp.SCHEDULES[name])
    policy_class = type(model.policy)  # SACPolicy / TD3Policy: what policy_kwargs feed
    takes = set(inspect.signature(policy_class.__init__).parameters)
    takes -= {"self", "observation_space", "action_space", "lr_schedule"}
    takes |= {"backend"}
    assert takes == set(hp.POLICY_KWARGS[name])


@pytest.mark.parametrize("cls", [cls for cls in DECLARED if cls not in ACTOR_CRITICS])
def test_every_saved_value_has_a_rule(cls: Any) -> None:
    """The rules list exactly what the algorithm saves and what its policy takes: a new saved
    hyperparameter or policy keyword needs its rule, or loading its own files fails."""
    replay = issubclass(cls, OffPolicyAlgorithm)
    model = cls("MlpPolicy", "CartPole-v1", **({"buffer_size": 100} if replay else {}))
    name = cls.__name__
    assert set(model._hyperparameters()) == set(hp.HYPERPARAMETERS[name])
    assert set(model._schedules()) == set(hp.SCHEDULES[name])
    network = type(model.policy)  # what policy_kwargs feed (DQNPolicy, ActorCriticPolicy...)
    taken = set(inspect.signature(network.__init__).parameters)
    taken -= {"self", "observation_space", "action_space", "lr_schedule"}
    taken |= {"optimizer_class", "optimizer_kwargs", "share_features_extractor", "backend"}
    assert taken == set(hp.POLICY_KWARGS[name])


@pytest.mark.parametrize("key", ["tensorboard_log", "device", "num_threads", "_init_setup_model"])
def test_a_model_file_does_not_choose_where_learn_writes(
    saved: dict[str, Path], tmp_path: Path, key: str
) -> None:
    logs = tmp_path / "planted"
    value = {"tensorboard_log": str(logs), "device": "cuda", "num_threads": 64}.get(key, False)
    path = _tamper(saved["PPO"], tmp_path / "m.zip", **{f"hyperparameters__{key}": value})
    with pytest.raises(ModelFileError) as info:
        PPO.load(path, env="CartPole-v1")
    assert str(info.value) == (
        f"{path}: hyperparameters names {key!r}, which a model file may not set (it may set "
        + ", ".join(sorted(hp.HYPERPARAMETERS["PPO"]))
        + ")"
    )
    assert not logs.exists()
    # The user's own keyword still does (their Python, not the file).
    model = PPO.load(saved["PPO"], env="CartPole-v1", tensorboard_log=str(logs))
    assert model.tensorboard_log == str(logs)


def test_a_huge_replay_buffer_is_refused_before_allocation(
    saved: dict[str, Path], tmp_path: Path
) -> None:
    path = _tamper(saved["DQN"], tmp_path / "m.zip", hyperparameters__buffer_size=10**12)
    tracemalloc.start()
    try:
        with pytest.raises(ModelFileError) as info:
            DQN.load(path, env="CartPole-v1")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert str(info.value) == (
        f"{path}: hyperparameters buffer_size=1000000000000 is refused: expected an integer "
        f"from 1 to {hp.MAX_BUFFER_SIZE}"
    )
    assert peak < 20 << 20  # the file's arrays, not a buffer


H, P, S = "hyperparameters__", "policy_kwargs__", "schedules__"
INT = "is refused: expected an integer from"
OUT_OF_RANGE = [
    ("PPO", H + "gamma", 1.5, "gamma=1.5 is refused: expected a number in [0.0, 1.0]"),
    ("PPO", H + "gamma", math.nan, "expected a number in [0.0, 1.0]"),
    ("PPO", H + "n_steps", 0, f"n_steps=0 {INT} 1 to 1000000"),
    ("PPO", H + "n_epochs", -1, f"n_epochs=-1 {INT} 1 to 10000"),
    ("PPO", H + "batch_size", "64", "batch_size='64' is refused: expected an integer"),
    ("PPO", H + "normalize_advantage", 1, "expected true or false"),
    ("PPO", H + "target_kl", 0, "expected null or a number in (0.0, 1000000.0]"),
    ("DQN", H + "seed", -1, "seed=-1 is refused: expected null or an integer from 0 to"),
    ("DQN", H + "train_freq", [4, "hour"], 'a positive integer or [n, "step"|"episode"]'),
    ("DQN", H + "replay_buffer_kwargs", {"device": "cuda"},
     "keys among ['copy_info_dict', 'frame_margin', 'goal_selection_strategy', "
     "'handle_timeout_termination', 'layout', 'n_sampled_goal'] (not 'device')"),
    ("DQN", H + "replay_buffer_class", "ReplayBuffer",
     "replay_buffer_class='ReplayBuffer' is refused: expected null or 'HerReplayBuffer'"),
    ("DQN", H + "replay_buffer_kwargs", {"goal_selection_strategy": "later"},
     "expected goal_selection_strategy to be 'future', 'final' or 'episode', not 'later'"),
    ("DQN", H + "exploration_final_eps", 2, "expected a number in [0.0, 1.0]"),
    ("PPO", P + "net_arch", [10**6, 10**6],
     "net_arch=[1000000, 1000000] is refused: expected null or a list of at most 64 layer"),
    # a network larger than the weights the file holds: refused before it is built
    ("PPO", P + "net_arch", [4096] * 20,
     "policy_kwargs net_arch=[4096, 4096, 4096, 4096, 4096, 4096, ...] needs at least "
     "318767104 weights, but the file's parameters hold 9155"),
    ("PPO", P + "net_arch", {"pi": [64], "vf": [64], "x": [1]},
     "expected null or a mapping with keys among ['pi', 'vf'] (not 'x')"),
    ("PPO", P + "evil", 1, "policy_kwargs names 'evil', which a model file may not set"),
    ("DQN", P + "ortho_init", True, "policy_kwargs names 'ortho_init'"),
    ("PPO", P + "optimizer_kwargs", {"lr": 1.0}, "a mapping with keys among ['alpha', 'amsgrad'"),
    ("PPO", P + "features_extractor_kwargs", {"features_dim": 10**9},
     "expected null or features_dim to be an integer from 1 to 65536, not 1000000000"),
    ("PPO", P + "activation_fn", "os.system",
     "activation_fn='os.system' is refused: expected a class as {\"__class__\": "),
    ("PPO", S + "learning_rate", {"type": "constant", "value": -1.0},
     "schedule learning_rate holds -1.0: expected a number in [0.0, 1000000.0]"),
    ("PPO", S + "clip_range", {"type": "linear", "start": 0.2, "end": 0.1, "end_fraction": 3},
     "schedule clip_range holds 3: expected a number in [0.0, 1.0]"),
    ("PPO", S + "clip_range", {"type": "table", "values": [0.1] * (hp.MAX_TABLE + 1)},
     "schedule clip_range must list 2 to 100000 values"),
    ("PPO", S + "clip_range", {"type": "code", "value": "import os"},
     "schedule clip_range is malformed"),
    ("PPO", S + "tensorboard_log", {"type": "constant", "value": 1.0},
     "schedules name 'tensorboard_log', which a model file may not set"),
    ("DQN", "n_envs", 10**9, f"n_envs=1000000000 {INT} 1 to 65536"),
    ("A2C", H + "n_steps", 0, f"n_steps=0 {INT} 1 to 1000000"),
    ("A2C", H + "rms_prop_eps", 0.0, "rms_prop_eps=0.0 is refused: expected a number in (0.0"),
    ("A2C", H + "use_rms_prop", "yes", "use_rms_prop='yes' is refused: expected true or false"),
    ("A2C", P + "ortho_init", 2, "policy_kwargs ortho_init=2 is refused: expected true or false"),
    ("A2C", S + "clip_range", {"type": "constant", "value": 0.2},
     "schedules name 'clip_range', which a model file may not set"),
]  # fmt: skip


@pytest.mark.parametrize(("algo", "key", "value", "expected"), OUT_OF_RANGE)
def test_out_of_range_values_are_refused(
    saved: dict[str, Path], tmp_path: Path, algo: str, key: str, value: Any, expected: str
) -> None:
    path = _tamper(saved[algo], tmp_path / "m.zip", **{key: value})
    cls = {"DQN": DQN, "PPO": PPO, "A2C": A2C}[algo]
    with pytest.raises(ModelFileError) as info:
        cls.load(path)
    assert str(info.value).startswith(f"{path}: ")
    assert expected in str(info.value)


def test_values_in_range_load(saved: dict[str, Path], tmp_path: Path) -> None:
    """Edges and the accepted shapes: gamma 1, train_freq as a pair, no value clipping,
    max_grad_norm inf (no clipping), PPO's separate pi/vf networks."""
    path = _tamper(
        saved["PPO"],
        tmp_path / "m.zip",
        hyperparameters__gamma=1.0,
        hyperparameters__max_grad_norm=math.inf,
        schedules__clip_range_vf=None,
    )
    model = PPO.load(path)
    assert model.gamma == 1.0 and model.max_grad_norm == math.inf
    path = _tamper(saved["DQN"], tmp_path / "d.zip", hyperparameters__train_freq=[1, "episode"])
    assert DQN.load(path).train_freq == (1, "episode")


def test_a_long_value_is_shortened_in_the_message(saved: dict[str, Path], tmp_path: Path) -> None:
    path = _tamper(saved["PPO"], tmp_path / "m.zip", policy_kwargs__net_arch=[[[[[1]]]]] * 10**4)
    with pytest.raises(ModelFileError) as info:
        PPO.load(path)
    assert len(str(info.value)) < 300


@pytest.mark.parametrize(
    ("hyperparams", "message"),
    [
        ({"tensorboard_log": "/x"}, "run: hyperparams names 'tensorboard_log', which is not a dqn "
         "hyperparameter"),
        ({"buffer_size": 10**12}, "run: hyperparams buffer_size=1000000000000 is refused: "
         "expected an integer from 1 to 100000000"),
        ({"policy_kwargs": [1]},
         "run: hyperparams policy_kwargs=[1] is refused: expected a mapping"),
        ([], "run: hyperparams must be a mapping, got []"),
    ],
)  # fmt: skip
def test_run_folder_hyperparams(hyperparams: Any, message: str) -> None:
    allowed = {"buffer_size", "learning_rate", "policy_kwargs"}
    with pytest.raises(ValueError) as info:
        hp.check_run_hyperparams("dqn", hyperparams, allowed, "run")
    assert str(info.value) == message
    # Preset-format values are left to presets.resolve; numbers in range pass.
    ok = {"learning_rate": "lin_1e-3", "buffer_size": 50_000, "policy_kwargs": {"net_arch": [64]}}
    hp.check_run_hyperparams("dqn", ok, allowed, "run")
