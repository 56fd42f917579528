"""Zip members and ``.npy`` arrays read from files whose headers may lie, in bounded memory.

A model file is a zip, and a zip states its members' sizes; a ``.npy`` header states a dtype and
shape. A crafted file can state anything: a 1 MB file whose member declares 2 GB makes a naive
reader allocate 2 GB before it finds out the data is not there or not wanted. Here every
declared size is checked, before anything is allocated, against

- a limit the caller gives (and, through ``expect`` hooks in the callers, what the reader
  expects the file to hold: the shapes of the model's parameters),
- what the stored bytes can physically hold: deflate expands at most 1032-fold, a stored member
  not at all (so a 1 MB file cannot make us allocate more than ~1 GB even within the limit),

and then read by streaming with reads bounded by the declared size, so a header that
understates its member fails the CRC check instead of growing a buffer. Encrypted members,
compression other than stored/deflate (bzip2 and LZMA bombs expand a million-fold) and
duplicate member names are refused. No module here imports torch.
"""

from __future__ import annotations

import itertools
import math
import zipfile
from collections.abc import Collection
from typing import IO

import numpy as np

from palaestra import error

__all__ = [
    "MAX_BYTES",
    "ModelFileError",
    "check_members",
    "read_member",
    "read_npy",
    "short",
    "summary",
]

MAX_BYTES = 16 << 30  # default cap on the uncompressed array bytes of one file
DEFLATE_MAX_RATIO = 1032  # 258-byte matches coded in 2 bits: deflate's largest expansion
NPY_HEADER_MAX = 4096  # a .npy header (magic, length, dict) of up to 32 dims fits easily
MAX_DIMS = 32
_CHUNK = 1 << 20  # bytes decompressed per read
_PLAIN_KINDS = "biufcUS"  # numeric, bool and fixed-width text dtypes: never objects, records


class ModelFileError(error.Error, ValueError):
    """A model, replay-buffer or statistics file is corrupt, truncated, foreign, oversized or
    unsafe; the message names the file, the member and what is wrong."""


def short(value: object, limit: int = 120) -> str:
    """``str(value)`` cut to ``limit`` characters, for messages about untrusted text."""
    text = str(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def summary(value: object, depth: int = 2, items: int = 4) -> str:
    """A short description of an untrusted, possibly huge or self-sharing structure (a parsed
    pickle can nest one list 2**60 times through its memo): at most ``items`` entries per
    container and ``depth`` levels, so it costs O(items**depth) however large ``value`` is.

    >>> summary({"w": [1, 2, 3, 4, 5, 6], "k": (2**200,)})
    "{'w': [1, 2, 3, 4, ... 6 in all], 'k': (<int of 201 bits>,)}"
    """
    if isinstance(value, (list, tuple, dict)):
        if depth <= 0:
            return f"<{type(value).__name__} of {len(value)}>"
        if isinstance(value, dict):
            pairs = itertools.islice(value.items(), items)
            parts = [f"{summary(k, 0)}: {summary(v, depth - 1, items)}" for k, v in pairs]
        else:
            parts = [summary(v, depth - 1, items) for v in itertools.islice(value, items)]
        if len(value) > items:
            parts.append(f"... {len(value)} in all")
        text = ", ".join(parts)
        if isinstance(value, dict):
            return "{" + text + "}"
        if isinstance(value, list):
            return "[" + text + "]"
        return "(" + text + ("," if len(value) == 1 else "") + ")"
    if isinstance(value, (bool, float)) or value is None:
        return repr(value)
    if isinstance(value, int):  # repr of a huge int is slow, and refused past 4300 digits
        return repr(value) if value.bit_length() <= 64 else f"<int of {value.bit_length()} bits>"
    if isinstance(value, (str, bytes)):
        return repr(value[:40]) + ("..." if len(value) > 40 else "")
    if isinstance(value, np.ndarray):
        return f"<array {value.dtype} {value.shape}>"
    return f"<{type(value).__name__}>"


def check_members(zf: zipfile.ZipFile, name: str) -> dict[str, zipfile.ZipInfo]:
    """The members by name, after refusing what no file palaestra reads contains: duplicate
    names, encryption, compression other than stored or deflate, and declared sizes that the
    stored bytes cannot hold."""
    members: dict[str, zipfile.ZipInfo] = {}
    for info in zf.infolist():
        member = short(info.filename, 80)
        if info.filename in members:
            raise ModelFileError(f"{name}: member {member!r} appears twice in the zip")
        if info.flag_bits & 0x1:
            raise ModelFileError(f"{name}: member {member!r} is encrypted")
        if info.compress_type == zipfile.ZIP_STORED:
            possible = info.compress_size
        elif info.compress_type == zipfile.ZIP_DEFLATED:
            possible = DEFLATE_MAX_RATIO * info.compress_size + 1024
        else:
            raise ModelFileError(
                f"{name}: member {member!r} uses zip compression method {info.compress_type}; "
                "only stored and deflate members are read"
            )
        if info.file_size > possible:
            raise ModelFileError(
                f"{name}: member {member!r} declares {info.file_size} bytes, more than its "
                f"{info.compress_size} stored bytes can hold (a zip bomb or a damaged header)"
            )
        members[info.filename] = info
    return members


def read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, limit: int, name: str) -> bytes:
    """The bytes of ``info``, refused before reading if it declares more than ``limit``."""
    if info.file_size > limit:
        raise ModelFileError(
            f"{name}: member {short(info.filename, 80)!r} declares {info.file_size} bytes, "
            f"more than the limit of {limit} bytes for it"
        )
    with zf.open(info) as file:
        data = file.read(limit + 1)
    if len(data) > limit:  # zipfile stops at the declared size; this is a second fence
        raise ModelFileError(f"{name}: member {short(info.filename, 80)!r} exceeds {limit} bytes")
    return data


def read_npy(
    zf: zipfile.ZipFile,
    info: zipfile.ZipInfo,
    name: str,
    max_bytes: int,
    dtypes: Collection[str] | None = None,
    shape: tuple[int, ...] | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """The array in the ``.npy`` member ``info``, read without pickle into one buffer: ``out``
    (a writable C-contiguous array of the stated dtype and shape, which is returned) or a new one.

    Its header must state a dtype among ``dtypes`` (``dtype.str`` values; by default any plain
    numeric, bool or text dtype), ``shape`` when given, and at most ``max_bytes`` of data, and
    the member must hold exactly that: all checked before the array is allocated.
    """
    member = short(info.filename, 80)
    with zf.open(info) as file:
        dtype, found, fortran = _npy_header(file, f"{name}: member {member!r}")
        if dtypes is not None and dtype.str not in dtypes:
            expected = ", ".join(sorted(dtypes))
            raise ModelFileError(f"{name}: member {member!r} holds dtype {dtype}, not {expected}")
        if dtypes is None and dtype.kind not in _PLAIN_KINDS:
            raise ModelFileError(
                f"{name}: member {member!r} holds dtype {short(dtype)}, not a plain numeric "
                "array (objects would need pickle)"
            )
        if shape is not None and found != shape:
            raise ModelFileError(f"{name}: member {member!r} has shape {found}, expected {shape}")
        nbytes = math.prod(found) * dtype.itemsize
        if nbytes > max_bytes:
            raise ModelFileError(
                f"{name}: member {member!r} declares {nbytes} bytes of data "
                f"(shape {found}), more than the limit of {max_bytes} bytes"
            )
        if file.tell() + nbytes != info.file_size:
            raise ModelFileError(
                f"{name}: member {member!r} holds {info.file_size - file.tell()} bytes of data, "
                f"its header says {nbytes}"
            )
        direct = (
            out is not None
            and not fortran
            and out.shape == found
            and out.dtype == dtype
            and out.flags.c_contiguous
            and out.flags.writeable
        )
        base = out if direct else np.empty(found[::-1] if fortran else found, dtype=dtype)
        assert base is not None
        _read_into(file, base, f"{name}: member {member!r}")
    result = base.T if fortran else base
    if out is not None and not direct:
        out[...] = result  # (a Fortran-ordered file, or a destination of another layout)
        return out
    return result


def _npy_header(file: IO[bytes], where: str) -> tuple[np.dtype, tuple[int, ...], bool]:
    try:
        version = np.lib.format.read_magic(file)
        if version == (1, 0):
            header = np.lib.format.read_array_header_1_0(file, max_header_size=NPY_HEADER_MAX)
        elif version in ((2, 0), (3, 0)):
            header = np.lib.format.read_array_header_2_0(file, max_header_size=NPY_HEADER_MAX)
        else:
            raise ValueError(f"unsupported .npy format version {version}")
    except (ValueError, TypeError, SyntaxError, RecursionError) as exc:
        raise ModelFileError(f"{where} is not a .npy array ({short(exc)})") from exc
    shape, fortran, dtype = header
    if len(shape) > MAX_DIMS or any(d < 0 for d in shape):
        raise ModelFileError(f"{where} has an invalid shape {short(shape)}")
    return dtype, tuple(shape), bool(fortran)


def _read_into(file: IO[bytes], array: np.ndarray, where: str) -> None:
    """Fill ``array``'s buffer from ``file`` in chunks; the file must end exactly there."""
    flat = array.reshape(-1).view(np.uint8).data  # a view of the array's own buffer
    pos = 0
    while pos < len(flat):
        count = file.readinto(flat[pos : pos + _CHUNK])  # type: ignore[attr-defined]
        if not count:
            raise ModelFileError(f"{where} is truncated ({pos} of {len(flat)} bytes)")
        pos += count
    if file.read(1):  # also completes zipfile's CRC check
        raise ModelFileError(f"{where} is longer than its header says")
