"""SB3's ``save_util`` (``stable_baselines3.common.save_util``): the helpers under SB3's model
files, for code that reads or writes SB3-layout archives itself.

The archives are SB3's layout, so SB3 and palaestra read each other's: ``data`` (JSON; a value
JSON cannot hold is a base64 cloudpickle beside its ``:type:`` and readable attributes),
``<name>.pth`` (``torch.save``'d state_dicts) and ``pytorch_variables.pth``. palaestra's own
model files are another format (``Algo.save``, no pickle at all); these helpers are for SB3's.

Writing is SB3's, except that every file is written atomically (``open_path(path, "w")``
returns a file that replaces ``path`` only when closed without an error). Reading differs where
SB3 would run code from the file, which palaestra does only when the caller says so:

- ``json_to_data`` raises ``UnsafeFileError`` for a pickled value unless ``custom_objects``
  gives it or ``allow_pickle=True`` (SB3 unpickles it);
- ``load_from_zip_file`` reads a ``.pth`` holding only tensors (a model's weights) without
  unpickling (``palaestra.compat.read_torch_state_dict``); any other ``.pth`` (an optimizer's
  state) needs ``allow_pickle=True``, which reads it with ``torch.load(weights_only=True)``;
- ``load_from_pkl`` raises ``UnsafeFileError`` unless ``allow_pickle=True``.

Members are read with bounded reads (``utils.bounded_zip``), as palaestra's model files are.
"""

from __future__ import annotations

import base64
import contextlib
import functools
import io
import json
import os
import pathlib
import pickle
import types
import warnings
import zipfile
from typing import Any

import cloudpickle
import torch

from palaestra import __version__
from palaestra.algos.common.utils import get_device, get_system_info
from palaestra.compat.torch_file import (
    MAX_STATE_DICT_BYTES,
    TorchFileError,
    UnsafeFileError,
    read_torch_state_dict,
)
from palaestra.utils.atomic_write import atomic_path
from palaestra.utils.bounded_zip import check_members, read_member

__all__ = [
    "UnsafeFileError",
    "data_to_json",
    "is_json_serializable",
    "json_to_data",
    "load_from_pkl",
    "load_from_zip_file",
    "open_path",
    "open_path_pathlib",
    "open_path_str",
    "recursive_getattr",
    "recursive_setattr",
    "save_to_pkl",
    "save_to_zip_file",
]

_MAX_DATA = 64 << 20  # the JSON ``data`` member (an SB3 model's: a few kB)
_MAX_TEXT = 1 << 20  # system_info.txt and the version member
TensorDict = dict[str, torch.Tensor]
PathOrFile = str | pathlib.Path | io.BufferedIOBase


def recursive_getattr(obj: Any, attr: str, *args: Any) -> Any:
    """``getattr`` along a dotted path: ``recursive_getattr(model, "policy.optimizer")``; a
    default in ``args`` is returned for a missing attribute at any step, as ``getattr``'s."""
    for name in attr.split("."):
        obj = getattr(obj, name, *args)
    return obj


def recursive_setattr(obj: Any, attr: str, val: Any) -> None:
    """``setattr`` at the end of a dotted path: ``recursive_setattr(model, "policy.x", 1)``."""
    owner, _, name = attr.rpartition(".")
    setattr(recursive_getattr(obj, owner) if owner else obj, name, val)


def is_json_serializable(item: Any) -> bool:
    """Whether ``json.dumps(item)`` succeeds."""
    try:
        json.dumps(item)
    except (TypeError, ValueError):  # ValueError: a circular structure (SB3 lets it out)
        return False
    return True


def data_to_json(data: dict[str, Any]) -> str:
    """``data`` as SB3's JSON: JSON values as they are; any other value as
    ``{":type:": str(type), ":serialized:": base64 cloudpickle}`` plus its own JSON-able
    attributes (others as their ``str``), for people and other languages to read."""
    serializable: dict[str, Any] = {}
    for key, item in data.items():
        if is_json_serializable(item):
            serializable[key] = item
            continue
        entry: dict[str, Any] = {
            ":type:": str(type(item)),
            ":serialized:": base64.b64encode(cloudpickle.dumps(item)).decode(),
        }
        attributes = item if isinstance(item, dict) else getattr(item, "__dict__", {})
        for name, value in attributes.items():
            entry[name] = value if is_json_serializable(value) else str(value)
        serializable[key] = entry
    return json.dumps(serializable, indent=4)


def json_to_data(
    json_string: str | bytes,
    custom_objects: dict[str, Any] | None = None,
    *,
    allow_pickle: bool = False,
) -> dict[str, Any]:
    """Inverse of ``data_to_json``. A key in ``custom_objects`` takes that object instead of
    the stored value; a pickled value needs ``allow_pickle=True`` (unpickling runs code the
    JSON names), else ``UnsafeFileError`` names the key. Unpickling errors warn and leave the
    key out, as in SB3."""
    if custom_objects is not None and not isinstance(custom_objects, dict):
        raise ValueError(
            f"custom_objects argument must be a dict or None, got {type(custom_objects).__name__}"
        )
    custom = custom_objects or {}
    loaded = json.loads(json_string)
    if not isinstance(loaded, dict):
        raise ValueError(f"expected a JSON object of class parameters, got {type(loaded).__name__}")
    data: dict[str, Any] = {}
    for key, item in loaded.items():
        if key in custom:
            data[key] = custom[key]
        elif isinstance(item, dict) and ":serialized:" in item:
            if not allow_pickle:
                raise UnsafeFileError(
                    f"{key!r} is a pickled {item.get(':type:', 'object')}: loading it would run "
                    f"code the data names; pass custom_objects={{{key!r}: ...}} instead, or "
                    "allow_pickle=True if you trust where it came from"
                )
            try:
                data[key] = cloudpickle.loads(base64.b64decode(str(item[":serialized:"])))
            except (RuntimeError, TypeError, AttributeError, ValueError) as exc:
                warnings.warn(
                    f"Could not deserialize object {key}. Consider using `custom_objects` "
                    f"argument to replace this object.\nException: {exc}",
                    stacklevel=2,
                )
        else:
            data[key] = item
    return data


# -- opening files ------------------------------------------------------------------------------
_MODES = {"w": "w", "write": "w", "r": "r", "read": "r"}
_FILE_TYPES = (io.BufferedWriter, io.BufferedReader, io.BytesIO, io.BufferedRandom)


class _AtomicFile(io.BufferedWriter):
    """A binary file written under a temporary name beside ``target`` and renamed over it
    (``utils.atomic_write.atomic_path``) on ``close()``; an exception inside ``with`` or a file
    dropped unclosed leaves ``target`` as it was."""

    def __init__(self, target: pathlib.Path) -> None:
        self._commit = atomic_path(target)
        super().__init__(io.FileIO(self._commit.__enter__(), "wb"))
        self.target = target

    def close(self) -> None:
        if not self.closed:
            super().close()
            self._commit.__exit__(None, None, None)

    def _abort(self) -> None:
        if "_commit" in vars(self) and not self.closed:  # (an __init__ that failed: nothing)
            super().close()
            with contextlib.suppress(RuntimeError):
                self._commit.__exit__(RuntimeError, RuntimeError("aborted"), None)

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: types.TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.close()
        else:
            self._abort()

    def __del__(self) -> None:
        self._abort()


@functools.singledispatch
def open_path(
    path: Any, mode: str, verbose: int = 0, suffix: str | None = None
) -> io.BufferedIOBase:
    """An open binary file for ``path``: a file object is checked (open, and readable for
    ``"r"``/``"read"`` or writable for ``"w"``/``"write"``) and returned; a ``str`` or
    ``Path`` is opened (``open_path_pathlib``)."""
    if not isinstance(path, _FILE_TYPES):
        raise TypeError(f"Path {path} parameter has invalid type: expected one of {_FILE_TYPES}.")
    if path.closed:
        raise ValueError(f"File stream {path} is closed.")
    if mode.lower() not in _MODES:
        raise ValueError(f"Expected mode to be either 'w' or 'r', got {mode!r}.")
    mode = _MODES[mode.lower()]
    if (mode == "w" and not path.writable()) or (mode == "r" and not path.readable()):
        raise ValueError(f"Expected a {'writable' if mode == 'w' else 'readable'} file.")
    return path


@open_path.register(str)
def open_path_str(
    path: str, mode: str, verbose: int = 0, suffix: str | None = None
) -> io.BufferedIOBase:
    """``open_path`` for a path given as a string (see ``open_path_pathlib``)."""
    return open_path_pathlib(pathlib.Path(path), mode, verbose, suffix)


@open_path.register(pathlib.Path)
def open_path_pathlib(
    path: pathlib.Path, mode: str, verbose: int = 0, suffix: str | None = None
) -> io.BufferedIOBase:
    """Open ``path`` with SB3's conveniences. ``"r"``: a missing ``path`` is tried as
    ``path.suffix`` (``model`` -> ``model.zip``). ``"w"``: a path without a suffix gets
    ``suffix``, missing folders are created (with a warning), a path that is a folder becomes
    ``<path>_2`` (with a warning); the file is written atomically."""
    if mode not in ("w", "r"):
        raise ValueError(f"Expected mode to be either 'w' or 'r', got {mode!r}.")
    if mode == "r":
        if not path.exists() and suffix:
            fallback = pathlib.Path(f"{path}.{suffix}")
            if verbose >= 2:
                warnings.warn(f"Path '{path}' not found. Attempting {fallback}.", stacklevel=2)
            path = fallback
        return open_path(path.open("rb"), mode, verbose, suffix)
    if path.suffix == "" and suffix:
        path = pathlib.Path(f"{path}.{suffix}")
    if path.is_dir():
        warnings.warn(f"Path '{path}' is a folder. Will save instead to {path}_2", stacklevel=2)
        return open_path_pathlib(pathlib.Path(f"{path}_2"), mode, verbose, suffix)
    if path.is_file() and verbose >= 2:
        warnings.warn(f"Path '{path}' exists, will overwrite it.", stacklevel=2)
    if not path.parent.exists():
        warnings.warn(f"Path '{path.parent}' does not exist. Will create it.", stacklevel=2)
        path.parent.mkdir(parents=True, exist_ok=True)
    return _AtomicFile(path)


# -- zip archives -------------------------------------------------------------------------------
def save_to_zip_file(
    save_path: PathOrFile,
    data: dict[str, Any] | None = None,
    params: dict[str, Any] | None = None,
    pytorch_variables: dict[str, Any] | None = None,
    verbose: int = 0,
) -> None:
    """Write an SB3-layout model archive: ``data`` as ``data_to_json``, each of ``params``
    (name -> state_dict) as ``<name>.pth`` and ``pytorch_variables`` as
    ``pytorch_variables.pth`` (``torch.save``), plus the palaestra version and system info.
    A path gets ``.zip`` when it has no suffix and is written atomically."""
    serialized = data_to_json(data) if data is not None else None
    file = open_path(save_path, "w", verbose=0, suffix="zip")
    try:
        with zipfile.ZipFile(file, mode="w") as archive:
            if serialized is not None:
                archive.writestr("data", serialized)
            if pytorch_variables is not None:
                with archive.open("pytorch_variables.pth", "w", force_zip64=True) as member:
                    torch.save(pytorch_variables, member)
            for name, state in (params or {}).items():
                with archive.open(f"{name}.pth", "w", force_zip64=True) as member:
                    torch.save(state, member)
            archive.writestr("_palaestra_version", __version__)
            archive.writestr("system_info.txt", get_system_info(print_info=False)[1])
    except BaseException:
        if isinstance(file, _AtomicFile):
            file._abort()
        raise
    if isinstance(save_path, (str, pathlib.Path)):
        file.close()


def load_from_zip_file(
    load_path: PathOrFile,
    load_data: bool = True,
    custom_objects: dict[str, Any] | None = None,
    device: torch.device | str = "auto",
    verbose: int = 0,
    print_system_info: bool = False,
    *,
    allow_pickle: bool = False,
) -> tuple[dict[str, Any] | None, dict[str, Any], Any]:
    """Read an SB3-layout archive: ``(data, params, pytorch_variables)`` as SB3's, tensors on
    ``device``. ``data`` is None without a ``data`` member or with ``load_data=False``;
    pickled values in it need ``custom_objects`` or ``allow_pickle`` (see ``json_to_data``).
    A ``.pth`` of tensors only is read without unpickling; another (an optimizer's state)
    needs ``allow_pickle=True``, else ``UnsafeFileError`` names it."""
    file = open_path(load_path, "r", verbose=verbose, suffix="zip")
    name = str(load_path) if isinstance(load_path, (str, pathlib.Path)) else "the given file"
    target = get_device(device)
    data, params, variables = None, {}, None
    try:
        with zipfile.ZipFile(file) as archive:
            members = check_members(archive, name)
            if "palaestra.json" in members:
                raise ValueError(
                    f"{name} is a palaestra model file, not an SB3-layout archive: load it "
                    "with the algorithm's load() (e.g. PPO.load)"
                )
            if print_system_info:
                _print_system_info(archive, members, name)
            if load_data and "data" in members:
                raw = read_member(archive, members["data"], _MAX_DATA, name)
                data = json_to_data(raw, custom_objects, allow_pickle=allow_pickle)
            for member in members:
                stem, extension = os.path.splitext(member)
                if extension != ".pth":
                    continue
                raw = read_member(archive, members[member], MAX_STATE_DICT_BYTES, name)
                value = _read_pth(raw, f"{member} in {name}", target, allow_pickle)
                # SB3 < 0.9 named the variables "tensors.pth"
                if member in ("pytorch_variables.pth", "tensors.pth"):
                    variables = value
                else:
                    params[stem] = value
    except zipfile.BadZipFile as exc:
        raise ValueError(f"Error: the file {load_path} wasn't a zip-file") from exc
    finally:
        if isinstance(load_path, (str, pathlib.Path)):
            file.close()
    return data, params, variables


def _print_system_info(
    archive: zipfile.ZipFile, members: dict[str, zipfile.ZipInfo], name: str
) -> None:
    if "system_info.txt" not in members:
        warnings.warn(
            "The model was saved with SB3 <= 1.2.0 and thus cannot print system information.",
            UserWarning,
            stacklevel=3,
        )
        return
    print("== SAVED MODEL SYSTEM INFO ==")
    print(read_member(archive, members["system_info.txt"], _MAX_TEXT, name).decode("utf-8"))


def _read_pth(raw: bytes, where: str, device: torch.device, allow_pickle: bool) -> Any:
    """A ``torch.save``'d object: a tensor dict read as data; anything else by
    ``torch.load(weights_only=True)`` when ``allow_pickle``."""
    try:
        arrays = read_torch_state_dict(raw)
    except TorchFileError as exc:
        if not allow_pickle:
            raise UnsafeFileError(
                f"{where} is not a plain tensor state_dict ({exc}); pass allow_pickle=True to "
                "read it with torch.load(weights_only=True) if you trust the file"
            ) from exc
        return torch.load(io.BytesIO(raw), map_location=device, weights_only=True)
    return {key: torch.from_numpy(array).to(device) for key, array in arrays.items()}


# -- pickles ------------------------------------------------------------------------------------
def save_to_pkl(path: PathOrFile, obj: Any, verbose: int = 0) -> None:
    """Pickle ``obj`` (highest protocol, as SB3) to ``path`` (``.pkl`` added when it has no
    suffix; written atomically). Reading it back needs ``load_from_pkl(allow_pickle=True)``."""
    file = open_path(path, "w", verbose=verbose, suffix="pkl")
    try:
        pickle.dump(obj, file, protocol=pickle.HIGHEST_PROTOCOL)
    except BaseException:
        if isinstance(file, _AtomicFile):
            file._abort()
        raise
    if isinstance(path, (str, pathlib.Path)):
        file.close()


def load_from_pkl(path: PathOrFile, verbose: int = 0, *, allow_pickle: bool = False) -> Any:
    """Unpickle the object at ``path`` (``path.pkl`` when ``path`` is missing). Unpickling runs
    whatever code the file names, so it needs ``allow_pickle=True``: without it nothing is read
    and ``UnsafeFileError`` says so. palaestra's own files (``save_replay_buffer``, VecNormalize's
    ``save``) need no pickle."""
    if not allow_pickle:
        raise UnsafeFileError(
            f"load_from_pkl({path!r}) would unpickle the file, which runs any code it names; "
            "pass allow_pickle=True if you trust the file"
        )
    file = open_path(path, "r", verbose=verbose, suffix="pkl")
    try:
        return pickle.load(file)  # the caller allowed it
    finally:
        if isinstance(path, (str, pathlib.Path)):
            file.close()
