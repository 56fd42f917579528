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
"""

from __future__ import annotations

import io
import os
import pickletools
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from palaestra import error

__all__ = ["TorchFileError", "UnsafeFileError", "read_torch_state_dict"]

_MAX_PICKLE = 64 << 20

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


class TorchFileError(error.Error, ValueError):
    """A file is not a readable ``torch.save`` state_dict (corrupt, foreign, unsupported)."""


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
) -> dict[str, np.ndarray]:
    """``{name: array}`` from a ``torch.save(module.state_dict())`` file, unpickling nothing.

    Raises :class:`UnsafeFileError` if the file names any callable outside the allow-list and
    :class:`TorchFileError` if it is not a zip-format tensor state_dict.
    """
    name = str(source) if isinstance(source, (str, os.PathLike)) else "the given torch file"
    data = io.BytesIO(source) if isinstance(source, bytes) else source
    if isinstance(data, (str, os.PathLike)) and not Path(data).exists():
        raise FileNotFoundError(f"no torch file at {name!r}")
    try:
        with zipfile.ZipFile(data) as zf:
            return _read(zf, name)
    except zipfile.BadZipFile as exc:
        raise TorchFileError(
            f"{name} is not a zip-format torch file ({exc}); files from torch < 1.6 "
            "(legacy format) are not supported"
        ) from exc


def _read(zf: zipfile.ZipFile, name: str) -> dict[str, np.ndarray]:
    pickles = [n for n in zf.namelist() if n.endswith("/data.pkl") and n.count("/") == 1]
    if len(pickles) != 1:
        raise TorchFileError(f"{name} is a zip but not a torch file (no <dir>/data.pkl)")
    prefix = pickles[0][: -len("data.pkl")]
    if zf.getinfo(pickles[0]).file_size > _MAX_PICKLE:
        raise TorchFileError(f"{name}: data.pkl is implausibly large for a state_dict")
    byteorder = "little"
    if prefix + "byteorder" in zf.namelist():
        byteorder = zf.read(prefix + "byteorder").decode("ascii", "replace").strip()
    if byteorder not in ("little", "big"):
        raise TorchFileError(f"{name}: unknown byte order {byteorder!r}")
    machine = _Machine(zf, prefix, "<" if byteorder == "little" else ">", name)
    result = machine.run(zf.read(pickles[0]))
    if not isinstance(result, dict) or not all(
        isinstance(k, str) and isinstance(v, np.ndarray) for k, v in result.items()
    ):
        raise TorchFileError(f"{name} holds a {type(result).__name__}, not a tensor state_dict")
    return result


class _Machine:
    """The subset of the pickle virtual machine that a tensor state_dict uses."""

    def __init__(self, zf: zipfile.ZipFile, prefix: str, order: str, name: str) -> None:
        self.zf, self.prefix, self.order, self.name = zf, prefix, order, name
        self.stack: list[Any] = []
        self.memo: dict[int, Any] = {}
        self.storages: dict[str, _Storage] = {}

    def fail(self, message: str, unsafe: bool = False) -> TorchFileError:
        cls = UnsafeFileError if unsafe else TorchFileError
        return cls(f"{self.name}: {message}")

    def run(self, stream: bytes) -> Any:
        try:
            for opcode, arg, _pos in pickletools.genops(stream):
                done = self.step(opcode.name, arg)
                if done:
                    return self.stack.pop()
        except (ValueError, IndexError, KeyError, TypeError) as exc:
            if isinstance(exc, TorchFileError):
                raise
            raise self.fail(f"malformed pickle stream ({exc!r})") from exc
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
                    f"refers to {module}.{attr}, which a tensor state_dict never does; refusing "
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
            raise self.fail(f"unexpected persistent id {pid!r}")
        key, numel = pid[2], pid[4]
        if key not in self.storages:
            file = f"{self.prefix}data/{key}"
            if "/" in key or file not in self.zf.namelist():
                raise self.fail(f"storage {key!r} is missing")
            dtype = np.dtype(self.order + _STORAGES[pid[1].name])
            raw = self.zf.read(file)
            if numel < 0 or len(raw) < numel * dtype.itemsize:
                raise self.fail(f"storage {key!r} holds fewer than its {numel} elements")
            array = np.frombuffer(raw, dtype=dtype, count=numel)
            self.storages[key] = _Storage(array.astype(dtype.newbyteorder("=")))
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
        raise self.fail(f"unexpected call {func.module}.{func.name}{args!r}")

    def _tensor(self, storage: Any, offset: Any, size: Any, stride: Any) -> np.ndarray:
        ints = (
            isinstance(offset, int)
            and isinstance(size, tuple)
            and isinstance(stride, tuple)
            and len(size) == len(stride)
            and all(isinstance(d, int) and d >= 0 for d in (*size, *stride))
        )
        if not isinstance(storage, _Storage) or not ints or offset < 0:
            raise self.fail(f"malformed tensor (offset {offset!r}, size {size!r})")
        data = storage.array
        if 0 in size:
            return np.zeros(size, dtype=data.dtype)
        last = offset + sum((d - 1) * st for d, st in zip(size, stride))
        if last >= data.size:
            raise self.fail(f"tensor of size {size} reads past its storage ({data.size} elements)")
        view = np.lib.stride_tricks.as_strided(
            data[offset:], shape=size, strides=[st * data.itemsize for st in stride]
        )
        return np.array(view)  # a copy: no aliasing between tensors that share a storage


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
