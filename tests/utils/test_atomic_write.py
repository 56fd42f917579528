"""Files written whole or not at all, and line logs whose torn last line is skipped: unit
tests, and ``kill -9`` in the middle of saving a model, three times (the previous file loads)."""

from __future__ import annotations

import itertools
import multiprocessing
import os
import random
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from palaestra.algos.common.model_io import read_archive, write_archive
from palaestra.utils import atomic_write as atomic_write_module
from palaestra.utils.atomic_write import (
    atomic_path,
    atomic_write,
    complete_text,
    cut_torn_line,
    open_append,
)

TEMP = re.compile(r"^\.[^/]+\.[0-9a-f]{8}\.tmp$")  # .<name>.<random>.tmp: hidden, never loaded


def _names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_replaces_whole_with_the_usual_permissions(tmp_path: Path) -> None:
    target = tmp_path / "status.json"
    target.write_text("old")
    with atomic_write(target, "w", encoding="utf-8") as file:
        file.write("new")
        assert target.read_text() == "old"  # nothing visible until the block ends
        (temp,) = [n for n in _names(tmp_path) if n != "status.json"]
        assert TEMP.match(temp)
    assert target.read_text() == "new" and _names(tmp_path) == ["status.json"]
    umask = os.umask(0o022)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask  # not mkstemp's 0600


@pytest.mark.parametrize("error", [ValueError, KeyboardInterrupt])
def test_an_exception_keeps_the_old_file_and_leaves_no_temp(
    tmp_path: Path, error: type[BaseException]
) -> None:
    target = tmp_path / "model.zip"
    target.write_bytes(b"old")
    with pytest.raises(error), atomic_write(target) as file:
        file.write(b"half a model")
        raise error
    assert target.read_bytes() == b"old" and _names(tmp_path) == ["model.zip"]


def test_atomic_path_for_writers_that_need_a_name(tmp_path: Path) -> None:
    target = tmp_path / "video.mp4"
    with atomic_path(target, suffix=".tmp.mp4") as temp:
        assert temp.parent == tmp_path and temp.name.endswith(".tmp.mp4")
        temp.write_bytes(b"frames")
    assert target.read_bytes() == b"frames" and _names(tmp_path) == ["video.mp4"]
    with pytest.raises(ValueError, match="mode 'w' or 'wb', got 'a'"):
        with atomic_write(target, "a"):
            pass


def test_line_logs_survive_a_torn_last_line(tmp_path: Path) -> None:
    log = tmp_path / "episodes.csv"
    with open_append(log, "steps,return\r\n") as file:
        file.write("10,1.5\r\n")
    with open(log, "a", encoding="utf-8", newline="") as file:
        file.write("20,2.")  # a crash in the middle of a row
    assert complete_text(log) == "steps,return\r\n10,1.5\r\n"
    with open_append(log, "steps,return\r\n") as file:  # resuming cuts the torn row
        file.write("30,3.0\r\n")
    assert log.read_bytes() == b"steps,return\r\n10,1.5\r\n30,3.0\r\n"
    log.write_bytes(b"no newline at all")
    cut_torn_line(log)
    assert log.read_bytes() == b""


# -- kill -9 in the middle of a save -------------------------------------------------------------
def _save_forever(path: str, nbytes: int, ready: multiprocessing.synchronize.Event) -> None:
    """Save version 0, 1, 2 ... of one archive back to back (each ~0.3 s of deflate)."""
    weights = np.random.default_rng(0).random(nbytes // 8)  # incompressible: a slow save
    for version in range(10**6):
        weights[0] = version
        write_archive(path, "model", {"version": version}, {"w": weights})
        ready.set()


def _advice_log(monkeypatch: pytest.MonkeyPatch, chunk: int) -> list[tuple[int, int]]:
    """Record the (offset, length) of every ``posix_fadvise`` a write-behind file gives, with
    a chunk of ``chunk`` bytes."""
    calls: list[tuple[int, int]] = []

    def advise(fd: int, offset: int, length: int, advice: int) -> None:
        assert advice == os.POSIX_FADV_DONTNEED
        calls.append((offset, length))

    monkeypatch.setattr(atomic_write_module, "WRITE_BEHIND_CHUNK", chunk)
    monkeypatch.setattr(os, "posix_fadvise", advise)
    return calls


def _handed_and_dropped(
    calls: list[tuple[int, int]],
) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
    """Split the advice log into hand-overs and drops: each round after the first drops the
    range handed the round before, then hands the new one."""
    handed, dropped = [calls[0]], []
    for i in range(1, len(calls), 2):
        dropped.append(calls[i])
        handed.append(calls[i + 1])
    assert dropped == handed[:-1]  # a range is dropped one round after it was handed over
    return handed, dropped


@pytest.mark.skipif(not hasattr(os, "posix_fadvise"), reason="no posix_fadvise")
def test_write_behind_hands_each_chunk_to_the_disk_and_drops_it_a_round_later(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Once at least a chunk (here 10,000 bytes) was written since the last advice, the new
    range is handed over (DONTNEED starts its writeback) and the range handed the time
    before is dropped; the ranges tile the file in order; a write that goes back (a zip
    header filled in after its data) changes bytes, not the ranges; the file is exactly
    what a plain write gives."""
    calls = _advice_log(monkeypatch, 10_000)
    target = tmp_path / "model.zip"
    data = bytes(range(256)) * 400  # 102,400 bytes
    with atomic_write(target, "wb", write_behind=True) as file:
        file.write(b"H" * 10)
        for start in range(0, len(data), 3000):
            file.write(data[start : start + 3000])
        file.seek(3)
        file.write(b"xyz")  # goes back: no new range
        file.seek(0, os.SEEK_END)
        file.write(b"end")
    assert target.read_bytes() == b"HHHxyzHHHH" + data + b"end"
    handed, _ = _handed_and_dropped(calls)
    assert handed[0][0] == 0
    assert all(a + n == b for (a, n), (b, _) in itertools.pairwise(handed))
    assert all(n >= 10_000 for _, n in handed)
    end = handed[-1][0] + handed[-1][1]
    assert len(data) + 13 - 10_000 < end <= len(data) + 13  # the tail stays for the fsync


@pytest.mark.skipif(not hasattr(os, "posix_fadvise"), reason="no posix_fadvise")
def test_write_behind_on_a_file_system_that_refuses_advice_writes_a_plain_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[int] = []

    def refuse(fd: int, offset: int, length: int, advice: int) -> None:
        calls.append(offset)
        raise OSError(22, "Invalid argument")

    monkeypatch.setattr(atomic_write_module, "WRITE_BEHIND_CHUNK", 100)
    monkeypatch.setattr(os, "posix_fadvise", refuse)
    with atomic_write(tmp_path / "f.bin", "wb", write_behind=True) as file:
        for i in range(10):
            file.write(bytes([i]) * 150)
    assert (tmp_path / "f.bin").read_bytes() == b"".join(bytes([i]) * 150 for i in range(10))
    assert calls == [0]  # asked once, then never again
    assert _names(tmp_path) == ["f.bin"]


def test_write_behind_is_for_binary_files(tmp_path: Path) -> None:
    with pytest.raises(
        ValueError, match=r"atomic_write\(write_behind=True\) writes mode 'wb', got 'w'"
    ):
        with atomic_write(tmp_path / "a.txt", "w", write_behind=True):
            pass
    assert _names(tmp_path) == []


@pytest.mark.skipif(not hasattr(os, "posix_fadvise"), reason="no posix_fadvise")
def test_a_model_archive_is_written_behind_and_reads_back(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``write_archive`` writes a file of 4 MiB of arrays or more through the write-behind
    file: 5.7 MB written with a 64 KiB chunk are handed over in ranges that tile the file,
    and read back equal. A smaller file is assembled in memory and written in one piece,
    never advised."""
    calls = _advice_log(monkeypatch, 64 << 10)
    write_archive(tmp_path / "small", "model", {}, {"a": np.arange(1 << 20, dtype=np.uint8)})
    assert calls == [] and read_archive(tmp_path / "small.zip", "model")[1]["a"][-1] == 255
    arrays = {"a": np.arange(1_000_000, dtype=np.float32), "b": np.ones((300, 700), np.float64)}
    write_archive(tmp_path / "m", "model", {"x": 1}, arrays, compress=False)
    meta, back = read_archive(tmp_path / "m.zip", "model")
    assert meta == {"x": 1} and all(np.array_equal(back[k], arrays[k]) for k in arrays)
    handed, _ = _handed_and_dropped(calls)
    assert handed[0][0] == 0
    assert all(a + n == b for (a, n), (b, _) in itertools.pairwise(handed))
    size = (tmp_path / "m.zip").stat().st_size
    assert size - (64 << 10) <= handed[-1][0] + handed[-1][1] <= size


@pytest.mark.skipif(sys.platform == "win32", reason="fork and SIGKILL")
def test_kill_9_during_saves_keeps_a_loadable_file(tmp_path: Path) -> None:
    """A process saving a 4 MB model over and over is killed at a random moment, three
    times: the file always loads whole and self-consistent; what a killed save leaves is a
    hidden ``.tmp`` file, which no loader reads (a killed process cannot clean up)."""
    path = tmp_path / "model.zip"
    context = multiprocessing.get_context("fork")  # the child only runs numpy and zipfile
    rng = random.Random(12)
    leftovers = 0
    for trial in range(3):
        ready = context.Event()
        child = context.Process(target=_save_forever, args=(str(path), 4 << 20, ready))
        child.start()
        if trial == 0:  # later trials may be killed in their first save: the file is older
            assert ready.wait(60), "the first save did not finish"
        time.sleep(rng.uniform(0.05, 0.3))
        assert child.pid is not None
        os.kill(child.pid, signal.SIGKILL)
        child.join()
        assert child.exitcode == -signal.SIGKILL
        meta, arrays = read_archive(tmp_path / "model", "model")  # "model" finds model.zip
        assert arrays["w"][0] == meta["version"] and arrays["w"].nbytes == 4 << 20
        temps = [n for n in _names(tmp_path) if n != "model.zip"]
        assert all(TEMP.match(n) for n in temps), temps
        leftovers += len(temps)
    assert leftovers >= 1  # the kills did land in the middle of saves


CHILD = r"""
import sys
from palaestra.algos import PPO
model = PPO("MlpPolicy", "CartPole-v1", n_steps=64, batch_size=64, n_epochs=1, seed=0,
            policy_kwargs={"net_arch": [2048, 2048]})  # ~8.4M parameters, ~100 MB saved
model.learn(64)  # an optimizer state to save too
path = sys.argv[1]
model.save(path)
print("saved", flush=True)
while True:
    model.num_timesteps += 1
    model.save(path)
"""


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_kill_9_while_saving_a_large_model(tmp_path: Path) -> None:
    """The same with a real PPO model of ~100 MB, saved by ``model.save`` in a fresh
    interpreter, killed three times after a random delay; the previous file loads each time."""
    from palaestra.algos import PPO

    path = tmp_path / "big.zip"
    src = str(Path(__file__).resolve().parents[2] / "src")
    rng = random.Random(7)
    for _ in range(3):
        child = subprocess.Popen(
            [sys.executable, "-c", CHILD, str(path)], stdout=subprocess.PIPE, text=True,
            env={**os.environ, "PYTHONPATH": src},
        )  # fmt: skip
        assert child.stdout is not None and child.stdout.readline().strip() == "saved"
        time.sleep(rng.uniform(0.2, 2.0))
        child.send_signal(signal.SIGKILL)
        child.wait()
        assert child.returncode == -signal.SIGKILL
        model = PPO.load(path)
        assert model.num_timesteps >= 64
        temps = [n for n in _names(tmp_path) if n != "big.zip"]
        assert all(TEMP.match(n) for n in temps), temps
