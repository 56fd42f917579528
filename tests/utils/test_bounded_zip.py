"""Crafted files that declare far more than they hold are refused before anything is allocated:
every loader runs in a child process whose address space is capped at what it uses plus
300 MB, and each crafted file declares 512 MiB (a real deflate bomb: ~520 KB on disk) or more."""

from __future__ import annotations

import io
import json
import os
import re
import subprocess
import sys
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.compat.crafted import (
    deflated_zeros,
    float_storage,
    forge_size,
    memo_bomb,
    npy_header,
    palaestra_zip,
    sb3_zip,
    state_dict_with,
    tensor,
    torch_zip,
    with_deflated_member,
    zip_of,
)

from palaestra.utils.bounded_zip import ModelFileError, check_members, summary

HEADROOM = 300 << 20  # address space the child may still take after its warm-up
BOMB_MIB = 512

# Runs in the child: warm up every loader it will use on a good file (imports, torch's thread
# pools), cap the address space, then load each crafted file and report what happened.
CHILD = r"""
import json, resource, sys, time

cases, good = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))


def call(kind, path, kwargs):
    if kind == "ppo_load":
        from palaestra.algos import PPO
        return PPO.load(path, **kwargs)
    if kind == "read_archive":
        from palaestra.algos.common.model_io import read_archive
        return read_archive(path, **kwargs)
    if kind == "from_sb3":
        from palaestra.compat import from_sb3
        return from_sb3(path, **kwargs)
    if kind == "read_torch_state_dict":
        from palaestra.compat.torch_file import read_torch_state_dict
        return read_torch_state_dict(path, **kwargs)
    from palaestra.vec_env import VecNormalize, make_vec_env
    return VecNormalize.load(path, make_vec_env("MountainCar-v0", n_envs=1))


for kind, path in good.items():
    call(kind, path, {})
size = next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmSize:"))
limit = size * 1024 + int(sys.argv[3])
resource.setrlimit(resource.RLIMIT_AS, (limit, resource.getrlimit(resource.RLIMIT_AS)[1]))
report = {}
for name, case in cases.items():
    start = time.process_time()
    try:
        call(case["call"], case["path"], case["kwargs"])
        outcome = ("no error", "")
    except MemoryError as exc:
        outcome = ("MemoryError", str(exc))
    except Exception as exc:
        outcome = (type(exc).__name__, str(exc))
    report[name] = [*outcome, time.process_time() - start]
print(json.dumps({"report": report, "torch": "torch" in sys.modules}))
"""


def _run_child(folder: Path, crafted: dict[str, Any], good: dict[str, Path]) -> dict[str, Any]:
    """Load each crafted file in a child under RLIMIT_AS; check type, message and time."""
    cases = {}
    for name, (call, kwargs, raw, _message) in crafted.items():
        path = folder / f"{name}.zip"
        path.write_bytes(raw)
        assert path.stat().st_size < 1 << 20, name  # each under 1 MB on disk
        cases[name] = {"call": call, "path": str(path), "kwargs": kwargs}
    (folder / "cases.json").write_text(json.dumps(cases))
    (folder / "good.json").write_text(json.dumps({k: str(v) for k, v in good.items()}))
    src = str(Path(__file__).resolve().parents[2] / "src")
    child = subprocess.run(
        [sys.executable, "-c", CHILD, folder / "cases.json", folder / "good.json",
         str(HEADROOM)],
        capture_output=True, text=True, timeout=300, env={**os.environ, "PYTHONPATH": src},
    )  # fmt: skip
    assert child.returncode == 0, child.stderr[-3000:]
    result = json.loads(child.stdout.strip().splitlines()[-1])
    for name, (_, _, _, message) in crafted.items():
        kind, text, seconds = result["report"][name]
        assert kind in ("ModelFileError", "TorchFileError"), (name, kind, text[:300])
        assert re.search(message, text), (name, text[:300])
        assert seconds < 0.5, (name, seconds)  # CPU seconds: load stretches wall time, not these
    return result


def _edit_archive(src: Path, name: str, shape: tuple[int, ...]) -> tuple[bytes, str]:
    """A copy of the archive ``src`` whose manifest declares ``shape`` for array ``name``;
    returns the bytes and the member that must then hold that much."""
    with zipfile.ZipFile(src) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    manifest = json.loads(members["palaestra.json"])
    manifest["arrays"][name]["shape"] = list(shape)
    members["palaestra.json"] = json.dumps(manifest).encode()
    return zip_of(members, zipfile.ZIP_DEFLATED), manifest["arrays"][name]["file"]


def _bomb(dtype: str, n_mib: int = BOMB_MIB) -> tuple[bytes, int, int]:
    """A deflate stream of a .npy member of ``n_mib`` MiB of zeros (~1 KB a MiB)."""
    itemsize = np.dtype(dtype).itemsize
    return deflated_zeros(npy_header(dtype, ((n_mib << 20) // itemsize,)), n_mib)


def _normalize_files(folder: Path) -> tuple[Path, dict[str, bytes]]:
    from palaestra.vec_env import VecNormalize, make_vec_env

    path = folder / "good.npz"
    VecNormalize(make_vec_env("MountainCar-v0", n_envs=1)).save(path)
    with zipfile.ZipFile(path) as zf:
        return path, {n: zf.read(n) for n in zf.namelist()}


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS and /proc/self/status: Linux")
def test_crafted_files_are_refused_in_bounded_memory(tmp_path: Path) -> None:
    """The fast half: loaders that need no torch (VecNormalize, the torch-file reader)."""
    good_stats, stats = _normalize_files(tmp_path)
    good_torch = tmp_path / "good.pth"
    good_torch.write_bytes(torch_zip(float_storage(4), {"0": bytes(16)}))
    stride0 = state_dict_with(tensor("FloatStorage", "0", 1, 0, (50000, 50000), (0, 0)))
    crafted = {
        "normalize_bomb": ("vecnormalize_load", {},
                           with_deflated_member(zip_of(stats), "obs_var.npy", _bomb("<f8")),
                           r"member 'obs_var.npy' declares 536870912 bytes of data \(shape "
                           r"\(67108864,\)\), more than the limit of 65552"),
        "normalize_forged": ("vecnormalize_load", {},
                             forge_size(zip_of(stats), "obs_var.npy", 4_000_000_000),
                             r"member 'obs_var.npy' declares 4000000000 bytes, more than its "
                             r"\d+ stored bytes can hold"),
        "torch_storage": ("read_torch_state_dict", {},
                          torch_zip(float_storage(1 << 30), {"0": bytes(64)}),
                          r"storage '0' \(member 'archive/data/0'\) holds 64 bytes, fewer "
                          r"than its 1073741824 elements need"),
        "torch_stride0": ("read_torch_state_dict", {}, torch_zip(stride0, {"0": bytes(4)}),
                          r"has stride 0"),
        "torch_memo_bomb": ("read_torch_state_dict", {}, torch_zip(memo_bomb(60)),
                            r"unexpected call collections.OrderedDict\(\(<tuple"),
        "torch_storage_bomb": ("read_torch_state_dict", {"max_bytes": 100 << 20},
                               with_deflated_member(torch_zip(float_storage(1 << 27), {"0": b""}),
                                                    "archive/data/0", deflated_zeros(b"", 512)),
                               r"would take the storages past 536870912 bytes, more than the "
                               r"limit max_bytes=104857600"),
    }  # fmt: skip
    good = {"vecnormalize_load": good_stats, "read_torch_state_dict": good_torch}
    assert not _run_child(tmp_path, crafted, good)["torch"]  # fast: no torch in the child


@pytest.mark.slow
@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS and /proc/self/status: Linux")
def test_crafted_model_files_are_refused_in_bounded_memory(tmp_path: Path) -> None:
    """The half that imports torch (~7 s here): palaestra models, replay buffers, SB3 files."""
    from palaestra.algos import PPO

    good_model = tmp_path / "good.zip"
    PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=16, seed=0).save(good_model)
    # The first layer declares (128, 2**20) float32 and holds that many zeros.
    data, member = _edit_archive(good_model, "policy/pi_net.0.weight", (128, 1 << 20))
    buffer = palaestra_zip({"observations": ("<f4", [BOMB_MIB << 18], b"")}, "replay_buffer")
    stride0 = state_dict_with(tensor("FloatStorage", "0", 1, 0, (50000, 50000), (0, 0)))
    crafted = {
        "model_bomb": ("ppo_load", {},
                       with_deflated_member(data, member, deflated_zeros(
                           npy_header("<f4", (128, 1 << 20)), BOMB_MIB)),
                       r"parameter 'pi_net.0.weight' has shape \(128, 1048576\), this model "
                       r"expects \(64, 4\)"),
        "model_forged": ("ppo_load", {}, forge_size(data, member, 4_000_000_000),
                         r"member 'arrays/\d+.npy' declares 4000000000 bytes, more than its "
                         r"\d+ stored bytes can hold"),
        "buffer_bomb": ("read_archive", {"kind": "replay_buffer", "max_bytes": 100 << 20},
                        with_deflated_member(buffer, "arrays/00000.npy", _bomb("<f4")),
                        r"declare 536870912 bytes in all, more than the limit "
                        r"max_bytes=104857600"),
        "sb3_storage": ("from_sb3", {}, sb3_zip(torch_zip(float_storage(1 << 30),
                                                          {"0": bytes(64)})),
                        r"holds 64 bytes, fewer than its 1073741824 elements need"),
        "sb3_stride0": ("from_sb3", {}, sb3_zip(torch_zip(stride0, {"0": bytes(4)})),
                        r"has stride 0"),
        "sb3_memo_bomb": ("from_sb3", {}, sb3_zip(torch_zip(memo_bomb(60))),
                          r"unexpected call collections.OrderedDict\(\(<tuple"),
    }  # fmt: skip
    assert _run_child(tmp_path, crafted, {"ppo_load": good_model})["torch"]


def test_check_members_and_summary() -> None:
    bomb = with_deflated_member(
        zip_of({"a": b""}), "a", deflated_zeros(b"", 4)
    )  # 4 MiB in ~4 KB: within deflate's ratio, so accepted here

    with zipfile.ZipFile(io.BytesIO(bomb)) as zf:
        assert check_members(zf, "f")["a"].file_size == 4 << 20
    with zipfile.ZipFile(io.BytesIO(forge_size(bomb, "a", 1 << 31))) as zf:
        with pytest.raises(ModelFileError, match=r"f: member 'a' declares 2147483648 bytes"):
            check_members(zf, "f")
    deep: Any = []
    for _ in range(10_000):
        deep = [deep, deep]  # 2**10000 leaves, shared
    assert summary(deep) == "[[<list of 2>, <list of 2>], [<list of 2>, <list of 2>]]"
    assert summary(np.zeros((3, 2))) == "<array float64 (3, 2)>"
