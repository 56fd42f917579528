"""Model and replay-buffer files: a zip of one JSON manifest and ``.npy`` arrays. No pickle.

SB3 pickles its hyperparameters and ``torch.save``s its tensors, so loading a file can run
arbitrary code. Here the manifest is plain JSON, arrays are plain ``.npy`` (never pickle),
classes named in the manifest (``activation_fn`` …) resolve only inside ``torch.nn``,
``torch.optim`` and ``palaestra.algos`` (anything else must come through ``custom_objects``).
Loading is bounded (``utils.bounded_zip``): every array's dtype, shape and size is checked
against its member and against what the caller expects (``expect``, or ``read_manifest`` then
``read_arrays``) before anything is allocated. A stored (uncompressed) member holds its bytes on
disk, so a file can only make the reader allocate what it really contains; only the deflated
members, which a small file can inflate 1032-fold, count against ``max_bytes``. Model files are
written stored (as SB3's are, and for the same reason: deflating gigabytes of float weights
costs minutes and saves ~7%), so whatever ``save`` writes, ``load`` reads, at any size; replay
buffers and env states, which compress well, are deflated. Arrays stream one at a time both ways
(``write_archive`` takes torch tensors and copies each to the host only as it is written;
``read_arrays``' ``sink`` reads an array straight into its destination, a model's parameter),
so neither side holds a second copy of the file in memory. Bad files raise ``ModelFileError``
naming the member and what is wrong. Files are written atomically, and written behind
(``atomic_write(write_behind=True)``): each 8 MiB goes to the disk as soon as it is written and
leaves the page cache once it is there, so the ``fsync`` that makes the save durable has little
left to wait for (SB3 writes in place and does not ``fsync``; saving is still faster).

Layout::

    palaestra.json         {"format": "palaestra", "kind": "model", "version": 1,
                            "meta": {...}, "arrays": {name: {"file", "dtype", "shape"}}}
    arrays/00000.npy ...   one array each
"""

from __future__ import annotations

import contextlib
import functools
import importlib
import io
import json
import math
import operator
import os
import zipfile
import zlib
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, NamedTuple

import numpy as np
import torch
from torch import nn

from palaestra.algos.public_paths import public_ref, resolve_moved
from palaestra.utils.atomic_write import atomic_write
from palaestra.utils.bounded_zip import (
    MAX_BYTES,
    MAX_DIMS,
    NPY_HEADER_MAX,
    ModelFileError,
    check_members,
    read_member,
    read_npy,
    short,
)

__all__ = [
    "MAX_BYTES",
    "ArraySpec",
    "Manifest",
    "ModelFileError",
    "Sink",
    "decode_classes",
    "encode_classes",
    "optimizer_from_arrays",
    "optimizer_to_arrays",
    "read_archive",
    "read_arrays",
    "read_manifest",
    "resolve_path",
    "write_archive",
]

FORMAT, VERSION, MANIFEST = "palaestra", 1, "palaestra.json"
_MAX_MANIFEST = 64 << 20
_DTYPES = {"<f4", "<f8", "<f2", "|u1", "|i1", "<i2", "<u2", "<i4", "<u4", "<i8", "<u8", "|b1"}

PathLike = str | os.PathLike[str] | IO[bytes]
_CHUNK = 16 << 20  # bytes handed to the zip writer at a time (a view, never a copy)
_SMALL = 4 << 20  # arrays below this many bytes in all: the file is assembled in memory


class ArraySpec(NamedTuple):
    """What the manifest declares for one array, known before the array is read."""

    dtype: np.dtype
    shape: tuple[int, ...]

    @property
    def nbytes(self) -> int:
        return math.prod(self.shape) * self.dtype.itemsize


# ``expect(meta, declared)``: a caller's check of the declared arrays before any is read; it
# raises ModelFileError (naming the array and what it expected) for one it does not want.
Expect = Callable[[dict[str, Any], dict[str, ArraySpec]], None]
# ``sink(name, spec, read)``: a caller's destination for some arrays as they are read, one at a
# time. ``read(out)`` reads the array (into ``out``, a C-contiguous array of its dtype and shape,
# when given, else into a new one) and returns it; the sink returns True when it took the array
# (it is then left out of ``read_arrays``' result) and False to leave it there unread.
Sink = Callable[[str, ArraySpec, Callable[[np.ndarray | None], np.ndarray]], bool]


@dataclass(frozen=True)
class Manifest:
    """A checked manifest: the metadata and the declared arrays, none of them read yet."""

    meta: dict[str, Any]
    declared: dict[str, ArraySpec]
    files: dict[str, str]  # array name -> zip member
    source: PathLike
    name: str  # for messages
    stamp: tuple[int, ...] | None  # (device, inode, size, mtime) of the file read, if a path


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
    path: PathLike,
    kind: str,
    meta: dict[str, Any],
    arrays: Mapping[str, np.ndarray | torch.Tensor],
    *,
    compress: bool = True,
) -> None:
    """Write ``meta`` (JSON-able) and named numeric arrays (numpy or torch) as one archive.

    Arrays are written one at a time: a tensor is copied to the host only as it is written,
    and a host array is handed to the zip writer as views of its own buffer. ``compress=False``
    stores them uncompressed (model files: fast, and loadable at any size, see the module
    docstring). A path is written atomically (``utils.atomic_write``): a crash or ``kill -9``
    mid-save leaves the previous file whole. A file object is written directly.
    """
    for name, array in arrays.items():
        if _dtype_str(array) not in _DTYPES:
            dtype = array.dtype if isinstance(array, torch.Tensor) else np.asarray(array).dtype
            raise TypeError(f"cannot store array {name!r} of dtype {dtype}")
    target = resolve_path(path, for_write=True)
    if not isinstance(target, (str, os.PathLike)):
        _write_zip(target, kind, meta, arrays, compress)
        return
    Path(target).parent.mkdir(parents=True, exist_ok=True)
    if sum(_nbytes(array) for array in arrays.values()) < _SMALL:
        # A small file is assembled in memory and written with one call: a zip writer
        # seeks back to each member's header, a system call or two per array on a file.
        staged = io.BytesIO()
        _write_zip(staged, kind, meta, arrays, compress)
        with atomic_write(target, "wb") as file:
            file.write(staged.getbuffer())
        return
    with atomic_write(target, "wb", write_behind=True) as file:
        _write_zip(file, kind, meta, arrays, compress)


def _nbytes(array: np.ndarray | torch.Tensor) -> int:
    if isinstance(array, torch.Tensor):
        return array.numel() * array.element_size()
    return int(np.asarray(array).nbytes)


def _dtype_str(array: Any) -> str:
    """The numpy ``dtype.str`` an array or tensor is stored as ('' if numpy has none)."""
    if isinstance(array, torch.Tensor):
        return _torch_dtype_str(array.dtype)
    return np.asarray(array).dtype.str


@functools.cache
def _torch_dtype_str(dtype: torch.dtype) -> str:
    try:
        return torch.empty(0, dtype=dtype).numpy().dtype.str
    except TypeError:  # bfloat16 and other types numpy lacks
        return ""


def _host(array: np.ndarray | torch.Tensor) -> np.ndarray:
    """A C-ordered host array: a view where the data already is one, else one copy."""
    if isinstance(array, torch.Tensor):
        array = array.detach().cpu().numpy()
    return np.asarray(array, order="C")  # (ascontiguousarray makes 0-d 1-d)


def _write_npy(out: IO[bytes], array: np.ndarray) -> None:
    """``np.save``'s bytes, without its 16 MiB ``tobytes`` copies: the header, then the
    array's own buffer in slices."""
    out.write(_npy_header(array.dtype.str, array.shape))
    data = array.reshape(-1).view(np.uint8).data  # C-contiguous: a view of its buffer
    for start in range(0, len(data), _CHUNK):
        out.write(data[start : start + _CHUNK])


@functools.lru_cache(maxsize=1024)
def _npy_header(dtype: str, shape: tuple[int, ...]) -> bytes:
    """The ``.npy`` 1.0 header of a C-ordered array (a model repeats a few dtypes and shapes:
    each header is built once)."""
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": dtype, "fortran_order": False, "shape": shape}
    )
    return header.getvalue()


def _write_zip(
    file: IO[bytes],
    kind: str,
    meta: dict[str, Any],
    arrays: Mapping[str, np.ndarray | torch.Tensor],
    compress: bool,
) -> None:
    entries: dict[str, dict[str, Any]] = {}
    method = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
    with zipfile.ZipFile(file, "w", compression=method) as zf:
        for i, (name, value) in enumerate(arrays.items()):
            array = _host(value)
            member = f"arrays/{i:05d}.npy"
            # zip64 well before 2 GiB: incompressible data deflates to slightly more bytes.
            with zf.open(member, "w", force_zip64=array.nbytes > 1 << 30) as out:
                _write_npy(out, array)
            entries[name] = {"file": member, "dtype": array.dtype.str, "shape": list(array.shape)}
            del array  # a device tensor's host copy goes before the next one is made
        manifest = {
            "format": FORMAT,
            "kind": kind,
            "version": VERSION,
            "meta": meta,
            "arrays": entries,
        }
        zf.writestr(MANIFEST, json.dumps(manifest), compress_type=zipfile.ZIP_DEFLATED)


def read_archive(
    path: PathLike, kind: str, *, max_bytes: int = MAX_BYTES, expect: Expect | None = None
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Read and validate an archive written by ``write_archive``; ``ModelFileError`` if not.

    Nothing is allocated for an array before its declared size is checked: against the
    member's size, against ``max_bytes`` for all arrays together (raise it to read a larger
    replay buffer), and by ``expect(meta, declared)`` when given, which sees every array's
    declared dtype and shape before any array is read.
    """
    source, name = _source(path)
    with _opened(source, name, kind) as zf:
        manifest = _manifest(zf, kind, source, name, max_bytes)
        if expect is not None:
            expect(manifest.meta, manifest.declared)
        return manifest.meta, _arrays(zf, manifest)


def read_manifest(path: PathLike, kind: str, *, max_bytes: int = MAX_BYTES) -> Manifest:
    """The checked manifest alone (no array is read): for a caller that builds something from
    the metadata before it decides which arrays it accepts (``read_arrays``)."""
    source, name = _source(path)
    with _opened(source, name, kind) as zf:
        return _manifest(zf, kind, source, name, max_bytes)


def read_arrays(
    manifest: Manifest, expect: Expect | None = None, sink: Sink | None = None
) -> dict[str, np.ndarray]:
    """The arrays ``manifest`` declares, after ``expect(meta, declared)`` accepted them, less
    those ``sink`` took as they were read (see ``Sink``); the file must be the one the
    manifest came from."""
    if expect is not None:
        expect(manifest.meta, manifest.declared)
    with _opened(manifest.source, manifest.name, "") as zf:
        if manifest.stamp is not None and _stamp(manifest.source) != manifest.stamp:
            raise ModelFileError(f"{manifest.name} changed while it was being loaded")
        return _arrays(zf, manifest, sink)


def _source(path: PathLike) -> tuple[PathLike, str]:
    source = resolve_path(path, for_write=False)
    if isinstance(source, Path) and not source.exists():
        raise FileNotFoundError(f"no model file at {str(path)!r} (nor {str(path)!r}.zip)")
    return source, str(source) if isinstance(source, Path) else "the given file object"


def _stamp(source: PathLike) -> tuple[int, ...] | None:
    if not isinstance(source, (str, os.PathLike)):
        return None
    st = os.stat(source)
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


@contextlib.contextmanager
def _opened(source: PathLike, name: str, kind: str) -> Iterator[zipfile.ZipFile]:
    """The zip, with the errors of damaged files turned into ModelFileError."""
    what = f"a palaestra {kind} file" if kind else "a palaestra file"
    try:
        with zipfile.ZipFile(source) as zf:
            yield zf
    except zipfile.BadZipFile as exc:
        # "wasn't a zip-file": SB3's words, which callers match
        raise ModelFileError(
            f"{name} is corrupt or not {what} (it wasn't a zip-file: {short(exc)})"
        ) from exc
    except (EOFError, OSError, zipfile.LargeZipFile, zlib.error) as exc:
        raise ModelFileError(f"{name} is truncated or unreadable ({short(exc)})") from exc


def _manifest(
    zf: zipfile.ZipFile, kind: str, source: PathLike, name: str, max_bytes: int
) -> Manifest:
    members = check_members(zf, name)
    if MANIFEST not in members:
        if {"data", "policy.pth"} <= set(members):
            raise ModelFileError(
                f"{name} is a Stable-Baselines3 model file, which Algo.load does not unpickle "
                "(that can run code); palaestra.compat.from_sb3(path) reads the weights of an "
                "SB3 DQN/PPO MlpPolicy file without unpickling anything."
            )
        raise ModelFileError(
            f"{name} is a zip archive but not a palaestra {kind} file (no {MANIFEST})"
        )
    raw = read_member(zf, members[MANIFEST], _MAX_MANIFEST, name)
    try:
        manifest = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise ModelFileError(f"{name}: manifest is not valid JSON ({short(exc)})") from exc
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise ModelFileError(
            f"{name} is not a palaestra file (format {short(repr(manifest.get('format')))})"
            if isinstance(manifest, dict)
            else f"{name}: malformed manifest"
        )
    if manifest.get("kind") != kind:
        raise ModelFileError(
            f"{name} is a palaestra {short(repr(manifest.get('kind')))} file, not a {kind} file"
        )
    if not isinstance(manifest.get("version"), int) or manifest["version"] > VERSION:
        raise ModelFileError(
            f"{name} has format version {short(repr(manifest.get('version')))}; this "
            f"palaestra reads versions up to {VERSION}, upgrade palaestra"
        )
    meta, entries = manifest.get("meta"), manifest.get("arrays")
    if not isinstance(meta, dict) or not isinstance(entries, dict):
        raise ModelFileError(f"{name}: manifest lacks 'meta' or 'arrays'")
    declared, files = {}, {}
    for key, entry in entries.items():
        files[key], declared[key] = _entry(key, entry, members, name)
    if len(set(files.values())) != len(files):
        raise ModelFileError(f"{name}: two arrays name the same member")
    # Stored members hold their bytes on disk (check_members): only what deflate inflates
    # is bounded by max_bytes.
    stored = zipfile.ZIP_STORED
    total = sum(
        spec.nbytes for key, spec in declared.items() if members[files[key]].compress_type != stored
    )
    if total > max_bytes:
        raise ModelFileError(
            f"{name}: its deflated arrays declare {total} bytes in all, more than the limit "
            f"max_bytes={max_bytes} (pass a larger max_bytes to read a file this large)"
        )
    return Manifest(meta, declared, files, source, name, _stamp(source))


def _entry(
    key: str, entry: Any, members: dict[str, zipfile.ZipInfo], name: str
) -> tuple[str, ArraySpec]:
    """The member and declared spec of one array, refused when the member cannot hold it."""
    where = f"{name}: array {short(key, 80)!r}"
    try:
        file, dtype = str(entry["file"]), np.dtype(str(entry["dtype"]))
        shape = tuple(operator.index(d) for d in entry["shape"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(f"{where} has a malformed entry") from exc
    if file not in members:
        raise ModelFileError(f"{where}: its member {short(file, 80)!r} is missing")
    if dtype.str not in _DTYPES or len(shape) > MAX_DIMS or any(d < 0 for d in shape):
        raise ModelFileError(f"{where} has an unsupported dtype/shape ({dtype}, {short(shape)})")
    spec = ArraySpec(dtype, shape)
    size = members[file].file_size
    if not spec.nbytes < size <= spec.nbytes + NPY_HEADER_MAX:  # data plus a .npy header
        raise ModelFileError(
            f"{where}: member {short(file, 80)!r} holds {size} bytes, its declared "
            f"{dtype} {shape} needs {spec.nbytes} plus a .npy header"
        )
    return file, spec


def _arrays(
    zf: zipfile.ZipFile, manifest: Manifest, sink: Sink | None = None
) -> dict[str, np.ndarray]:
    """Each declared array, streamed into a buffer of exactly its declared size (the sink's,
    or a new one)."""
    members = check_members(zf, manifest.name)
    arrays = {}
    for key, spec in manifest.declared.items():
        info = members.get(manifest.files[key])
        if info is None:
            raise ModelFileError(f"{manifest.name}: array {short(key, 80)!r} is missing")

        def read(
            out: np.ndarray | None, info: zipfile.ZipInfo = info, spec: ArraySpec = spec
        ) -> np.ndarray:
            dtypes = {spec.dtype.str}
            return read_npy(zf, info, manifest.name, spec.nbytes, dtypes, spec.shape, out=out)

        if sink is None or not sink(key, spec, read):
            arrays[key] = read(None)
    return arrays


# -- classes in policy_kwargs -----------------------------------------------------------------
_ALLOWED = {  # the first prefix a class's module has decides
    "torch.nn": nn.Module,
    "torch.optim": torch.optim.Optimizer,
    "palaestra.algos.common.sb2_compat": torch.optim.Optimizer,  # RMSpropTFLike
    "palaestra.algos": nn.Module,
}


def encode_classes(value: Any) -> Any:
    """Replace classes in (nested) kwargs by ``{"__class__": "module:qualname"}``, naming
    palaestra's classes by the path users import them from (``public_paths.public_ref``)."""
    if isinstance(value, type):
        return {"__class__": public_ref(value)}
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
        # a file from before a class moved names its old module (resolve_moved's table)
        module, _, qualname = resolve_moved(ref).partition(":")
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
) -> tuple[Any, dict[str, torch.Tensor]]:
    """Split ``optimizer.state_dict()`` into JSON (param groups, scalars) and tensors (left
    where they are: ``write_archive`` copies each to the host as it writes it)."""
    state = optimizer.state_dict()
    arrays: dict[str, torch.Tensor] = {}
    scalars: dict[str, dict[str, Any]] = {}
    for idx, per_param in state["state"].items():
        for key, val in per_param.items():
            if isinstance(val, torch.Tensor):
                arrays[f"{prefix}/{idx}/{key}"] = val.detach()
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
            # read_npy's arrays are fresh and writable: shared, not copied
            per_param.setdefault(int(idx), {})[key] = torch.from_numpy(array)
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
