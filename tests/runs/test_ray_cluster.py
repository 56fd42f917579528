"""A grid on a Ray cluster of two nodes (simulated on this machine): the same bits as local."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from palaestra.runs import RunSpec
from palaestra.runs.grid import GridRun, run_grid

ray = pytest.importorskip("ray")


@pytest.mark.slow
def test_two_node_cluster_trains_a_grid_like_the_local_backend(tmp_path: Path) -> None:
    from ray.cluster_utils import Cluster

    from palaestra.runs import load_model

    if ray.is_initialized():
        ray.shutdown()
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    cluster.add_node(num_cpus=1)
    try:
        runs = {
            backend: [
                GridRun("ppo", RunSpec.from_preset("ppo", "CartPole-v1", seed=s, n_timesteps=512),
                        tmp_path / backend / f"seed{s}")
                for s in range(4)
            ]
            for backend in ("local", "ray")
        }  # fmt: skip
        run_grid(runs["local"], "local")
        outcomes = run_grid(runs["ray"], "ray", address=cluster.address)
        assert [o.status for o in outcomes] == ["trained"] * 4
        assert len({n["NodeID"] for n in ray.nodes() if n["Alive"]}) == 2
        for a, b in zip(runs["local"], runs["ray"]):
            ours = load_model(a.run_dir / "model.zip").policy.state_dict()
            theirs = load_model(b.run_dir / "model.zip").policy.state_dict()
            for name, value in ours.items():
                np.testing.assert_array_equal(value.numpy(), theirs[name].numpy())
    finally:
        ray.shutdown()
        cluster.shutdown()


# -- errors and cleanup ------------------------------------------------------------------------
AUTH_CAUSE = (
    "Failed to connect to GCS. Last connection error: Traceback (most recent call last):\n"
    '  File "python/ray/includes/common.pxi", line 119, in ray._raylet.check_status\n'
    "ray.exceptions.AuthenticationError: RPC error: InvalidAuthToken: Authentication token is "
    "missing or incorrect. Note: RAY_AUTH_MODE is currently 'disabled' (not 'token'). Ensure "
    "that the token for the cluster is available in a local file (e.g., ~/.ray/auth_token ..."
)  # what Ray 2.60's ray.init chains under "Failed to connect to Ray cluster at ..."
AUTH_LINE = (
    "cannot join the Ray cluster at '127.0.0.1:{port}': the cluster uses token authentication "
    "and refused this process (InvalidAuthToken: Authentication token is missing or incorrect) "
    "(export RAY_AUTH_MODE=token here, with the cluster's token in ~/.ray/auth_token, "
    "RAY_AUTH_TOKEN_PATH or RAY_AUTH_TOKEN (`ray get-auth-token` on the head prints it))"
)


def test_a_refused_token_is_reported_with_rays_cause_and_the_fix(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from palaestra.runs import RunError, grid

    def refused(address: str, **kwargs: object) -> None:
        try:
            raise RuntimeError(AUTH_CAUSE)
        except RuntimeError as exc:
            raise ConnectionError(f"Failed to connect to Ray cluster at {address}") from exc

    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    monkeypatch.setattr(ray, "init", refused)
    monkeypatch.setattr(grid, "_probe", lambda address: None)  # something listens there
    with pytest.raises(RunError) as info:
        grid.connect_ray("127.0.0.1:6379")
    assert info.value.line() == AUTH_LINE.format(port=6379) and info.value.code == 1

    def timeout(address: str, **kwargs: object) -> None:
        raise ConnectionError("Failed to connect to Ray cluster at x") from TimeoutError("GCS")

    monkeypatch.setattr(ray, "init", timeout)
    with pytest.raises(RunError, match=r"^cannot join the Ray cluster at '127.0.0.1:1': GCS$"):
        grid.connect_ray("127.0.0.1:1")


def test_a_local_ray_is_shut_down_on_sigterm(monkeypatch: pytest.MonkeyPatch) -> None:
    """SIGTERM to a command running a local Ray (nothing else handling it) exits through
    SystemExit with 143, so the Ray it started is shut down rather than left running."""
    import signal

    from palaestra.runs import grid

    class FakeRay:
        down = False

        def shutdown(self) -> None:
            self.down = True

    fake = FakeRay()
    monkeypatch.setattr(grid, "_initialized", lambda: False)
    monkeypatch.setattr(grid, "connect_ray", lambda address, num_cpus=None: fake)
    monkeypatch.setattr(grid.reaper, "start", lambda: None)  # no real Ray to watch
    previous = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        with pytest.raises(SystemExit) as info, grid.ray_session(None) as session:
            assert session is fake and signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL
            os.kill(os.getpid(), signal.SIGTERM)
        assert info.value.code == 143 and fake.down
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # given back
    finally:
        signal.signal(signal.SIGTERM, previous)


def _tree(pid: int) -> set[int]:
    """``pid``'s descendants now (Linux ``/proc``)."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found, todo = set(), [pid]
    while todo:
        parent = todo.pop()
        children = {p for p, pp in parents.items() if pp == parent}
        todo.extend(children - found)
        found |= children
    return found


def _running(pids: set[int]) -> set[int]:
    alive = set()
    for pid in pids:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state != "Z":
            alive.add(pid)
    return alive


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")
@pytest.mark.parametrize("signame", ["SIGTERM", "SIGKILL"])
def test_a_signal_to_compare_on_a_local_ray_leaves_no_ray_process(
    tmp_path: Path, signame: str
) -> None:
    """SIGTERM: the command shuts its Ray down and exits 143. SIGKILL: Ray's reaper stops the
    GCS and raylet, palaestra's watcher (runs.reaper) the agents Ray's leaves."""
    import signal
    import subprocess
    import sys
    import time

    import palaestra

    src = str(Path(palaestra.__file__).parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}
    cmd = [sys.executable, "-m", "palaestra", "compare", "algos", "--env", "CartPole-v1",
           "--algos", "a2c", "--seeds", "0", "1", "--timesteps", "10000000", "--runs-dir",
           str(tmp_path / "c"), "--out", str(tmp_path / "c.png"), "--backend", "ray"]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env)  # fmt: skip
    try:
        assert proc.stdout is not None
        assert "training ->" in proc.stdout.readline()
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:  # the raylet starts its agents after a moment
            names = {
                Path(f"/proc/{p}/cmdline").read_bytes()[:40] for p in _running(_tree(proc.pid))
            }
            if any(b"RuntimeEnvAgent" in n or b"DashboardAgent" in n for n in names):
                break
            time.sleep(0.2)
        ray_procs = _tree(proc.pid)
        assert len(ray_procs) >= 4, ray_procs  # gcs, raylet, agents, workers...
        proc.send_signal(getattr(signal, signame))
        code = proc.wait(timeout=60)
        err = proc.stderr.read() if proc.stderr else ""
        if signame == "SIGTERM":
            assert code == 143, err
            assert "SIGTERM received: stopping the runs and the local Ray" in err
        else:
            assert code == -signal.SIGKILL
        deadline = time.monotonic() + 20
        while _running(ray_procs) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not _running(ray_procs), err
    finally:
        proc.kill()


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")
def test_the_readme_cluster_steps_with_token_authentication(tmp_path: Path) -> None:
    """README's steps on this machine (loopback): a head started with a token refuses a
    command without it, naming the cause and the fix; with RAY_AUTH_MODE=token it runs."""
    import shutil
    import socket
    import subprocess
    import sys

    import palaestra

    with socket.socket() as s:  # a free port above Ray's worker ports (10002-19999)
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    import tempfile

    # Short: Ray's socket paths under it must fit in 107 bytes.
    temp = Path(tempfile.mkdtemp(prefix="ray", dir="/tmp"))
    home = tmp_path / "home"
    home.mkdir()
    src = str(Path(palaestra.__file__).parents[1])
    bin_dir = str(Path(sys.executable).parent)
    env = {**os.environ, "HOME": str(home), "PATH": bin_dir + os.pathsep + os.environ["PATH"],
           "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}  # fmt: skip
    env.pop("RAY_AUTH_MODE", None)
    ray_cli = shutil.which("ray", path=env["PATH"])
    assert ray_cli is not None
    token = {**env, "RAY_AUTH_MODE": "token"}
    subprocess.run([ray_cli, "get-auth-token", "--generate"], env=token, check=True,
                   capture_output=True, timeout=60)  # fmt: skip
    head = [ray_cli, "start", "--head", f"--port={port}", "--node-ip-address=127.0.0.1",
            "--num-cpus=1", f"--temp-dir={temp}", "--disable-usage-stats"]  # fmt: skip
    subprocess.run(head, env=token, check=True, capture_output=True, timeout=120)
    compare = [sys.executable, "-m", "palaestra", "compare", "algos", "--env", "CartPole-v1",
               "--algos", "a2c", "--seeds", "0", "--timesteps", "64", "--runs-dir",
               str(tmp_path / "c"), "--out", str(tmp_path / "c.png"), "--backend", "ray",
               "--address", f"127.0.0.1:{port}"]  # fmt: skip
    try:
        refused = subprocess.run(compare, env=env, capture_output=True, text=True, timeout=180)
        assert refused.returncode == 1
        assert refused.stderr.splitlines()[-1] == "palaestra: error: " + AUTH_LINE.format(port=port)
        joined = subprocess.run(compare, env=token, capture_output=True, text=True, timeout=180)
        assert joined.returncode == 0, joined.stderr
        assert (tmp_path / "c" / "a2c" / "seed0" / "model.zip").is_file()
    finally:  # this head's processes only (`ray stop` would stop every Ray on the machine)
        mine = set()
        for entry in Path("/proc").iterdir():
            try:
                if entry.name.isdigit() and str(temp).encode() in (entry / "cmdline").read_bytes():
                    mine |= {int(entry.name), *_tree(int(entry.name))}
            except OSError:
                continue
        for pid in mine:
            try:
                os.kill(pid, 9)
            except OSError:
                pass
        shutil.rmtree(temp, ignore_errors=True)


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")
def test_the_reaper_kills_the_ray_processes_of_a_sigkilled_driver(tmp_path: Path) -> None:
    """A driver with a stand-in for a Ray process (its command line names a ``/ray/`` path)
    is SIGKILLed: no handler runs, and the watcher kills what it left."""
    import signal
    import subprocess
    import sys
    import time

    import palaestra

    driver_code = (
        "import subprocess, sys, time\n"
        "child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(120)', "
        "'/stand-in/ray/worker'])\n"
        "from palaestra.runs import reaper\n"
        "watcher = reaper.start()\n"
        "print(child.pid, watcher.pid, flush=True)\n"
        "time.sleep(120)\n"
    )
    src = str(Path(palaestra.__file__).parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}
    driver = subprocess.Popen([sys.executable, "-c", driver_code], stdout=subprocess.PIPE,
                              text=True, env=env)  # fmt: skip
    try:
        assert driver.stdout is not None
        child, watcher = map(int, driver.stdout.readline().split())
        assert _running({child, watcher}) == {child, watcher}
        driver.send_signal(signal.SIGKILL)
        driver.wait(timeout=10)
        deadline = time.monotonic() + 15
        while _running({child, watcher}) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _running({child, watcher})  # the stand-in killed, the watcher gone
    finally:
        driver.kill()
