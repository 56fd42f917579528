"""The processes of a local Ray a command started, killed when the command dies without shutting
it down (SIGKILL, the OOM killer).

Ray's own reaper stops the GCS and the raylet of a driver that dies, but not the raylet's
agents (``ray::RuntimeEnvAgent``, ``ray::DashboardAgent``): they stay forever. So
:func:`palaestra.runs.grid.ray_session` starts this watcher beside a local Ray: it notes the
driver's Ray processes every half second and, once the driver is gone (its pipe closes, however
it ended), kills those still running. After an orderly ``ray.shutdown()`` there are none left.
Linux only (``/proc``); elsewhere it is not started.
"""

from __future__ import annotations

import os
import re
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

__all__ = ["start", "stop"]

_PROC = Path("/proc")
_GRACE_S = 2.0  # an orderly shutdown that is still under way finishes first


def start() -> subprocess.Popen[bytes] | None:
    """Watch this process's Ray processes from a separate session (a signal to this
    process's group does not reach the watcher); None where there is no ``/proc``."""
    if not (_PROC / "self" / "stat").exists():
        return None
    watcher = subprocess.Popen(
        [sys.executable, "-m", "palaestra.runs.reaper", str(os.getpid())],
        stdin=subprocess.PIPE,
        start_new_session=True,
    )
    # The Ray processes there are now, from here: a SIGKILL before the watcher's first look
    # would leave them with init as their parent, out of its sight.
    now = _ray_descendants(os.getpid())
    assert watcher.stdin is not None
    watcher.stdin.write(" ".join(f"{pid}:{started}" for pid, started in now.items()).encode())
    watcher.stdin.write(b"\n")
    watcher.stdin.flush()
    return watcher


def stop(watcher: subprocess.Popen[bytes] | None) -> None:
    """The driver's orderly end: close the pipe and let the watcher check and exit."""
    if watcher is None:
        return
    if watcher.stdin is not None:
        try:
            watcher.stdin.write(b"done\n")  # Ray is shut down: no grace needed
            watcher.stdin.close()
        except OSError:  # the watcher is gone already
            pass
    try:
        watcher.wait(timeout=10 * _GRACE_S)
    except subprocess.TimeoutExpired:
        watcher.kill()


def _stat(pid: int) -> tuple[int, str] | None:
    """``(parent pid, start time)`` of a live process, or None."""
    try:
        fields = (_PROC / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return (int(fields[1]), fields[19]) if fields[0] != "Z" else None


def _is_ray(pid: int) -> bool:
    try:
        cmdline = (_PROC / str(pid) / "cmdline").read_bytes()
    except OSError:
        return False
    return cmdline.startswith(b"ray::") or b"/ray/" in cmdline


def _ray_descendants(root: int) -> dict[int, str]:
    """The Ray processes below ``root``: pid -> start time (so a reused pid is not killed)."""
    stats = {}
    for entry in _PROC.iterdir():
        if entry.name.isdigit() and (stat := _stat(int(entry.name))) is not None:
            stats[int(entry.name)] = stat
    found: dict[int, str] = {}
    todo = [root]
    while todo:
        parent = todo.pop()
        for pid, (ppid, started) in stats.items():
            if ppid == parent and pid not in found:
                found[pid] = started
                todo.append(pid)
    return {pid: started for pid, started in found.items() if _is_ray(pid)}


def _session_processes(driver: int) -> dict[int, str]:
    """Processes whose command line names the Ray session ``driver`` started (its folder ends
    with the driver's PID): workers started between two looks, now children of init."""
    mark = re.compile(rb"/session_[0-9_-]+_%d/" % driver)
    found = {}
    for entry in _PROC.iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmdline = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        if mark.search(cmdline) and (stat := _stat(int(entry.name))) is not None:
            found[int(entry.name)] = stat[1]
    return found


def main(driver: int) -> None:
    """Watch ``driver`` until its pipe (our stdin) closes, then kill its Ray processes."""
    seen: dict[int, str] = {}
    done = False
    while True:
        ready, _, _ = select.select([sys.stdin.fileno()], [], [], 0.5)
        if ready:
            data = os.read(sys.stdin.fileno(), 65536)
            if not data:
                break  # the driver is gone, or done
            for item in data.split():  # "pid:start" of the Ray processes at the start; "done"
                number, _, started = item.decode().partition(":")
                if number == "done":
                    done = True
                elif number.isdigit():
                    seen[int(number)] = started
        seen.update(_ray_descendants(driver))
    if not done:
        time.sleep(_GRACE_S)
    seen.update(_session_processes(driver))
    for pid, started in seen.items():
        stat = _stat(pid)
        if stat is not None and stat[1] == started:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass


if __name__ == "__main__":
    main(int(sys.argv[1]))
