"""Gymnasium's ``ArrayConversion`` and ``NumpyToTorch``: an env stepped with torch tensors
(or another array module's arrays) and answering in them, actions converted back to what the
env takes.

``array_conversion(value, xp, device)`` converts numbers, arrays, mappings, tuples, lists and
named tuples (nested), passing ``None`` and strings through. numpy <-> torch on the CPU shares
memory, as Gymnasium's DLPack route does; other modules go through their ``asarray``.
Gymnasium needs ``array_api_compat`` for this; palaestra converts between numpy and torch
(the modules it depends on) itself, and any other module with ``asarray`` by it.

Importing this module imports torch only when a conversion involves it.
"""

from __future__ import annotations

import importlib
import numbers
from collections.abc import Mapping
from types import ModuleType
from typing import Any

import numpy as np

from palaestra.core import Env, Wrapper
from palaestra.utils.record_constructor import RecordConstructorArgs

__all__ = [
    "ArrayConversion",
    "NumpyToTorch",
    "array_conversion",
    "module_name_to_namespace",
    "module_namespace",
    "numpy_to_torch",
    "torch_to_numpy",
]

Device = Any  # a torch device or its name ("cpu", "cuda:0"); Gymnasium's alias


def _is_torch_tensor(value: Any) -> bool:
    return type(value).__module__.startswith("torch") and hasattr(value, "detach")


def _convert_array(value: Any, xp: ModuleType, device: Any) -> Any:
    if xp is np:
        if _is_torch_tensor(value):
            return value.detach().cpu().numpy()  # shares memory on the CPU
        return np.asarray(value)
    if xp.__name__ == "torch":
        return xp.asarray(value, device=device)  # a numpy array's memory on the CPU
    converted = xp.asarray(np.asarray(value) if _is_torch_tensor(value) else value)
    return converted if device is None else xp.asarray(converted, device=device)


def array_conversion(value: Any, xp: ModuleType, device: Any = None) -> Any:
    """``value`` with every number and array as an array of module ``xp`` (on ``device``),
    containers rebuilt with the same type."""
    if value is None or isinstance(value, (str, bytes)):
        return value
    if isinstance(value, (np.ndarray, np.generic, numbers.Number)) or _is_torch_tensor(value):
        return _convert_array(value, xp, device)
    if isinstance(value, Mapping):
        return type(value)(**{k: array_conversion(v, xp, device) for k, v in value.items()})
    if isinstance(value, tuple) and hasattr(value, "_make"):  # a named tuple
        return type(value)._make(array_conversion(v, xp, device) for v in value)
    if isinstance(value, (tuple, list)):
        return type(value)(array_conversion(v, xp, device) for v in value)
    if hasattr(value, "__array__") or hasattr(value, "__dlpack__"):
        return _convert_array(value, xp, device)
    raise TypeError(f"No known conversion for ({type(value)}) to xp module ({xp.__name__})")


def module_namespace(xp: ModuleType) -> ModuleType:
    """The array namespace of module ``xp``, for :func:`array_conversion` (Gymnasium's helper).

    Gymnasium returns ``array_api_compat``'s wrapper of the module; palaestra converts with the
    module itself, so it is returned as is once it proves to be an array module (it has
    ``asarray`` and ``empty``), else ``ValueError`` as in Gymnasium.
    """
    if not isinstance(xp, ModuleType) or not (hasattr(xp, "asarray") and hasattr(xp, "empty")):
        raise ValueError(f"Module {xp!r} is not an Array API compatible module.")
    return xp


def module_name_to_namespace(name: str) -> ModuleType:
    """:func:`module_namespace` of the module named ``name`` (``"numpy"``, ``"torch"``)."""
    if not isinstance(name, str):
        raise TypeError(f"name must be a module name such as 'numpy', got {name!r}")
    return module_namespace(importlib.import_module(name))


def _module(xp: Any, what: str) -> ModuleType:
    if not isinstance(xp, ModuleType) or not hasattr(xp, "asarray"):
        raise ValueError(f"{what} must be an array module such as numpy or torch, got {xp!r}")
    return xp


def numpy_to_torch(value: Any, device: Any = None) -> Any:
    """Gymnasium's ``numpy_to_torch``: ``array_conversion`` to torch."""
    import torch

    return array_conversion(value, torch, device)


def torch_to_numpy(value: Any, device: Any = None) -> Any:
    """Gymnasium's ``torch_to_numpy``: ``array_conversion`` to numpy."""
    return array_conversion(value, np)


class ConvertsArrays(RecordConstructorArgs):
    """What the single and vector ``ArrayConversion`` share: the two array modules (and
    devices), checked and recorded, and the conversions each way."""

    def _init_conversion(
        self, env_xp: ModuleType, target_xp: ModuleType, env_device: Any, target_device: Any
    ) -> None:
        RecordConstructorArgs.__init__(
            self,
            _disable_deepcopy=True,  # modules cannot be deep-copied
            env_xp=env_xp,
            target_xp=target_xp,
            env_device=env_device,
            target_device=target_device,
        )
        self._env_xp = _module(env_xp, "env_xp")
        self._target_xp = _module(target_xp, "target_xp")
        self._env_device, self._target_device = env_device, target_device

    def _in(self, value: Any) -> Any:
        return array_conversion(value, self._env_xp, self._env_device)

    def _out(self, value: Any) -> Any:
        return array_conversion(value, self._target_xp, self._target_device)


class ArrayConversion(Wrapper[Any, Any, Any, Any], ConvertsArrays):
    """Actions in ``target_xp`` arrays are converted to ``env_xp`` for the env; observations,
    infos and frames come back as ``target_xp`` arrays; the reward as a float and the flags
    as bools (Gymnasium's single-env wrapper)."""

    def __init__(
        self,
        env: Env[Any, Any],
        env_xp: ModuleType,
        target_xp: ModuleType,
        env_device: Any = None,
        target_device: Any = None,
    ) -> None:
        Wrapper.__init__(self, env)
        self._init_conversion(env_xp, target_xp, env_device, target_device)

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(self._in(action))
        return self._out(obs), float(reward), bool(terminated), bool(truncated), self._out(info)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        if options:
            options = self._in(options)
        obs, info = self.env.reset(seed=seed, options=options)
        return self._out(obs), self._out(info)

    def render(self) -> Any:
        return self._out(self.env.render())


class NumpyToTorch(ArrayConversion):
    """A numpy env driven with torch tensors: observations and infos as tensors on
    ``device``, tensor actions back to numpy."""

    def __init__(self, env: Env[Any, Any], device: Any = None) -> None:
        import torch

        RecordConstructorArgs.__init__(self, device=device)  # its own arguments, recorded first
        super().__init__(env, env_xp=np, target_xp=torch, target_device=device)
        self.device = device
