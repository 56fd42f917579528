"""Speed in a user's install: palaestra without gymnasium or SB3 beside it, against the dev venv.

Run from the repository root::

    .venv/bin/python benchmarks/user_install_speed.py            # builds the user venv first
    .venv/bin/python benchmarks/user_install_speed.py --venv /tmp/user-venv  # reuse one

The user venv is built as ``tests/userinstall/check.sh`` builds it: a fresh virtualenv, the
CPU torch (``torch==2.13.0``), then ``pip install ".[train]"`` from a clone of the committed
tree, so only what palaestra declares is there; the script checks that gymnasium and
stable_baselines3 are absent. The dev venv is the interpreter running this script. Each case
runs in a fresh interpreter of each venv, alternating which goes first, ``--rounds`` times, on
the committed tree (installed in the user venv, this tree's ``src`` in the dev venv: run it on a
clean tree, so that only the installed packages differ). Cases: the
palaestra side of ``vs_gymnax.py`` (batched Pendulum and Acrobot at 1024 and 16384 envs, env-steps
per CPU second) and of ``train_speed.py`` (the Zoo PPO and both DQN cases). Printed: each
venv's median and the user/dev ratio, with the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from before_after import _CHILD as _TRAIN  # benchmarks/ is on sys.path when run as a script
from child import last_json_line
from vs_gymnax import _PALAESTRA as _BATCH

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"

_ABSENT = """
import importlib.util, json
print(json.dumps([m for m in ("gymnasium", "stable_baselines3", "gymnax")
                  if importlib.util.find_spec(m) is not None]))
"""

BATCH_CASES = [(e, n) for e in ("Pendulum-v1", "Acrobot-v1") for n in (1024, 16384)]
TRAIN_CASES = ["ppo-cartpole-zoo", "dqn-mountaincar", "dqn-cartpole-cleanrl"]


def build_venv(where: Path) -> Path:
    """A user venv at ``where`` (check.sh's recipe, extras ``train``); its python."""
    clone = where / "palaestra"
    subprocess.run(["git", "clone", "--quiet", "--no-hardlinks", str(ROOT), str(clone)], check=True)
    subprocess.run([sys.executable, "-m", "venv", str(where / "venv")], check=True)
    python = where / "venv" / "bin" / "python"
    pip = [str(python), "-m", "pip", "--quiet", "--disable-pip-version-check", "install"]
    subprocess.run([*pip, "torch==2.13.0"], check=True)
    subprocess.run([*pip, ".[train]"], check=True, cwd=clone)
    return python


def run(python: Path, code: str, *args: str, installed: bool = False) -> float:
    """The number a child prints last: ``palaestra`` as installed in ``python``'s venv, or
    from this tree's ``src``."""
    path = str(BENCHMARKS) if installed else f"{ROOT / 'src'}{os.pathsep}{BENCHMARKS}"
    env = dict(os.environ, PYTHONPATH=path)
    return float(last_json_line([str(python), "-c", code, *args], env, BENCHMARKS))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--venv", type=Path, help="an existing user venv (else one is built)")
    parser.add_argument("--rounds", type=int, default=3, help="runs per venv and case (median)")
    parser.add_argument("--seconds", type=float, default=1.0, help="CPU seconds per batch run")
    parser.add_argument("--only", choices=["batch", "train"], help="only these cases")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="palaestra-user-speed-") as tmp:
        user = args.venv.resolve() / "bin" / "python" if args.venv else build_venv(Path(tmp))
        dev = Path(sys.executable)
        found = json.loads(
            subprocess.run(
                [str(user), "-c", _ABSENT], check=True, capture_output=True, text=True
            ).stdout
        )
        if found:
            sys.exit(f"the user venv has {found}: not a user's install")
        print(f"user venv: {user} (no gymnasium, stable_baselines3, gymnax); dev venv: {dev}")
        print(f"load average at start: {os.getloadavg()}")
        print("| case | user venv (steps/cpu-s) | dev venv (steps/cpu-s) | user / dev |")
        print("|---|---:|---:|---:|")
        cases: list[tuple[str, str, tuple[str, ...]]] = []
        if args.only != "train":
            cases += [
                (f"{e} x {n}", _BATCH, (e, str(n), str(args.seconds))) for e, n in BATCH_CASES
            ]
        if args.only != "batch":
            cases += [(name, _TRAIN, (name, "palaestra", "1")) for name in TRAIN_CASES]
        for name, code, case_args in cases:
            rates: dict[str, list[float]] = {"user": [], "dev": []}
            for r in range(args.rounds):
                for who in ("user", "dev") if r % 2 == 0 else ("dev", "user"):
                    python = user if who == "user" else dev
                    rates[who].append(run(python, code, *case_args, installed=who == "user"))
            u, d = statistics.median(rates["user"]), statistics.median(rates["dev"])
            print(f"| {name} | {u:,.0f} | {d:,.0f} | {u / d:.2f}x |", flush=True)
        print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
