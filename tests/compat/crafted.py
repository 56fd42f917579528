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


# -- bounded-loader fixtures: files whose declared sizes or structures are hostile --------------
def memo_bomb(depth: int) -> bytes:
    """A stream of ~8 bytes a level whose result shares one tuple 2**depth times through the
    memo (``t = (t, t)``, ``depth`` times), handed to ``OrderedDict(...)``: printing or hashing
    it naively never ends."""
    return b"\x80\x02ccollections\nOrderedDict\n" + shared_tuple(depth) + b"\x85R."


def shared_tuple(depth: int) -> bytes:
    """Pushes ``t`` where ``t = (t, t)`` ``depth`` times over, in ~8 bytes a level."""
    body = b")q\x000"  # EMPTY_TUPLE, BINPUT 0, POP
    body += b"h\x00h\x00\x86q\x000" * depth  # BINGET 0 twice, TUPLE2, BINPUT 0, POP
    return body + b"h\x00"  # BINGET 0


def float_storage(numel: int) -> bytes:
    """``state_dict_with`` a float tensor of ``numel`` elements over storage ``"0"``."""
    return state_dict_with(tensor("FloatStorage", "0", numel, 0, (numel,), (1,)))


def sb3_zip(
    policy_pth: bytes, data: dict | bytes | None = None, compression: int = zipfile.ZIP_STORED
) -> bytes:
    """An SB3 model file around ``policy_pth``; ``data`` defaults to a DQN MlpPolicy's."""
    import json

    if not isinstance(data, bytes):
        data = json.dumps(
            data or {"policy_class": {"__module__": "stable_baselines3.dqn.policies"}}
        ).encode()
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=compression) as zf:
        zf.writestr("data", data)
        zf.writestr("policy.pth", policy_pth)
        zf.writestr("_stable_baselines3_version", "2.3.0")
    return buf.getvalue()


def npy(array: object) -> bytes:
    """``np.save`` bytes (pickle allowed, so object arrays can be crafted)."""
    import numpy as np

    buf = io.BytesIO()
    np.save(buf, array, allow_pickle=True)
    return buf.getvalue()


def zip_of(members: dict[str, bytes], compression: int = zipfile.ZIP_STORED) -> bytes:
    """A zip holding ``members``."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=compression) as zf:
        for name, raw in members.items():
            zf.writestr(name, raw)
    return buf.getvalue()


def palaestra_zip(arrays: dict[str, tuple[str, list[int], bytes]], kind: str = "model") -> bytes:
    """A palaestra archive: ``{name: (dtype, declared shape, member bytes)}``, deflated (so a
    member of zeros is a deflate bomb: 1 GB in ~1 MB)."""
    import json

    entries, members = {}, {}
    for i, (name, (dtype, shape, raw)) in enumerate(arrays.items()):
        members[f"arrays/{i:05d}.npy"] = raw
        entries[name] = {"file": f"arrays/{i:05d}.npy", "dtype": dtype, "shape": shape}
    manifest = {"format": "palaestra", "kind": kind, "version": 1, "meta": {}, "arrays": entries}
    members["palaestra.json"] = json.dumps(manifest).encode()
    return zip_of(members, zipfile.ZIP_DEFLATED)


def npy_header(dtype: str, shape: tuple[int, ...]) -> bytes:
    """The ``.npy`` header alone, for members whose data is streamed or missing."""
    import numpy as np

    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buf, {"descr": dtype, "fortran_order": False, "shape": shape}
    )
    return buf.getvalue()


def forge_size(data: bytes, member: str, file_size: int) -> bytes:
    """``data`` (a zip) with ``member``'s declared uncompressed size replaced in both the local
    header and the central directory: a header that lies about what it holds."""
    import struct

    out = bytearray(data)
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        info = zf.getinfo(member)
    local = info.header_offset
    struct.pack_into("<I", out, local + 22, file_size)
    central = out.find(b"PK\x01\x02")
    while central >= 0:
        name_len = struct.unpack_from("<H", out, central + 28)[0]
        if out[central + 46 : central + 46 + name_len] == member.encode():
            struct.pack_into("<I", out, central + 24, file_size)
        central = out.find(b"PK\x01\x02", central + 4)
    return bytes(out)


def deflated_zeros(header: bytes, n_mib: int) -> tuple[bytes, int, int]:
    """``(raw deflate stream, size, crc32)`` of ``header`` then ``n_mib`` MiB of zeros, built
    from one compressed MiB repeated (full flushes make the blocks independent): a 512 MiB
    member in ~520 KB, made in a fraction of a second."""
    import zlib

    first = zlib.compressobj(9, zlib.DEFLATED, -15)
    head = first.compress(header) + first.flush(zlib.Z_FULL_FLUSH)
    zeros = zlib.compressobj(9, zlib.DEFLATED, -15)
    block = zeros.compress(bytes(1 << 20)) + zeros.flush(zlib.Z_FULL_FLUSH)
    crc = zlib.crc32(header)
    chunk = bytes(1 << 20)
    for _ in range(n_mib):
        crc = zlib.crc32(chunk, crc)
    return head + block * n_mib + zeros.flush(), len(header) + (n_mib << 20), crc


def with_deflated_member(data: bytes, member: str, stream: tuple[bytes, int, int]) -> bytes:
    """``data`` (a zip) with ``member`` replaced by a ready-made deflate ``stream`` (from
    ``deflated_zeros``): written stored, then its headers say deflated, its size and CRC."""
    import struct

    raw, size, crc = stream
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
        methods = {i.filename: i.compress_type for i in zf.infolist()}
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name, content in members.items():
            if name == member:
                zf.writestr(name, raw, compress_type=zipfile.ZIP_STORED)
            else:
                zf.writestr(name, content, compress_type=methods[name])
    out = bytearray(buf.getvalue())
    with zipfile.ZipFile(io.BytesIO(bytes(out))) as zf:
        offset = zf.getinfo(member).header_offset
    struct.pack_into("<H", out, offset + 8, zipfile.ZIP_DEFLATED)
    struct.pack_into("<I", out, offset + 14, crc)
    struct.pack_into("<I", out, offset + 22, size)
    central = out.find(b"PK\x01\x02")
    while central >= 0:
        name_len = struct.unpack_from("<H", out, central + 28)[0]
        if out[central + 46 : central + 46 + name_len] == member.encode():
            struct.pack_into("<H", out, central + 10, zipfile.ZIP_DEFLATED)
            struct.pack_into("<I", out, central + 16, crc)
            struct.pack_into("<I", out, central + 24, size)
        central = out.find(b"PK\x01\x02", central + 4)
    return bytes(out)
