"""The SB3-file reader in bounded memory: crafted ``policy.pth`` storages and views, bombs and
oversized members are refused before they are allocated, with the member and the limit named."""

from __future__ import annotations

import io
import time
import zipfile
from pathlib import Path

import pytest
from tests.compat.crafted import (
    float_storage,
    forge_size,
    memo_bomb,
    sb3_zip,
    state_dict_with,
    tensor,
    torch_zip,
)

from palaestra.compat import from_sb3
from palaestra.compat.sb3_file import read_sb3_file
from palaestra.compat.torch_file import TorchFileError
from palaestra.utils.bounded_zip import ModelFileError


def _file(tmp_path: Path, raw: bytes) -> Path:
    path = tmp_path / "sb3.zip"
    path.write_bytes(raw)
    return path


@pytest.mark.parametrize(
    ("policy", "message"),
    [
        (torch_zip(float_storage(1 << 30), {"0": bytes(64)}),
         r"storage '0' \(member 'archive/data/0'\) holds 64 bytes, fewer than its 1073741824"),
        (torch_zip(state_dict_with(tensor("FloatStorage", "0", 1, 0, (50000, 50000), (0, 0))),
                   {"0": bytes(4)}), r"has stride 0"),
        (torch_zip(memo_bomb(60)), r"unexpected call collections.OrderedDict\(\(<tuple of 2>"),
    ],
    ids=["huge_storage", "stride_0", "memo_bomb"],
)  # fmt: skip
def test_crafted_policy_files_are_refused_at_once(
    tmp_path: Path, policy: bytes, message: str
) -> None:
    path = _file(tmp_path, sb3_zip(policy))
    assert path.stat().st_size < 4096
    start = time.process_time()
    with pytest.raises(TorchFileError, match=message):
        from_sb3(path)
    assert time.process_time() - start < 0.5


def test_a_nested_deflate_bomb_stops_at_max_bytes(tmp_path: Path) -> None:
    # 16 MiB of zeros deflated inside a deflated policy.pth: ~20 KB on disk. Two layers of
    # deflate multiply to a million-fold, so the limit, not the ratio check, stops it.
    inner = io.BytesIO()
    with zipfile.ZipFile(inner, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("archive/data.pkl", float_storage(1 << 22))
        zf.writestr("archive/data/0", bytes(4 << 22))
    path = _file(tmp_path, sb3_zip(inner.getvalue(), compression=zipfile.ZIP_DEFLATED))
    assert path.stat().st_size < 50_000
    with pytest.raises(TorchFileError, match=r"storage '0' \(member 'archive/data/0'\) would "
                       r"take the storages past 16777216 bytes, more than the limit "
                       r"max_bytes=10000000"):  # fmt: skip
        read_sb3_file(path, max_bytes=10_000_000)
    with pytest.raises(ModelFileError, match=r"member 'policy.pth' declares \d+ bytes, more "
                       r"than the limit of 1000 bytes"):  # fmt: skip
        read_sb3_file(path, max_bytes=1000)


def test_oversized_and_forged_members_are_refused(tmp_path: Path) -> None:
    raw = sb3_zip(torch_zip(float_storage(4), {"0": bytes(16)}))
    path = _file(tmp_path, forge_size(raw, "data", 4_000_000_000))
    with pytest.raises(ModelFileError, match=r"member 'data' declares 4000000000 bytes, more "
                       r"than its \d+ stored bytes can hold"):  # fmt: skip
        read_sb3_file(path)
    deep = b'{"a": ' * 100_000 + b"1" + b"}" * 100_000  # RecursionError in json
    with pytest.raises(ModelFileError, match=r"'data' is not valid JSON \(maximum recursion"):
        read_sb3_file(_file(tmp_path, sb3_zip(b"", deep)))
