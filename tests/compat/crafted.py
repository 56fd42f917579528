"""Hand-written pickle streams and torch-format zips for the safe-reader tests.

The streams are assembled opcode by opcode (no ``pickle.dumps``), so each test says exactly what
the file contains.
"""

from __future__ import annotations

import io
import struct
import zipfile


def text(value: str) -> bytes:
    """BINUNICODE ``value``."""
    raw = value.encode()
    return b"X" + struct.pack("<I", len(raw)) + raw


def call_global(module: str, name: str, arg: str) -> bytes:
    """``module.name(arg)`` via GLOBAL, TUPLE1, REDUCE: what a malicious pickle does."""
    return b"c" + f"{module}\n{name}\n".encode() + text(arg) + b"\x85R"


def call_stack_global(module: str, name: str, arg: str) -> bytes:
    """The same through STACK_GLOBAL (protocol 4), which takes the names from the stack."""
    return text(module) + text(name) + b"\x93" + text(arg) + b"\x85R"


def state_dict_with(value: bytes) -> bytes:
    """``OrderedDict(w=<value>)`` as torch writes a state_dict (protocol 2)."""
    return b"\x80\x02ccollections\nOrderedDict\n)R(" + text("w") + value + b"u."


def payload(command_stream: bytes) -> bytes:
    """A bare stream that only runs the call."""
    return b"\x80\x02" + command_stream + b"."


def torch_zip(data_pkl: bytes, storages: dict[str, bytes] | None = None) -> bytes:
    """A zip laid out as ``torch.save`` lays it out."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("archive/data.pkl", data_pkl)
        zf.writestr("archive/byteorder", "little")
        zf.writestr("archive/version", "3\n")
        for key, raw in (storages or {}).items():
            zf.writestr(f"archive/data/{key}", raw)
    return buf.getvalue()


def tensor(
    storage_type: str, key: str, numel: int, offset: int, size: tuple, stride: tuple
) -> bytes:
    """``torch._utils._rebuild_tensor_v2(<storage key>, offset, size, stride, False, {})``."""

    def ints(values: tuple) -> bytes:
        return b"(" + b"".join(b"J" + struct.pack("<i", v) for v in values) + b"t"

    pid = b"(" + text("storage") + f"ctorch\n{storage_type}\n".encode() + text(key)
    pid += text("cpu") + b"J" + struct.pack("<i", numel) + b"tQ"
    args = b"(" + pid + b"J" + struct.pack("<i", offset) + ints(size) + ints(stride)
    return b"ctorch._utils\n_rebuild_tensor_v2\n" + args + b"\x89}tR"
