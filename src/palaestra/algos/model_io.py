"""Model and replay-buffer files: a zip of one JSON manifest and ``.npy`` arrays. No pickle.

SB3 pickles its hyperparameters and ``torch.save``s its tensors, so loading a file can run
arbitrary code. Here the manifest is plain JSON, arrays are read with ``allow_pickle=False``,
classes named in the manifest (``activation_fn`` …) resolve only inside ``torch.nn``,
``torch.optim`` and ``palaestra.algos`` (anything else must come through ``custom_objects``), and
every array's dtype, shape and size is checked before it is read. Bad files raise
``ModelFileError`` saying what is wrong.

Layout::

    palaestra.json         {"format": "palaestra", "kind": "model", "version": 1,
                            "meta": {...}, "arrays": {name: {"file", "dtype", "shape"}}}
    arrays/00000.npy ...   one array each
"""

from __future__ import annotations

import importlib
import io
import json
import os
import zipfile
from pathlib import Path
from typing import IO, Any

import numpy as np
import torch
from torch import nn

from palaestra import error

__all__ = [
    "ModelFileError",
    "decode_classes",
    "encode_classes",
    "optimizer_from_arrays",
    "optimizer_to_arrays",
    "read_archive",
    "resolve_path",
    "write_archive",
]

FORMAT, VERSION, MANIFEST = "palaestra", 1, "palaestra.json"
_MAX_MANIFEST = 64 << 20
_DTYPES = {"<f4", "<f8", "<f2", "|u1", "|i1", "<i2", "<u2", "<i4", "<u4", "<i8", "<u8", "|b1"}

PathLike = str | os.PathLike[str] | IO[bytes]


class ModelFileError(error.Error, ValueError):
    """A model or replay-buffer file is corrupt, truncated, foreign or unsafe."""


def resolve_path(path: PathLike, for_write: bool) -> PathLike:
    """SB3's naming: ``save("model")`` writes ``model.zip``; ``load("model")`` finds it."""
    if not isinstance(path, (str, os.PathLike)):
        return path
    p = Path(path)
    if for_write:
        return p.with_name(p.name + ".zip") if p.suffix == "" else p
    if not p.exists() and Path(str(p) + ".zip").exists():
        return Path(str(p) + ".zip")
    return p


def write_archive(
    path: PathLike, kind: str, meta: dict[str, Any], arrays: dict[str, np.ndarray]
) -> None:
    """Write ``meta`` (JSON-able) and named numeric arrays as one archive."""
    entries: dict[str, dict[str, Any]] = {}
    target = resolve_path(path, for_write=True)
    if isinstance(target, Path):
        target.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(target, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for i, (name, array) in enumerate(arrays.items()):
            array = np.ascontiguousarray(array)
            if array.dtype.str not in _DTYPES:
                raise TypeError(f"cannot store array {name!r} of dtype {array.dtype}")
            buf = io.BytesIO()
            np.save(buf, array, allow_pickle=False)
            file = f"arrays/{i:05d}.npy"
            zf.writestr(file, buf.getvalue())
            entries[name] = {"file": file, "dtype": array.dtype.str, "shape": list(array.shape)}
        manifest = {
            "format": FORMAT,
            "kind": kind,
            "version": VERSION,
            "meta": meta,
            "arrays": entries,
        }
        zf.writestr(MANIFEST, json.dumps(manifest))


def read_archive(path: PathLike, kind: str) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Read and validate an archive written by ``write_archive``; ``ModelFileError`` if not."""
    source = resolve_path(path, for_write=False)
    name = str(source) if isinstance(source, Path) else "the given file object"
    if isinstance(source, Path) and not source.exists():
        raise FileNotFoundError(f"no model file at {str(path)!r} (nor {str(path)!r}.zip)")
    try:
        with zipfile.ZipFile(source) as zf:
            return _read(zf, kind, name)
    except zipfile.BadZipFile as exc:
        raise ModelFileError(f"{name} is corrupt or not a palaestra {kind} file ({exc})") from exc
    except (EOFError, OSError, zipfile.LargeZipFile) as exc:
        raise ModelFileError(f"{name} is truncated or unreadable ({exc})") from exc


def _read(
    zf: zipfile.ZipFile, kind: str, name: str
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    names = set(zf.namelist())
    if MANIFEST not in names:
        if {"data", "policy.pth"} <= names:
            raise ModelFileError(
                f"{name} is a Stable-Baselines3 model file, which Algo.load does not unpickle "
                "(that can run code); palaestra.compat.from_sb3(path) reads the weights of an "
                "SB3 DQN/PPO MlpPolicy file without unpickling anything."
            )
        raise ModelFileError(
            f"{name} is a zip archive but not a palaestra {kind} file (no {MANIFEST})"
        )
    info = zf.getinfo(MANIFEST)
    if info.file_size > _MAX_MANIFEST:
        raise ModelFileError(f"{name}: manifest is implausibly large ({info.file_size} bytes)")
    try:
        manifest = json.loads(zf.read(MANIFEST).decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ModelFileError(f"{name}: manifest is not valid JSON ({exc})") from exc
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise ModelFileError(
            f"{name} is not a palaestra file (format {manifest.get('format')!r})"
            if isinstance(manifest, dict)
            else f"{name}: malformed manifest"
        )
    if manifest.get("kind") != kind:
        raise ModelFileError(
            f"{name} is a palaestra {manifest.get('kind')!r} file, not a {kind} file"
        )
    if not isinstance(manifest.get("version"), int) or manifest["version"] > VERSION:
        raise ModelFileError(
            f"{name} has format version {manifest.get('version')!r}; this "
            f"palaestra reads versions up to {VERSION}, upgrade palaestra"
        )
    meta, entries = manifest.get("meta"), manifest.get("arrays")
    if not isinstance(meta, dict) or not isinstance(entries, dict):
        raise ModelFileError(f"{name}: manifest lacks 'meta' or 'arrays'")
    arrays = {key: _read_array(zf, key, entry, name, names) for key, entry in entries.items()}
    return meta, arrays


def _read_array(
    zf: zipfile.ZipFile, key: str, entry: Any, name: str, names: set[str]
) -> np.ndarray:
    try:
        file, dtype, shape = (
            entry["file"],
            np.dtype(entry["dtype"]),
            tuple(int(d) for d in entry["shape"]),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(f"{name}: malformed entry for array {key!r}") from exc
    if file not in names or dtype.str not in _DTYPES or any(d < 0 for d in shape):
        raise ModelFileError(f"{name}: array {key!r} is missing or has an unsupported dtype/shape")
    expected = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if zf.getinfo(file).file_size > expected + 4096:  # .npy header is at most a few hundred bytes
        raise ModelFileError(f"{name}: array {key!r} is larger than its declared shape")
    try:
        array = np.load(io.BytesIO(zf.read(file)), allow_pickle=False)
    except ValueError as exc:  # object arrays (pickles) land here, as do damaged headers
        raise ModelFileError(f"{name}: array {key!r} is not a plain numeric array ({exc})") from exc
    if not isinstance(array, np.ndarray) or array.dtype != dtype or array.shape != shape:
        raise ModelFileError(f"{name}: array {key!r} does not match its declared dtype/shape")
    return array


# -- classes in policy_kwargs -----------------------------------------------------------------
_ALLOWED = {
    "torch.nn": nn.Module,
    "torch.optim": torch.optim.Optimizer,
    "palaestra.algos": nn.Module,
}


def encode_classes(value: Any) -> Any:
    """Replace classes in (nested) kwargs by ``{"__class__": "module:qualname"}``."""
    if isinstance(value, type):
        return {"__class__": f"{value.__module__}:{value.__qualname__}"}
    if isinstance(value, dict):
        return {str(k): encode_classes(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [encode_classes(v) for v in value]
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    raise TypeError(f"cannot store {value!r} in a model file (only JSON values and classes)")


def decode_classes(value: Any, custom: dict[str, Any]) -> Any:
    """Inverse of ``encode_classes``; classes outside the allowed packages must be in ``custom``
    (keyed by ``"module:qualname"`` or the bare class name)."""
    if isinstance(value, dict) and set(value) == {"__class__"}:
        ref = str(value["__class__"])
        module, _, qualname = ref.partition(":")
        short = qualname.rsplit(".", 1)[-1]
        for key in (ref, qualname, short):
            if key in custom:
                return custom[key]
        base = next(
            (b for p, b in _ALLOWED.items() if module == p or module.startswith(p + ".")), None
        )
        if base is None:
            raise ModelFileError(
                f"model file names class {ref!r}, which palaestra will not import; "
                f"pass it via custom_objects={{{short!r}: {short}}}"
            )
        obj: Any = importlib.import_module(module)
        for part in qualname.split("."):
            obj = getattr(obj, part, None)
        if not (isinstance(obj, type) and issubclass(obj, base)):
            raise ModelFileError(f"model file names {ref!r}, which is not a {base.__name__} class")
        return obj
    if isinstance(value, dict):
        return {k: decode_classes(v, custom) for k, v in value.items()}
    if isinstance(value, list):
        return [decode_classes(v, custom) for v in value]
    return value


# -- optimizer state --------------------------------------------------------------------------
def optimizer_to_arrays(
    optimizer: torch.optim.Optimizer, prefix: str
) -> tuple[Any, dict[str, np.ndarray]]:
    """Split ``optimizer.state_dict()`` into JSON (param groups, scalars) and arrays."""
    state = optimizer.state_dict()
    arrays: dict[str, np.ndarray] = {}
    scalars: dict[str, dict[str, Any]] = {}
    for idx, per_param in state["state"].items():
        for key, val in per_param.items():
            if isinstance(val, torch.Tensor):
                arrays[f"{prefix}/{idx}/{key}"] = val.detach().cpu().numpy()
            else:
                scalars.setdefault(str(idx), {})[key] = val
    groups = [encode_classes({k: v for k, v in g.items()}) for g in state["param_groups"]]
    return {"param_groups": groups, "scalars": scalars}, arrays


def optimizer_from_arrays(
    optimizer: torch.optim.Optimizer, meta: Any, arrays: dict[str, np.ndarray], prefix: str
) -> None:
    """Load what ``optimizer_to_arrays`` produced into ``optimizer``."""
    per_param: dict[int, dict[str, Any]] = {}
    for name, array in arrays.items():
        if name.startswith(prefix + "/"):
            idx, key = name[len(prefix) + 1 :].split("/", 1)
            per_param.setdefault(int(idx), {})[key] = torch.from_numpy(array.copy())
    for idx, values in meta["scalars"].items():
        per_param.setdefault(int(idx), {}).update(values)
    groups = []
    for group in meta["param_groups"]:
        group = dict(group)
        if isinstance(group.get("betas"), list):
            group["betas"] = tuple(group["betas"])
        groups.append(group)
    try:
        optimizer.load_state_dict({"state": per_param, "param_groups": groups})
    except (ValueError, KeyError, RuntimeError) as exc:
        raise ModelFileError(f"optimizer state does not fit this model ({exc})") from exc
