"""The public import paths of ``palaestra.algos`` after the move to ``common/`` and one package
per algorithm: each is the module that holds the code (the same object, never a copy), imported
on first use; and model files name classes by those paths."""

from __future__ import annotations

import importlib
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

import palaestra.algos
from palaestra.algos import DDPG, DQN, SAC, TD3, public_paths
from palaestra.algos.common.model_io import ModelFileError, decode_classes

ALIASES = sorted(public_paths.MODULE_ALIASES.items())


@pytest.mark.parametrize(("alias", "real"), ALIASES)
def test_a_public_path_is_the_module_itself(alias: str, real: str) -> None:
    module = importlib.import_module(alias)
    assert module is importlib.import_module(real)
    parent, _, leaf = alias.rpartition(".")
    assert module is sys.modules[alias] is getattr(importlib.import_module(parent), leaf)
    assert module.__name__ == module.__spec__.name == real  # its own spec, not the alias's


def test_public_paths_import_their_module_only_on_first_use() -> None:
    code = (
        "import sys, palaestra.algos\n"
        "before = 'palaestra.algos.common.results_plotter' in sys.modules\n"
        "from palaestra.algos.results_plotter import ts2xy\n"
        "import palaestra.algos.env_checker as e\n"
        "print(before, e is sys.modules['palaestra.algos.common.env_checker'])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"], out.stderr


def test_an_unknown_name_is_still_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match=r"module 'palaestra\.algos' has no attribute 'nope'"):
        palaestra.algos.nope  # noqa: B018
    with pytest.raises(ModuleNotFoundError, match=r"palaestra\.algos\.nope"):
        importlib.import_module("palaestra.algos.nope")


def test_sb3_porting_paths_of_the_algorithm_packages() -> None:
    from palaestra.algos import ddpg, dqn, sac, td3

    assert (dqn.DQN, sac.SAC, td3.TD3, ddpg.DDPG) == (DQN, SAC, TD3, DDPG)
    for package, policy in [(dqn, dqn.DQNPolicy), (sac, sac.SACPolicy), (td3, td3.TD3Policy)]:
        assert package.MlpPolicy is policy
        assert issubclass(package.CnnPolicy, policy)
        assert issubclass(package.MultiInputPolicy, policy)
    assert (ddpg.MlpPolicy, ddpg.CnnPolicy, ddpg.TD3Policy) == (
        td3.MlpPolicy,
        td3.CnnPolicy,
        td3.TD3Policy,
    )
    assert importlib.import_module("palaestra.algos.dqn.policies").QNetwork is dqn.QNetwork


@pytest.mark.parametrize(("old", "new"), sorted(public_paths.MOVED_CLASSES.items()))
def test_every_moved_class_resolves_to_the_class_it_names(old: str, new: str) -> None:
    module, _, qualname = new.partition(":")
    cls = getattr(importlib.import_module(module), qualname)
    assert decode_classes({"__class__": old}, {}) is cls
    assert old.rsplit(":", 1)[1] == qualname


def test_a_class_that_never_existed_is_still_refused() -> None:
    with pytest.raises(ModelFileError, match="not a Module class"):
        decode_classes({"__class__": "palaestra.algos.networks:NoSuchExtractor"}, {})


def test_new_files_name_classes_by_their_public_paths(tmp_path: Path) -> None:
    from palaestra.algos.dqn import DQNPolicy
    from palaestra.algos.networks import FlattenExtractor

    model = DQN(
        DQNPolicy,
        "CartPole-v1",
        buffer_size=100,
        policy_kwargs={"net_arch": [8], "features_extractor_class": FlattenExtractor},
    )
    model.save(tmp_path / "m.zip")
    with zipfile.ZipFile(tmp_path / "m.zip") as zf:
        text = "".join(zf.read(n).decode() for n in zf.namelist() if n.endswith(".json"))
    refs = {part.split('"')[0] for part in text.split('"__class__": "')[1:]}
    assert refs == {"palaestra.algos.dqn:DQNPolicy", "palaestra.algos.networks:FlattenExtractor"}


def test_public_ref_of_classes_outside_palaestra_is_where_they_are_defined() -> None:
    import torch

    assert public_paths.public_ref(torch.nn.ReLU) == "torch.nn.modules.activation:ReLU"
    assert public_paths.public_ref(TD3) == "palaestra.algos.td3:TD3"


def test_an_aliased_package_brings_its_submodules_as_the_same_objects() -> None:
    import palaestra.vec_env.normalize

    module = importlib.import_module("palaestra.algos.vec_env.normalize")
    assert module is palaestra.vec_env.normalize
    assert importlib.import_module("palaestra.algos.vec_env") is importlib.import_module(
        "palaestra.vec_env"
    )


def test_sb3_module_names_port_by_substitution() -> None:
    from palaestra.algos.base_class import BaseAlgorithm
    from palaestra.algos.env_util import make_vec_env
    from palaestra.algos.monitor import Monitor
    from palaestra.algos.noise import NormalActionNoise
    from palaestra.algos.off_policy_algorithm import OffPolicyAlgorithm
    from palaestra.algos.on_policy_algorithm import OnPolicyAlgorithm
    from palaestra.algos.running_mean_std import RunningMeanStd
    from palaestra.algos.torch_layers import NatureCNN
    from palaestra.algos.vec_env import DummyVecEnv
    from palaestra.vec_env import DummyVecEnv as Dummy
    from palaestra.vec_env import make_vec_env as make
    from palaestra.wrappers import Monitor as Mon

    assert issubclass(OffPolicyAlgorithm, BaseAlgorithm)
    assert issubclass(OnPolicyAlgorithm, BaseAlgorithm)
    assert (DummyVecEnv, make_vec_env, Monitor) == (Dummy, make, Mon)
    assert NormalActionNoise is palaestra.algos.NormalActionNoise
    assert RunningMeanStd.__module__ == "palaestra.wrappers.running_mean_std"
    # a class reachable by two aliases is recorded by the documented one
    assert public_paths.public_ref(NatureCNN) == "palaestra.algos.networks:NatureCNN"
