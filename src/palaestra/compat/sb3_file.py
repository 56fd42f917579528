"""What a Stable-Baselines3 ``.zip`` says, read as data: algorithm, spaces, settings, weights.

An SB3 model file holds ``data`` (JSON in which every value JSON cannot express is a base64
cloudpickle, next to its ``:type:`` and, for objects, their JSON-able attributes) and
``policy.pth`` (a ``torch.save`` state_dict). Only plain JSON is used here; the cloudpickled
strings are never decoded. ``policy.pth`` goes through :func:`read_torch_state_dict`. Every
member is read with a bounded read (``utils.bounded_zip``), and messages quote the file's
values in a bounded summary.
"""

from __future__ import annotations

import json
import re
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from palaestra import spaces
from palaestra.algos.common.model_io import PathLike, resolve_path
from palaestra.compat.torch_file import MAX_STATE_DICT_BYTES, read_torch_state_dict
from palaestra.utils.bounded_zip import (
    ModelFileError,
    check_members,
    read_member,
    short,
    summary,
)

__all__ = ["MISSING", "SB3File", "plain_value", "read_sb3_file", "sb3_type", "space_from_sb3"]

_MAX_DATA = 64 << 20
_TYPE = re.compile(r"^<class '([\w.]+)'>$")
_CONSTANT = re.compile(r"^ConstantSchedule\(val=([-+0-9.eE]+|inf)\)$")
MISSING = object()


@dataclass
class SB3File:
    """The plain parts of an SB3 model file."""

    name: str  # for messages
    algo: str  # "DQN", "PPO", "A2C", "SAC", ...
    version: str  # SB3 version that wrote it, "" if unknown
    data: dict[str, Any]
    state_dict: dict[str, np.ndarray]


def read_sb3_file(path: PathLike, *, max_bytes: int = MAX_STATE_DICT_BYTES) -> SB3File:
    """Open ``path`` (``"model"`` finds ``model.zip``, as SB3's ``load`` does) and read it;
    ``policy.pth`` may hold at most ``max_bytes`` (its zip and its tensors, each)."""
    source = resolve_path(path, for_write=False)
    name = str(source) if isinstance(source, Path) else "the given file object"
    if isinstance(source, Path) and not source.exists():
        raise FileNotFoundError(f"no SB3 model file at {str(path)!r} (nor {str(path)!r}.zip)")
    try:
        with zipfile.ZipFile(source) as zf:
            members = check_members(zf, name)
            if not {"data", "policy.pth"} <= set(members):
                kind = "a palaestra model file" if "palaestra.json" in members else "a zip archive"
                raise ModelFileError(
                    f"{name} is {kind}, not a Stable-Baselines3 model file (which holds 'data' "
                    "and 'policy.pth')"
                )
            data = _json(read_member(zf, members["data"], _MAX_DATA, name), name)
            version = ""
            if "_stable_baselines3_version" in members:
                raw = read_member(zf, members["_stable_baselines3_version"], 64, name)
                version = raw.decode("utf-8", "replace")
            algo = _algorithm(data, name)
            policy = read_member(zf, members["policy.pth"], max_bytes, name)
            state_dict = read_torch_state_dict(policy, max_bytes=max_bytes)
    except zipfile.BadZipFile as exc:
        raise ModelFileError(f"{name} is not a zip archive, so not an SB3 model file") from exc
    except (EOFError, OSError, zlib.error) as exc:
        raise ModelFileError(f"{name} is truncated or unreadable ({short(exc)})") from exc
    return SB3File(name, algo, version.strip(), data, state_dict)


def _json(raw: bytes, name: str) -> dict[str, Any]:
    try:
        data = json.loads(raw.decode("utf-8"))
    except (ValueError, RecursionError) as exc:  # bad UTF-8 or JSON, ints past 4300 digits
        raise ModelFileError(f"{name}: 'data' is not valid JSON ({short(exc)})") from exc
    if not isinstance(data, dict):
        raise ModelFileError(f"{name}: 'data' is not a JSON object")
    return data


def _algorithm(data: dict[str, Any], name: str) -> str:
    """Which SB3 algorithm wrote the file, from the policy class's module and the settings."""
    policy = data.get("policy_class")
    module = policy.get("__module__") if isinstance(policy, dict) else None
    if not isinstance(module, str):
        raise ModelFileError(f"{name}: 'data' does not say which policy class the model uses")
    parts = module.split(".")
    if parts[0] not in ("stable_baselines3", "sb3_contrib") or len(parts) < 2:
        raise ModelFileError(
            f"{name}: policy class from {short(repr(module))}, not from Stable-Baselines3"
        )
    if parts[1] != "common":  # stable_baselines3.dqn.policies, sb3_contrib.qrdqn.policies ...
        return parts[1].upper()
    # PPO and A2C share common.policies.ActorCriticPolicy; PPO alone clips and runs epochs.
    return "PPO" if "clip_range" in data and "n_epochs" in data else "A2C"


def plain_value(value: Any) -> Any:
    """A setting as plain JSON, or ``MISSING`` for a pickled one; a pickled constant schedule
    gives its constant (SB3 stores its repr, ``ConstantSchedule(val=0.2)``, beside it)."""
    if value is None or isinstance(value, (bool, int, float, str, list)):
        return value
    if isinstance(value, dict) and ":serialized:" not in value:
        return value
    if isinstance(value, dict):
        match = _CONSTANT.match(str(value.get("value_schedule", "")))
        if match:
            return float(match.group(1))
    return MISSING


def sb3_type(desc: Any) -> str:
    """``"Box"`` from ``{":type:": "<class 'gymnasium.spaces.box.Box'>", ...}``."""
    match = _TYPE.match(str(desc.get(":type:", ""))) if isinstance(desc, dict) else None
    return match.group(1).rsplit(".", 1)[-1] if match else "?"


def space_from_sb3(desc: Any, what: str, name: str) -> spaces.Space[Any]:
    """Rebuild a space from the JSON attributes SB3 writes beside its pickle.

    Box bounds are numpy's printed arrays (8 decimals); pass an ``env`` to ``from_sb3`` to use
    its exact spaces instead.
    """
    kind = sb3_type(desc)
    if kind not in ("Discrete", "MultiBinary", "MultiDiscrete", "Box"):
        raise ModelFileError(
            f"{name}: {what} space {kind} is not supported (an MlpPolicy model has a Box, "
            "Discrete, MultiDiscrete or MultiBinary one)"
        )
    try:
        if kind == "Discrete":
            return spaces.Discrete(int(desc["n"]), start=int(desc["start"]), dtype=desc["dtype"])
        if kind == "MultiBinary":
            return spaces.MultiBinary(desc["n"])
        dtype, shape = np.dtype(desc["dtype"]), tuple(int(d) for d in desc["_shape"])
        if kind == "MultiDiscrete":
            nvec, start = (_printed_array(desc[k], dtype, shape) for k in ("nvec", "start"))
            return spaces.MultiDiscrete(nvec, dtype, start=start)
        low, high = (_printed_array(desc[k], dtype, shape) for k in ("low", "high"))
        return spaces.Box(low, high, shape, dtype)
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(
            f"{name}: cannot rebuild the {what} space from {summary(_strip(desc))} "
            f"({short(exc)}); "
            "pass env=... to use the env's spaces"
        ) from exc


def _strip(desc: Any) -> Any:
    return (
        {k: v for k, v in desc.items() if k != ":serialized:"} if isinstance(desc, dict) else desc
    )


def _printed_array(text: Any, dtype: np.dtype, shape: tuple[int, ...]) -> np.ndarray:
    """Parse numpy's ``str()`` of an array: ``"[-4.8 -inf 0.41887903]"``, nested when 2-D."""
    text = str(text)
    if "..." in text:
        raise ValueError("the array was printed in summarised form")
    tokens = text.replace("[", " ").replace("]", " ").split()
    parse: Any = {"b": lambda t: t == "True", "i": int, "u": int}.get(dtype.kind, float)
    return np.array([parse(t) for t in tokens], dtype=dtype).reshape(shape)
