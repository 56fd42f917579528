"""Run Stable-Baselines3's own test suite against palaestra, its import paths mapped as the
README's table maps them, and count what passes on both.

    python -m tests.compat.sb3_suite [--files test_her.py ...] [--out DIR]

The tests come from SB3's source distribution on PyPI (the installed version's, downloaded
once into a cache). They run twice in fresh processes: on SB3 itself (the baseline: which ids
pass there) and with an import hook that makes ``stable_baselines3.X`` the palaestra module
``public_paths.SB3_MODULES`` names for it and ``gymnasium.X`` the module ``palaestra.X``. The
hook lives in a ``sitecustomize`` on ``PYTHONPATH`` so that subprocess workers (SubprocVecEnv
under spawn or forkserver) get it too. The report counts, per file, the ids passing on SB3 and
how many of those pass on palaestra, and groups palaestra's failures by their first line.

A measurement tool (CPU-heavy: the whole suite trains hundreds of small models), not part of
the default test run.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import xml.etree.ElementTree as ET
from importlib import metadata
from pathlib import Path

CACHE = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "palaestra-suites"
REPO = Path(__file__).resolve().parents[2]

# Written as the palaestra run's sitecustomize: maps SB3 and Gymnasium paths before any test
# module is imported, in the runner and in every worker process it starts.
HOOK = """
import importlib, importlib.abc, importlib.machinery, sys

from palaestra.algos import public_paths as _paths


def _target(name):
    for theirs, ours in (("stable_baselines3", "palaestra.algos"), ("gymnasium", "palaestra")):
        if name == theirs or name.startswith(theirs + "."):
            if theirs == "stable_baselines3" and name in _paths.SB3_MODULES:
                real = _paths.SB3_MODULES[name]
                if real is None:
                    raise ModuleNotFoundError(f"{name} has no palaestra module", name=name)
                return real
            return ours + name[len(theirs):]
    return None


class _Loader(importlib.abc.Loader):
    def __init__(self, module):
        self.module = module

    def create_module(self, spec):
        return self.module

    def exec_module(self, module):
        pass


class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path, target=None):
        real = _target(fullname)
        if real is None:
            return None
        try:
            module = importlib.import_module(real)
        except ModuleNotFoundError as exc:
            raise ModuleNotFoundError(f"{fullname} -> {real}: {exc}", name=fullname) from None
        return importlib.machinery.ModuleSpec(fullname, _Loader(module))


sys.meta_path.insert(0, _Finder())
"""


def sb3_tests(version: str) -> Path:
    """SB3's ``tests/`` folder for ``version``, downloaded from PyPI once and cached."""
    root = CACHE / f"stable_baselines3-{version}"
    if not (root / "tests").is_dir():
        CACHE.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp:
            subprocess.run(
                [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps",
                 "--no-binary", ":all:", f"stable-baselines3=={version}", "-d", tmp],
                check=True,
            )  # fmt: skip
            (sdist,) = Path(tmp).glob("*.tar.gz")
            with tarfile.open(sdist) as tar:
                members = [m for m in tar.getmembers() if "/tests/" in m.name + "/"]
                tar.extractall(CACHE, members=members, filter="data")
    return root / "tests"


def run(tests: Path, files: list[str], junit: Path, hooked: bool, timeout: int) -> None:
    """One pytest run over ``files`` in ``tests`` writing ``junit``; on palaestra when hooked."""
    env = dict(os.environ)
    paths = [str(REPO / "src")]
    if hooked:
        hook_dir = junit.parent / "hook"
        hook_dir.mkdir(exist_ok=True)
        (hook_dir / "sitecustomize.py").write_text(HOOK, encoding="utf-8")
        paths.insert(0, str(hook_dir))
    env["PYTHONPATH"] = os.pathsep.join([*paths, env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env.setdefault("MPLBACKEND", "Agg")
    command = [
        sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--tb=line",
        "--continue-on-collection-errors",
        f"--timeout={timeout}", f"--junitxml={junit}", "-o", "junit_family=xunit1",
        *(files or ["."]),
    ]  # fmt: skip
    subprocess.run(command, cwd=tests, env=env, check=False)


def outcomes(junit: Path) -> dict[str, tuple[str, str]]:
    """``{test id: (outcome, first line of the message)}`` from a JUnit XML report."""
    result: dict[str, tuple[str, str]] = {}
    for case in ET.parse(junit).getroot().iter("testcase"):
        test_id = f"{case.get('file') or case.get('classname')}::{case.get('name')}"
        outcome, message = "passed", ""
        for child in case:
            if child.tag in ("failure", "error", "skipped"):
                outcome = "skipped" if child.tag == "skipped" else "failed"
                lines = (child.get("message") or child.text or "").strip().splitlines()
                message = lines[0][:160] if lines else ""
                break
        result[test_id] = (outcome, message)
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--files", nargs="*", default=[], help="test files (default: all)")
    parser.add_argument("--out", type=Path, default=Path("sb3_suite_report"))
    parser.add_argument("--timeout", type=int, default=600, help="seconds per test")
    parser.add_argument("--reuse-baseline", action="store_true", help="keep out/sb3.xml")
    args = parser.parse_args(argv)

    version = metadata.version("stable-baselines3")
    tests = sb3_tests(version)
    args.out.mkdir(parents=True, exist_ok=True)
    out = args.out.resolve()
    if not (args.reuse_baseline and (out / "sb3.xml").exists()):
        run(tests, args.files, out / "sb3.xml", hooked=False, timeout=args.timeout)
    run(tests, args.files, out / "palaestra.xml", hooked=True, timeout=args.timeout)

    theirs, ours = outcomes(out / "sb3.xml"), outcomes(out / "palaestra.xml")
    per_file: dict[str, list[int]] = collections.defaultdict(lambda: [0, 0])
    reasons: collections.Counter[str] = collections.Counter()
    for test_id, (outcome, _) in theirs.items():
        if outcome != "passed":
            continue
        counts = per_file[test_id.split("::")[0]]
        counts[0] += 1
        mine, message = ours.get(test_id, ("missing", "not collected"))
        if mine == "passed":
            counts[1] += 1
        else:
            reasons[message] += 1
    total = [sum(c[0] for c in per_file.values()), sum(c[1] for c in per_file.values())]
    report = {
        "sb3_version": version,
        "passed_on_sb3": total[0],
        "passed_on_palaestra_of_those": total[1],
        "per_file": {name: {"sb3": a, "palaestra": b} for name, (a, b) in sorted(per_file.items())},
        "failure_reasons": reasons.most_common(),
    }
    (out / "report.json").write_text(json.dumps(report, indent=1), encoding="utf-8")
    for name, (a, b) in sorted(per_file.items()):
        print(f"{name:40s} {b:4d} / {a:4d}")
    share = 100 * total[1] / max(total[0], 1)
    print(f"{'total':40s} {total[1]:4d} / {total[0]:4d}  ({share:.1f}%)")
    print("most common failures on palaestra:")
    for message, count in reasons.most_common(25):
        print(f"  {count:4d}  {message}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
