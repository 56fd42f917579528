"""Model archives: round trip, and a clear ModelFileError for every kind of bad file."""

import io
import os
import pickle
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch

from palaestra.algos.model_io import (
    ModelFileError,
    decode_classes,
    encode_classes,
    read_archive,
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
