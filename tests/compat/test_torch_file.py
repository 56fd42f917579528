"""The safe ``torch.save`` reader: same arrays as ``torch.load(weights_only=True)``, and every
file that names code is refused without running it."""

from __future__ import annotations

import io
import struct
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch
from tests.compat.crafted import (
    call_global,
    call_stack_global,
    float_storage,
    memo_bomb,
    payload,
    shared_tuple,
    state_dict_with,
    tensor,
    text,
    torch_zip,
)

from palaestra.compat import UnsafeFileError, read_torch_state_dict
from palaestra.compat.torch_file import TorchFileError


def saved(obj: object) -> bytes:
    buf = io.BytesIO()
    torch.save(obj, buf)
    return buf.getvalue()


def test_reads_what_torch_load_reads() -> None:
    base = torch.arange(24, dtype=torch.float64).reshape(4, 6)
    state = {
        "linear.weight": torch.randn(3, 5),
        "transposed": base.t(),  # strided view
        "slice": base[1:3, 2:],  # offset into a shared storage
        "int32": torch.tensor([1, -2, 3], dtype=torch.int32),
        "int64": torch.tensor([2**40, -1]),
        "uint8": torch.arange(5, dtype=torch.uint8),
        "int8": torch.tensor([-3], dtype=torch.int8),
        "int16": torch.tensor([300], dtype=torch.int16),
        "bool": torch.tensor([True, False]),
        "half": torch.ones(2, dtype=torch.float16),
        "scalar": torch.tensor(3.5),
        "empty": torch.zeros(0, 3),
        "param": torch.nn.Parameter(torch.ones(2)),
    }
    raw = saved(torch.nn.Module.state_dict(torch.nn.Linear(2, 2)) | state)
    ours = read_torch_state_dict(raw)
    reference = torch.load(io.BytesIO(raw), weights_only=True)
    assert list(ours) == list(reference)
    for key, value in reference.items():
        expected = value.detach().numpy()
        assert ours[key].dtype == expected.dtype and ours[key].shape == expected.shape, key
        np.testing.assert_array_equal(ours[key], expected)
    ours["transposed"][0, 0] = -1  # copies: tensors sharing a storage do not alias
    assert ours["slice"].min() >= 0


def test_reads_a_path(tmp_path: Path) -> None:
    torch.save({"a": torch.ones(2)}, tmp_path / "w.pth")
    np.testing.assert_array_equal(read_torch_state_dict(tmp_path / "w.pth")["a"], [1.0, 1.0])
    with pytest.raises(FileNotFoundError, match=r"no torch file at .*missing.pth"):
        read_torch_state_dict(tmp_path / "missing.pth")


def test_hand_written_state_dict_is_read() -> None:
    raw = torch_zip(
        state_dict_with(tensor("FloatStorage", "0", 4, 1, (3,), (1,))),
        {"0": struct.pack("<4f", 1, 2, 3, 4)},
    )
    np.testing.assert_array_equal(read_torch_state_dict(raw)["w"], [2, 3, 4])


MALICIOUS = {
    "os.system": lambda m: payload(call_global("os", "system", f"touch {m}")),
    "posix.system": lambda m: payload(call_global("posix", "system", f"touch {m}")),
    "builtins.exec": lambda m: payload(call_global("builtins", "exec", f"open(r'{m}', 'w')")),
    "stack_global": lambda m: b"\x80\x04" + call_stack_global("os", "system", f"touch {m}") + b".",
    "inside_state_dict": lambda m: state_dict_with(call_global("os", "system", f"touch {m}")),
    "torch_lookalike": lambda m: payload(call_global("torch.serialization", "load", str(m))),
}


@pytest.mark.parametrize("name", list(MALICIOUS))
def test_code_in_the_pickle_is_refused_and_not_run(name: str, tmp_path: Path) -> None:
    marker = tmp_path / "payload_ran"
    raw = torch_zip(MALICIOUS[name](marker))
    with pytest.raises(UnsafeFileError, match=r"which a tensor state_dict never does; refusing"):
        read_torch_state_dict(raw)
    assert not marker.exists()


def test_the_payload_is_live_when_unpickled(tmp_path: Path) -> None:
    # Control for the test above: the same bytes, unpickled the usual way (in a child process),
    # do create the marker, so "not created" above means "refused", not "harmless payload".
    marker = tmp_path / "payload_ran"
    stream = tmp_path / "stream.pkl"
    stream.write_bytes(MALICIOUS["os.system"](marker))
    unpickle = "import pickle, sys; pickle.loads(open(sys.argv[1], 'rb').read())"
    subprocess.run([sys.executable, "-c", unpickle, str(stream)], check=True)
    assert marker.exists()


@pytest.mark.parametrize(
    ("stream", "message"),
    [
        (payload(b"(" + text("x") + b"i__main__\nX\n"), r"opcode INST, which a tensor state"),
        (payload(b"ccollections\nOrderedDict\n)\x81"), r"opcode NEWOBJ, which a tensor state"),
        (payload(b"ctorch\nFloatStorage\n" + text("x") + b"\x85R"), r"unexpected call torch.Float"),
        (payload(b"ccollections\nOrderedDict\n" + text("x") + b"\x85R"), r"unexpected call"),
        (payload(b"(" + text("storage") + b"tQ"), r"unexpected persistent id"),
        (payload(text("not a dict")), r"holds a str, not a tensor state_dict"),
        (b"\x80\x02}", r"malformed pickle stream .*exhausted before seeing STOP"),
        (b"\x80\x02h\x05.", r"malformed pickle stream"),
    ],
)
def test_other_bad_streams_say_what_is_wrong(stream: bytes, message: str) -> None:
    with pytest.raises(TorchFileError, match=message):
        read_torch_state_dict(torch_zip(stream))


@pytest.mark.parametrize(
    ("value", "storages", "message"),
    [
        (tensor("FloatStorage", "0", 4, 2, (3,), (1,)), {"0": bytes(16)}, r"reads past its"),
        (tensor("FloatStorage", "0", 4, 0, (2,), (1,)), {}, r"storage '0' is missing"),
        (tensor("FloatStorage", "../x", 1, 0, (1,), (1,)), {}, r"storage '../x' is missing"),
        (tensor("FloatStorage", "0", 8, 0, (2,), (1,)), {"0": bytes(16)}, r"fewer than its 8"),
        (tensor("FloatStorage", "0", 4, -1, (2,), (1,)), {"0": bytes(16)}, r"malformed tensor"),
    ],
)
def test_bad_tensors_are_refused(value: bytes, storages: dict, message: str) -> None:
    with pytest.raises(TorchFileError, match=message):
        read_torch_state_dict(torch_zip(state_dict_with(value), storages))


def test_files_that_are_not_zip_torch_files() -> None:
    with pytest.raises(TorchFileError, match=r"not a zip-format torch file .*legacy format"):
        read_torch_state_dict(b"\x80\x02}q\x00.")
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("readme.txt", "hi")
    with pytest.raises(TorchFileError, match=r"is a zip but not a torch file"):
        read_torch_state_dict(buf.getvalue())


# -- bounded reading -----------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("value", "storages", "message"),
    [
        # 11 bytes of storage, a (50000, 50000) float view: 10 GB if copied.
        (tensor("FloatStorage", "0", 1, 0, (50000, 50000), (0, 0)), {"0": bytes(4)},
         r"tensor of size \(50000, 50000\) has stride 0 \(a broadcast view"),
        (tensor("FloatStorage", "0", 4, 0, (3, 2), (1, 1)), {"0": bytes(16)},
         r"stride \(1, 1\) has overlapping dimensions"),
        (tensor("FloatStorage", "0", 2**30, 0, (2,), (1,)), {"0": bytes(16)},
         r"storage '0' \(member 'archive/data/0'\) holds 16 bytes, fewer than its 1073741824"),
        (tensor("FloatStorage", "0", 4, 0, (2,), (-1,)), {"0": bytes(16)}, r"malformed tensor"),
    ],
)  # fmt: skip
def test_views_and_storages_that_would_allocate_are_refused(
    value: bytes, storages: dict, message: str
) -> None:
    with pytest.raises(TorchFileError, match=message):
        read_torch_state_dict(torch_zip(state_dict_with(value), storages))


def test_storage_budget_and_view_copies_are_capped() -> None:
    raw = torch_zip(float_storage(1 << 18), {"0": bytes(1 << 20)})
    assert read_torch_state_dict(raw)["w"].shape == (1 << 18,)
    with pytest.raises(TorchFileError, match=r"past 1048576 bytes, more than the limit "
                       r"max_bytes=1000000"):  # fmt: skip
        read_torch_state_dict(raw, max_bytes=1_000_000)
    # 64 keys viewing one 256 KiB storage: 16 MiB of copies from a ~2 KB pickle.
    views = b"".join(
        text(f"w{i}") + tensor("FloatStorage", "0", 1 << 16, 0, (1 << 16,), (1,)) for i in range(64)
    )
    stream = b"\x80\x02ccollections\nOrderedDict\n)R(" + views + b"u."
    with pytest.raises(TorchFileError, match=r"its tensors copy \d+ bytes out of 262144 bytes "
                       r"of storage, more than the limit of 4x"):  # fmt: skip
        read_torch_state_dict(torch_zip(stream, {"0": bytes(1 << 18)}))


def test_a_memo_bomb_is_refused_at_once_with_a_short_message() -> None:
    import time

    start = time.process_time()
    with pytest.raises(TorchFileError, match=r"unexpected call collections.OrderedDict") as info:
        read_torch_state_dict(torch_zip(memo_bomb(80)))  # 2**80 nodes if walked
    assert time.process_time() - start < 0.5
    assert len(str(info.value)) < 400
    key_bomb = b"\x80\x02}" + shared_tuple(80) + b"K\x01s."  # {t: 1}
    with pytest.raises(TorchFileError, match=r"a dict key is a tuple, not a name"):
        read_torch_state_dict(torch_zip(key_bomb))  # hashing that key never ends


def test_a_storage_in_a_bzip2_member_is_refused() -> None:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("archive/data.pkl", float_storage(4))
        zf.writestr("archive/data/0", bytes(16), compress_type=zipfile.ZIP_BZIP2)
    with pytest.raises(TorchFileError, match=r"'archive/data/0' uses zip compression method 12"):
        read_torch_state_dict(buf.getvalue())
