"""Model archives: round trip, and a clear ModelFileError for every kind of bad file."""

import io
import os
import pickle
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from tests.compat.crafted import forge_size, npy_header, palaestra_zip, zip_of

from palaestra.algos.common.model_io import (
    ArraySpec,
    ModelFileError,
    decode_classes,
    encode_classes,
    read_archive,
    read_arrays,
    read_manifest,
    write_archive,
)


def _archive(tmp_path: Path) -> Path:
    write_archive(
        tmp_path / "m",
        "model",
        {"algo": "DQN"},
        {"w": np.arange(6, dtype=np.float32).reshape(2, 3)},
    )
    return tmp_path / "m.zip"


def test_roundtrip_and_sb3_naming(tmp_path: Path) -> None:
    path = _archive(tmp_path)
    assert path.exists()
    meta, arrays = read_archive(tmp_path / "m", "model")  # ".zip" found as SB3 does
    assert meta == {"algo": "DQN"} and arrays["w"].shape == (2, 3)
    with pytest.raises(FileNotFoundError):
        read_archive(tmp_path / "nope", "model")


def test_wrong_kind_and_version(tmp_path: Path) -> None:
    path = _archive(tmp_path)
    with pytest.raises(ModelFileError, match="not a replay_buffer"):
        read_archive(path, "replay_buffer")
    with zipfile.ZipFile(path) as zf:
        manifest = zf.read("palaestra.json").replace(b'"version": 1', b'"version": 99')
        arrays = {n: zf.read(n) for n in zf.namelist() if n != "palaestra.json"}
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("palaestra.json", manifest)
        for n, b in arrays.items():
            zf.writestr(n, b)
    with pytest.raises(ModelFileError, match="version 99"):
        read_archive(path, "model")


@pytest.mark.parametrize("cut", [10, 200, -30])
def test_truncated_and_corrupt(tmp_path: Path, cut: int) -> None:
    data = _archive(tmp_path).read_bytes()
    bad = tmp_path / "bad.zip"
    bad.write_bytes(data[:cut])
    with pytest.raises(ModelFileError):
        read_archive(bad, "model")
    flipped = bytearray(data)
    flipped[60] ^= 0xFF  # inside the first member's compressed bytes
    bad.write_bytes(bytes(flipped))
    with pytest.raises(ModelFileError):
        read_archive(bad, "model")


def test_foreign_files(tmp_path: Path) -> None:
    text = tmp_path / "notes.txt"
    text.write_text("hello")
    with pytest.raises(ModelFileError, match="corrupt or not a palaestra"):
        read_archive(text, "model")
    other = tmp_path / "other.zip"
    with zipfile.ZipFile(other, "w") as zf:
        zf.writestr("readme.md", "hi")
    with pytest.raises(ModelFileError, match="not a palaestra model"):
        read_archive(other, "model")


class _RunsCode:
    def __reduce__(self):  # type: ignore[no-untyped-def]
        return (exec, ("import os; os.environ['PALAESTRA_PWNED'] = '1'",))


def test_malicious_files_never_run_code(tmp_path: Path) -> None:
    payload = pickle.dumps(_RunsCode())
    # 1. An SB3-style file whose "data"/"policy.pth" are pickles.
    sb3 = tmp_path / "sb3.zip"
    with zipfile.ZipFile(sb3, "w") as zf:
        zf.writestr("data", payload)
        zf.writestr("policy.pth", payload)
    with pytest.raises(ModelFileError, match="Stable-Baselines3"):
        read_archive(sb3, "model")
    # 2. Our own layout with a pickled object array in place of a tensor.
    buf = io.BytesIO()
    np.save(buf, np.array([_RunsCode()], dtype=object), allow_pickle=True)
    evil = tmp_path / "evil.zip"
    with zipfile.ZipFile(evil, "w") as zf:
        zf.writestr("arrays/00000.npy", buf.getvalue())
        zf.writestr(
            "palaestra.json",
            '{"format": "palaestra", "kind": "model", "version": 1, '
            '"meta": {}, "arrays": {"w": {"file": "arrays/00000.npy", '
            '"dtype": "<f4", "shape": [1]}}}',
        )
    with pytest.raises(ModelFileError):
        read_archive(evil, "model")
    # 3. A manifest naming a class outside torch.nn / torch.optim / palaestra.algos.
    with pytest.raises(ModelFileError, match="will not import"):
        decode_classes({"activation_fn": {"__class__": "os:system"}}, {})
    with pytest.raises(ModelFileError, match="not a Module"):
        decode_classes({"activation_fn": {"__class__": "torch.nn:functional"}}, {})
    assert "PALAESTRA_PWNED" not in os.environ
    pickle.loads(payload)  # the payload is live: loading it the SB3 way would have run it
    assert os.environ.pop("PALAESTRA_PWNED") == "1"


def test_oversized_member_rejected(tmp_path: Path) -> None:
    buf = io.BytesIO()
    np.save(buf, np.zeros(100_000, dtype=np.float32))
    bomb = tmp_path / "bomb.zip"
    with zipfile.ZipFile(bomb, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("arrays/0.npy", buf.getvalue())
        zf.writestr(
            "palaestra.json",
            '{"format": "palaestra", "kind": "model", "version": 1, '
            '"meta": {}, "arrays": {"w": {"file": "arrays/0.npy", "dtype": "<f4", "shape": [2]}}}',
        )
    with pytest.raises(ModelFileError, match=r"'arrays/0.npy' holds 400128 bytes, its declared"):
        read_archive(bomb, "model")


def test_class_codec() -> None:
    kwargs = {
        "activation_fn": torch.nn.ReLU,
        "optimizer_class": torch.optim.RMSprop,
        "net_arch": [32],
    }
    assert decode_classes(encode_classes(kwargs), {}) == kwargs

    class Custom(torch.nn.Module):
        pass

    enc = encode_classes({"activation_fn": Custom})
    with pytest.raises(ModelFileError, match="custom_objects"):
        decode_classes(enc, {})
    assert decode_classes(enc, {"Custom": Custom}) == {"activation_fn": Custom}


# -- bounded reading: declared sizes are checked before anything is allocated -------------------
GIB = 1 << 30


def _bomb(tmp_path: Path, shape: list[int], kind: str = "model") -> Path:
    """A deflated member of zeros as large as ``shape`` declares (1 GiB in ~1 MB)."""
    nbytes = int(np.prod(shape)) * 4
    raw = npy_header("<f4", tuple(shape)) + bytes(nbytes)
    path = tmp_path / "bomb.zip"
    path.write_bytes(palaestra_zip({"policy/w": ("<f4", shape, raw)}, kind))
    return path


def test_declared_arrays_pass_expect_before_any_is_read(tmp_path: Path) -> None:
    path = _bomb(tmp_path, [1 << 20])  # 4 MiB of zeros in ~4 KB
    seen: list[Any] = []

    def expect(meta: dict[str, Any], declared: dict[str, ArraySpec]) -> None:
        seen.append(declared)
        raise ModelFileError("not this one")

    with pytest.raises(ModelFileError, match="not this one"):
        read_archive(path, "model", expect=expect)
    assert seen == [{"policy/w": ArraySpec(np.dtype("<f4"), (1 << 20,))}]
    manifest = read_manifest(path, "model")  # the two-step form: nothing read yet
    assert manifest.declared["policy/w"].nbytes == 4 << 20
    assert read_arrays(manifest)["policy/w"].shape == (1 << 20,)


def test_total_size_is_capped(tmp_path: Path) -> None:
    path = _bomb(tmp_path, [1 << 20], kind="replay_buffer")
    with pytest.raises(ModelFileError, match=r"declare 4194304 bytes in all, more than the limit "
                       r"max_bytes=1000000 \(pass a larger max_bytes"):  # fmt: skip
        read_archive(path, "replay_buffer", max_bytes=1_000_000)
    assert read_archive(path, "replay_buffer")[1]["policy/w"].shape == (1 << 20,)


def test_a_declared_shape_the_member_cannot_hold(tmp_path: Path) -> None:
    path = tmp_path / "huge.zip"
    raw = npy_header("<f4", (GIB,)) + bytes(64)  # declares 4 GiB, holds 64 bytes
    path.write_bytes(palaestra_zip({"w": ("<f4", [GIB], raw)}))
    with pytest.raises(ModelFileError, match=r"member 'arrays/00000.npy' holds \d+ bytes, its "
                       r"declared float32 \(1073741824,\) needs 4294967296"):  # fmt: skip
        read_archive(path, "model")


def test_zip_headers_that_lie_are_refused(tmp_path: Path) -> None:
    # A member whose header claims more than deflate can expand its stored bytes into.
    path = tmp_path / "forged.zip"
    raw = npy_header("<f4", (4,)) + bytes(16)
    data = palaestra_zip({"w": ("<f4", [GIB], raw)})
    path.write_bytes(forge_size(data, "arrays/00000.npy", 4 * GIB - 1))
    with pytest.raises(ModelFileError, match=r"'arrays/00000.npy' declares 4294967295 bytes, "
                       r"more than its \d+ stored bytes can hold \(a zip bomb"):  # fmt: skip
        read_archive(path, "model")
    # A header that understates its member: the bounded read stops, the CRC check fails.
    path.write_bytes(forge_size(palaestra_zip({"w": ("<f4", [4], raw)}), "arrays/00000.npy", 140))
    with pytest.raises(ModelFileError, match=r"corrupt .*Bad CRC-32 for file 'arrays/00000.npy'"):
        read_archive(path, "model")


def test_compression_other_than_deflate_and_duplicates_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "bz.zip"
    path.write_bytes(zip_of({"palaestra.json": b"{}"}, zipfile.ZIP_BZIP2))
    with pytest.raises(ModelFileError, match="compression method 12; only stored and deflate"):
        read_archive(path, "model")
    with zipfile.ZipFile(path, "w") as zf, pytest.warns(UserWarning, match="Duplicate name"):
        zf.writestr("palaestra.json", "{}")
        zf.writestr("palaestra.json", "{}")
    with pytest.raises(ModelFileError, match=r"member 'palaestra\.json' appears twice"):
        read_archive(path, "model")


def test_written_atomically_over_the_previous_file(tmp_path: Path) -> None:
    path = _archive(tmp_path)
    before = path.read_bytes()
    with pytest.raises(TypeError, match="cannot store"):
        write_archive(path, "model", {}, {"w": np.array(["text"])})
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.zip"]  # no temporary file left


def test_zero_dimensional_arrays_keep_their_shape(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # np.ascontiguousarray turns 0-d arrays into (1,): a 0-d statistic or step count must
    # come back as saved, or a restored run state no longer fits its object.
    write_archive(tmp_path / "a.zip", "model", {}, {"s": np.array(2.5), "f": np.ones((3, 2)).T})
    _, arrays = read_archive(tmp_path / "a.zip", "model")
    assert arrays["s"].shape == () and float(arrays["s"]) == 2.5
    assert arrays["f"].shape == (2, 3) and arrays["f"].flags.c_contiguous
