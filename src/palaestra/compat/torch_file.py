"""Read a ``torch.save``'d tensor ``state_dict`` without unpickling it and without torch.

A ``torch.save`` file is a zip: ``<dir>/data.pkl`` is a pickle stream describing the dict and
``<dir>/data/<key>`` hold the raw tensor bytes. Unpickling the stream (``torch.load`` with
``weights_only=False``, ``pickle.load``) calls whatever the stream names, which is how a
model file runs code. Here the stream is only parsed (``pickletools.genops``) and interpreted
by a small stack machine that knows the opcodes a state_dict uses. The callables it may name are
an allow-list of four kinds: ``collections.OrderedDict``, ``torch._utils._rebuild_tensor_v2``,
``torch._utils._rebuild_parameter`` and the ``torch.<Type>Storage`` classes; none is called,
each is recognised and its effect computed with numpy. Anything else (``os.system``,
``builtins.eval``, object construction opcodes ...) raises :class:`UnsafeFileError` before
anything after it is read.

Reading is bounded as well: a storage's declared element count must fit in its member (read
with a bounded read, never trusted), every tensor view must lie inside its storage without
stride-0 or overlapping dimensions, the copies the views make, the pickle's size and its
number of opcodes are capped, and no parsed structure is hashed, compared or printed whole
(a memo lets a few bytes describe a 2**60-node structure): messages show a bounded summary.
"""

from __future__ import annotations

import io
import math
import os
import pickletools
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from palaestra.utils.bounded_zip import (
    MAX_DIMS,
    ModelFileError,
    check_members,
    read_member,
    short,
    summary,
)

__all__ = ["MAX_STATE_DICT_BYTES", "TorchFileError", "UnsafeFileError", "read_torch_state_dict"]

MAX_STATE_DICT_BYTES = 1 << 30  # default cap on a file's storages (an MlpPolicy's: a few MB)

_MAX_PICKLE = 16 << 20  # a state_dict's data.pkl is ~150 bytes a tensor
_MAX_OPS = 2_000_000  # opcodes, so objects: bounds the parsed structure's memory
_MAX_INT = 1 << 62  # for sizes, strides, offsets and element counts
_VIEW_COPIES = 4  # tensors may copy 4x the bytes of their storages (tied weights: 2-3 views)

# Legacy typed-storage names, which torch.save still writes for every tensor.
_STORAGES = {
    "FloatStorage": "f4",
    "DoubleStorage": "f8",
    "HalfStorage": "f2",
    "LongStorage": "i8",
    "IntStorage": "i4",
    "ShortStorage": "i2",
    "CharStorage": "i1",
    "ByteStorage": "u1",
    "BoolStorage": "b1",
}
_ORDERED_DICT = ("collections", "OrderedDict")
_REBUILD_TENSOR = ("torch._utils", "_rebuild_tensor_v2")
_REBUILD_PARAMETER = ("torch._utils", "_rebuild_parameter")
_ALLOWED = {_ORDERED_DICT, _REBUILD_TENSOR, _REBUILD_PARAMETER} | {
    ("torch", name) for name in _STORAGES
}


class TorchFileError(ModelFileError):
    """A file is not a readable ``torch.save`` state_dict (corrupt, foreign, unsupported,
    oversized)."""


class UnsafeFileError(TorchFileError):
    """A file names code to run: not a plain tensor state_dict. Nothing in it was run."""


@dataclass(frozen=True)
class _Global:
    module: str
    name: str


@dataclass(frozen=True)
class _Storage:
    array: np.ndarray  # the whole storage, 1-D


_MARK = object()


def read_torch_state_dict(
    source: str | os.PathLike[str] | bytes | IO[bytes],
    *,
    max_bytes: int = MAX_STATE_DICT_BYTES,
) -> dict[str, np.ndarray]:
    """``{name: array}`` from a ``torch.save(module.state_dict())`` file, unpickling nothing.

    Raises :class:`UnsafeFileError` if the file names any callable outside the allow-list and
    :class:`TorchFileError` if it is not a zip-format tensor state_dict, or if its storages
    would take more than ``max_bytes``.
    """
    name = str(source) if isinstance(source, (str, os.PathLike)) else "the given torch file"
    data = io.BytesIO(source) if isinstance(source, bytes) else source
    if isinstance(data, (str, os.PathLike)) and not Path(data).exists():
        raise FileNotFoundError(f"no torch file at {name!r}")
    try:
        with zipfile.ZipFile(data) as zf:
            return _read(zf, name, max_bytes)
    except zipfile.BadZipFile as exc:
        raise TorchFileError(
            f"{name} is not a zip-format torch file ({short(exc)}); files from torch < 1.6 "
            "(legacy format) are not supported"
        ) from exc
    except (EOFError, zlib.error) as exc:
        raise TorchFileError(f"{name} is truncated or corrupt ({short(exc)})") from exc
    except TorchFileError:
        raise
    except ModelFileError as exc:  # from the zip checks: keep this module's error type
        raise TorchFileError(str(exc)) from exc


def _read(zf: zipfile.ZipFile, name: str, max_bytes: int) -> dict[str, np.ndarray]:
    members = check_members(zf, name)
    pickles = [n for n in members if n.endswith("/data.pkl") and n.count("/") == 1]
    if len(pickles) != 1:
        raise TorchFileError(f"{name} is a zip but not a torch file (no <dir>/data.pkl)")
    prefix = pickles[0][: -len("data.pkl")]
    byteorder = "little"
    if prefix + "byteorder" in members:
        raw = read_member(zf, members[prefix + "byteorder"], 16, name)
        byteorder = raw.decode("ascii", "replace").strip()
    if byteorder not in ("little", "big"):
        raise TorchFileError(f"{name}: unknown byte order {byteorder!r}")
    machine = _Machine(zf, members, prefix, "<" if byteorder == "little" else ">", name, max_bytes)
    result = machine.run(read_member(zf, members[pickles[0]], _MAX_PICKLE, name))
    if not isinstance(result, dict) or not all(
        isinstance(k, str) and isinstance(v, np.ndarray) for k, v in result.items()
    ):
        raise TorchFileError(f"{name} holds a {type(result).__name__}, not a tensor state_dict")
    return result


class _Machine:
    """The subset of the pickle virtual machine that a tensor state_dict uses."""

    def __init__(
        self,
        zf: zipfile.ZipFile,
        members: dict[str, zipfile.ZipInfo],
        prefix: str,
        order: str,
        name: str,
        budget: int,
    ) -> None:
        self.zf, self.members, self.prefix, self.order, self.name = zf, members, prefix, order, name
        self.stack: list[Any] = []
        self.memo: dict[int, Any] = {}
        self.storages: dict[str, _Storage] = {}
        self.budget = budget  # bytes the storages may take in all
        self.stored = 0  # bytes of storage read
        self.copied = 0  # bytes of tensors made from them

    def fail(self, message: str, unsafe: bool = False) -> TorchFileError:
        cls = UnsafeFileError if unsafe else TorchFileError
        return cls(f"{self.name}: {message}")

    def run(self, stream: bytes) -> Any:
        try:
            for count, (opcode, arg, _pos) in enumerate(pickletools.genops(stream)):
                if count >= _MAX_OPS:
                    raise self.fail(
                        f"data.pkl has more than {_MAX_OPS} opcodes, the limit for a state_dict"
                    )
                done = self.step(opcode.name, arg)
                if done:
                    return self.stack.pop()
        except (ValueError, IndexError, KeyError, TypeError, OverflowError) as exc:
            if isinstance(exc, TorchFileError):
                raise
            raise self.fail(f"malformed pickle stream ({short(repr(exc))})") from exc
        raise self.fail("pickle stream ends without STOP")

    def pop_mark(self) -> list[Any]:
        for i in range(len(self.stack) - 1, -1, -1):
            if self.stack[i] is _MARK:
                items = self.stack[i + 1 :]
                del self.stack[i:]
                return items
        raise self.fail("MARK expected on the pickle stack")

    def step(self, op: str, arg: Any) -> bool:
        s = self.stack
        if op in ("PROTO", "FRAME"):
            pass
        elif op == "STOP":
            return True
        elif op == "MARK":
            s.append(_MARK)
        elif op in ("GLOBAL", "STACK_GLOBAL"):
            if op == "GLOBAL":
                module, _, attr = str(arg).partition(" ")
            else:
                attr, module = s.pop(), s.pop()
                if not (isinstance(module, str) and isinstance(attr, str)):
                    raise self.fail("STACK_GLOBAL needs two strings")
            if (module, attr) not in _ALLOWED:
                raise self.fail(
                    f"refers to {short(module, 60)}.{short(attr, 60)}, which a tensor "
                    "state_dict never does; refusing "
                    "to load it (the file may be malicious; nothing in it was run)",
                    unsafe=True,
                )
            s.append(_Global(module, attr))
        elif op in ("BINPUT", "LONG_BINPUT", "PUT"):
            self.memo[int(arg)] = s[-1]
        elif op == "MEMOIZE":
            self.memo[len(self.memo)] = s[-1]
        elif op in ("BINGET", "LONG_BINGET", "GET"):
            s.append(self.memo[int(arg)])
        elif op == "EMPTY_TUPLE":
            s.append(())
        elif op == "TUPLE":
            s.append(tuple(self.pop_mark()))
        elif op in ("TUPLE1", "TUPLE2", "TUPLE3"):
            n = int(op[-1])
            s[-n:] = [tuple(s[-n:])]
        elif op == "EMPTY_LIST":
            s.append([])
        elif op in ("APPEND", "APPENDS"):
            self._container(list).extend([s.pop()] if op == "APPEND" else self.pop_mark())
        elif op == "EMPTY_DICT":
            s.append({})
        elif op in ("SETITEM", "SETITEMS"):
            if op == "SETITEM":
                items = s[-2:]
                del s[-2:]
            else:
                items = self.pop_mark()
            target = self._container(dict)
            for key, value in zip(items[::2], items[1::2]):
                if not isinstance(key, (str, int)):  # hashing a shared tuple can take 2**n
                    raise self.fail(f"a dict key is a {type(key).__name__}, not a name")
                target[key] = value
        elif op in _LITERALS:
            s.append(arg)
        elif op == "NONE":
            s.append(None)
        elif op in ("NEWTRUE", "NEWFALSE"):
            s.append(op == "NEWTRUE")
        elif op == "POP":
            s.pop()
        elif op == "BINPERSID":
            s.append(self._storage(s.pop()))
        elif op == "REDUCE":
            args = s.pop()
            s.append(self._reduce(s.pop(), args))
        elif op == "BUILD":
            s.pop()  # OrderedDict's __dict__ (torch's `_metadata`): not needed for the tensors
            if not isinstance(s[-1], dict):
                raise self.fail(f"BUILD on a {type(s[-1]).__name__}, not on a state_dict")
        else:
            raise self.fail(
                f"uses the pickle opcode {op}, which a tensor state_dict never does; refusing to "
                "load it (the file may be malicious; nothing in it was run)",
                unsafe=True,
            )
        return False

    def _container(self, kind: type) -> Any:
        if not isinstance(self.stack[-1], kind):
            raise self.fail(f"expected a {kind.__name__} on the pickle stack")
        return self.stack[-1]

    def _storage(self, pid: Any) -> _Storage:
        if not (
            isinstance(pid, tuple)
            and len(pid) == 5
            and pid[0] == "storage"
            and isinstance(pid[1], _Global)
            and pid[1].module == "torch"
            and pid[1].name in _STORAGES
            and isinstance(pid[2], str)
            and isinstance(pid[4], int)
        ):
            raise self.fail(f"unexpected persistent id {summary(pid)}")
        key, numel = pid[2], pid[4]
        if key not in self.storages:
            file = f"{self.prefix}data/{key}"
            if "/" in key or file not in self.members:
                raise self.fail(f"storage {short(key, 60)!r} is missing")
            info = self.members[file]
            dtype = np.dtype(self.order + _STORAGES[pid[1].name])
            if not 0 <= numel < _MAX_INT or info.file_size < numel * dtype.itemsize:
                raise self.fail(
                    f"storage {key!r} (member {file!r}) holds {info.file_size} bytes, fewer "
                    f"than its {short(numel, 40)} elements need"
                )
            nbytes = numel * dtype.itemsize
            if self.stored + nbytes > self.budget:
                raise self.fail(
                    f"storage {key!r} (member {file!r}) would take the storages past "
                    f"{nbytes + self.stored} bytes, more than the limit max_bytes={self.budget}"
                )
            with self.zf.open(info) as member:
                raw = member.read(nbytes)  # the elements only, however long the member
            if len(raw) < nbytes:
                raise self.fail(f"storage {key!r} holds fewer than its {numel} elements")
            self.stored += nbytes
            array = np.frombuffer(raw, dtype=dtype, count=numel)
            native = dtype.newbyteorder("=")
            self.storages[key] = _Storage(array if dtype.isnative else array.astype(native))
        return self.storages[key]

    def _reduce(self, func: Any, args: Any) -> Any:
        if not isinstance(func, _Global) or not isinstance(args, tuple):
            raise self.fail("REDUCE on something other than an allowed function")
        where = (func.module, func.name)
        if where == _ORDERED_DICT and args == ():
            return {}
        if where == _REBUILD_TENSOR and len(args) in (6, 7):
            return self._tensor(*args[:4])
        if where == _REBUILD_PARAMETER and len(args) == 3 and isinstance(args[0], np.ndarray):
            return args[0]
        raise self.fail(f"unexpected call {func.module}.{func.name}{summary(args)}")

    def _tensor(self, storage: Any, offset: Any, size: Any, stride: Any) -> np.ndarray:
        ints = (
            isinstance(offset, int)
            and isinstance(size, tuple)
            and isinstance(stride, tuple)
            and len(size) == len(stride) <= MAX_DIMS
            and all(isinstance(d, int) and 0 <= d < _MAX_INT for d in (*size, *stride))
        )
        if not isinstance(storage, _Storage) or not ints or not 0 <= offset < _MAX_INT:
            raise self.fail(f"malformed tensor (offset {summary(offset)}, size {summary(size)})")
        data = storage.array
        if 0 in size:
            return np.zeros(size, dtype=data.dtype)
        self._check_view(size, stride)
        last = offset + sum((d - 1) * st for d, st in zip(size, stride))
        if last >= data.size:
            raise self.fail(f"tensor of size {size} reads past its storage ({data.size} elements)")
        self.copied += math.prod(size) * data.itemsize
        if self.copied > _VIEW_COPIES * self.stored + (1 << 20):
            raise self.fail(
                f"its tensors copy {self.copied} bytes out of {self.stored} bytes of storage, "
                f"more than the limit of {_VIEW_COPIES}x (views repeated to multiply memory)"
            )
        view = np.lib.stride_tricks.as_strided(
            data[offset:], shape=size, strides=[st * data.itemsize for st in stride]
        )
        return np.array(view)  # a copy: no aliasing between tensors that share a storage

    def _check_view(self, size: tuple[int, ...], stride: tuple[int, ...]) -> None:
        """Refuse views that read an element twice: stride 0 (a broadcast) or dimensions that
        overlap. Sorted by stride, each dimension must step past everything the smaller ones
        cover, as in any slice or transpose of a contiguous tensor."""
        covered = 0  # elements spanned by the dimensions checked so far, minus one
        for d, st in sorted(((d, st) for d, st in zip(size, stride) if d > 1), key=lambda p: p[1]):
            if st == 0:
                raise self.fail(
                    f"tensor of size {size} has stride 0 (a broadcast view repeating one "
                    "element), which torch.save never writes"
                )
            if st <= covered:
                raise self.fail(
                    f"tensor of size {size} and stride {stride} has overlapping dimensions, "
                    "which torch.save never writes"
                )
            covered += (d - 1) * st


_LITERALS = {
    "BINUNICODE",
    "SHORT_BINUNICODE",
    "BINUNICODE8",
    "UNICODE",
    "BININT",
    "BININT1",
    "BININT2",
    "INT",
    "LONG",
    "LONG1",
    "LONG4",
    "BINFLOAT",
    "FLOAT",
}
