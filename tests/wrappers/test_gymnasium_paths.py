"""Gymnasium's wrapper paths and names under ``palaestra.wrappers`` (issue 26): ``"vector"`` in
``__all__``, ``numpy_to_torch`` and ``array_conversion``'s namespace helpers, HumanRendering's
recorded ``backend``, and the vector ``TransformAction``'s warning, side by side."""

from __future__ import annotations

import importlib
import subprocess
import sys
import warnings

import numpy as np
import pytest

import palaestra
import palaestra.wrappers
from palaestra import spaces
from palaestra.wrappers import HumanRendering
from palaestra.wrappers import vector as vector_wrappers

gymnasium = pytest.importorskip("gymnasium")
gym_wrappers = pytest.importorskip("gymnasium.wrappers")

# Gymnasium's jax wrappers: palaestra has no jax dependency (docs/differences.md, known gaps)
JAX_ONLY = {"JaxToNumpy", "JaxToTorch"}


def test_every_gymnasium_wrapper_name_and_vector_are_exported() -> None:
    assert "vector" in palaestra.wrappers.__all__
    assert set(gym_wrappers.__all__) - JAX_ONLY <= set(palaestra.wrappers.__all__)
    for name in set(gym_wrappers.__all__) - JAX_ONLY:
        assert getattr(palaestra.wrappers, name) is not None, name
    assert palaestra.wrappers.vector is vector_wrappers


def test_star_import_gives_the_vector_module() -> None:
    code = "from palaestra.wrappers import *\nprint(vector.__name__, AddWhiteNoise.__name__)\n"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["palaestra.wrappers.vector", "AddWhiteNoise"]


def test_numpy_to_torch_module_path() -> None:
    module = importlib.import_module("palaestra.wrappers.numpy_to_torch")
    assert set(module.__all__) == {"Device", "NumpyToTorch", "numpy_to_torch", "torch_to_numpy"}
    assert module.NumpyToTorch is palaestra.wrappers.NumpyToTorch
    vector_module = importlib.import_module("palaestra.wrappers.vector.numpy_to_torch")
    assert vector_module.NumpyToTorch is vector_wrappers.NumpyToTorch
    torch = pytest.importorskip("torch")
    tensor = module.numpy_to_torch({"a": np.arange(3, dtype=np.float32)})["a"]
    assert isinstance(tensor, torch.Tensor) and tensor.dtype == torch.float32
    back = module.torch_to_numpy(tensor)
    assert isinstance(back, np.ndarray) and back.dtype == np.float32


def test_importing_numpy_to_torch_does_not_import_torch() -> None:
    code = "import sys, palaestra.wrappers.numpy_to_torch\nprint('torch' in sys.modules)\n"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_array_conversion_namespace_helpers() -> None:
    from palaestra.wrappers.array_conversion import (
        array_conversion,
        module_name_to_namespace,
        module_namespace,
    )

    assert module_namespace(np) is np
    assert module_name_to_namespace("numpy") is np
    converted = array_conversion([1.5, (2, 3)], xp=module_namespace(np))
    assert isinstance(converted, list) and isinstance(converted[1], tuple)
    assert converted[0].dtype == np.float64
    with pytest.raises(ValueError, match=r"Module 'numpy' is not an Array API compatible"):
        module_namespace("numpy")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="is not an Array API compatible module"):
        module_namespace(warnings)  # a module without asarray
    with pytest.raises(ModuleNotFoundError):
        module_name_to_namespace("no_such_array_module")
    with pytest.raises(TypeError, match="must be a module name"):
        module_name_to_namespace(np)  # type: ignore[arg-type]


def test_human_rendering_records_its_backend_for_the_spec() -> None:
    env = HumanRendering(palaestra.make("CartPole-v1", render_mode="rgb_array"), backend="x")
    assert env._saved_kwargs == {"backend": "x"}
    wrapper_spec = env.spec.additional_wrappers[-1]
    assert wrapper_spec.name == "HumanRendering" and wrapper_spec.kwargs == {"backend": "x"}
    rebuilt = palaestra.make(env.spec)
    assert isinstance(rebuilt, HumanRendering) and rebuilt._backend == "x"
    assert HumanRendering(palaestra.make("CartPole-v1", render_mode="rgb_array"))._saved_kwargs == {
        "backend": None
    }
    envs = palaestra.make_vec("CartPole-v1", 2, vectorization_mode="sync", render_mode="rgb_array")
    assert vector_wrappers.HumanRendering(envs, backend="y")._saved_kwargs["backend"] == "y"


def _messages(caught: list[warnings.WarningMessage]) -> list[str]:
    return [str(w.message) for w in caught]


@pytest.mark.parametrize("given", ["action_space", "single_action_space", "both_agree", "none"])
def test_vector_transform_action_warns_when_spaces_disagree(given: str) -> None:
    def spaces_for(lib: object) -> dict[str, object]:
        box = lib.spaces.Box(-1, 1, (2,))  # type: ignore[attr-defined]
        batched = lib.spaces.Box(-1, 1, (3, 2))  # type: ignore[attr-defined]
        return {
            "action_space": {"action_space": box},  # not a batch of the single space
            "single_action_space": {"single_action_space": box},  # batched from it: agrees
            "both_agree": {"action_space": batched, "single_action_space": box},
            "none": {},
        }[given]

    ours_env = palaestra.make_vec("Pendulum-v1", 3, vectorization_mode="sync")
    theirs_env = gymnasium.make_vec("Pendulum-v1", 3, vectorization_mode="sync")
    with warnings.catch_warnings(record=True) as ours:
        warnings.simplefilter("always")
        vector_wrappers.TransformAction(ours_env, lambda a: a, **spaces_for(palaestra))
    with warnings.catch_warnings(record=True) as theirs:
        warnings.simplefilter("always")
        gymnasium.wrappers.vector.TransformAction(theirs_env, lambda a: a, **spaces_for(gymnasium))
    assert len(_messages(ours)) == len(_messages(theirs)) == (1 if given == "action_space" else 0)
    if given == "action_space":
        assert (
            "the action space and the batched single action space don't match"
            in (_messages(ours)[0])
        )
        assert "batched single_action_space=Box(-2.0, 2.0, (3, 1), float32)" in _messages(ours)[0]


def test_transform_observation_still_warns() -> None:
    envs = palaestra.make_vec("Pendulum-v1", 2, vectorization_mode="sync")
    with pytest.warns(UserWarning, match="observation space and the batched single observation"):
        vector_wrappers.TransformObservation(
            envs, lambda o: o, observation_space=spaces.Box(-1, 1, (5,))
        )


def test_numpy_to_torch_converts_as_gymnasiums() -> None:
    """Side by side with Gymnasium's functions (they need array_api_compat, a dev dependency)."""
    torch = pytest.importorskip("torch")
    theirs = pytest.importorskip("gymnasium.wrappers.numpy_to_torch", exc_type=ImportError)
    from palaestra.wrappers import numpy_to_torch as ours

    value = {
        "a": np.arange(6, dtype=np.float32).reshape(2, 3),
        "b": (np.int64(3), [np.array([True, False])]),
        "c": 2.5,
        "d": None,
    }
    got, want = ours.numpy_to_torch(value), theirs.numpy_to_torch(value)
    assert type(got) is type(want) and type(got["b"]) is type(want["b"])
    for g, w in [(got["a"], want["a"]), (got["b"][0], want["b"][0]), (got["c"], want["c"])]:
        assert isinstance(g, torch.Tensor) and g.dtype == w.dtype and g.shape == w.shape
        assert torch.equal(g, w)
    assert torch.equal(got["b"][1][0], want["b"][1][0]) and got["d"] is want["d"] is None
    back, their_back = ours.torch_to_numpy(got), theirs.torch_to_numpy(want)
    np.testing.assert_array_equal(back["a"], their_back["a"])
    assert back["a"].dtype == their_back["a"].dtype == np.float32


def test_array_conversion_of_an_unknown_type_is_a_type_error_not_a_bare_exception() -> None:
    theirs = pytest.importorskip("gymnasium.wrappers.array_conversion", exc_type=ImportError)
    from palaestra.wrappers.array_conversion import array_conversion, module_namespace

    with pytest.raises(Exception, match="No known conversion") as caught:
        theirs.array_conversion(object(), xp=theirs.module_namespace(np))
    assert type(caught.value) is Exception
    with pytest.raises(TypeError, match="No known conversion"):
        array_conversion(object(), xp=module_namespace(np))
