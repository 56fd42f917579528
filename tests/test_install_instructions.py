"""The README's own-environment install, as the user-install check runs it: CPU torch first,
extras that pyproject declares, and a check script that installs the same."""

from __future__ import annotations

import re
from pathlib import Path

import tomllib

ROOT = Path(__file__).resolve().parents[1]


def _install_block() -> list[str]:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("### Installing palaestra in your own environment", 1)[1]
    block = section.split("```bash", 1)[1].split("```", 1)[0]
    return [line.split("#", 1)[0].strip() for line in block.strip().splitlines()]


def test_cpu_torch_comes_before_the_extras() -> None:
    lines = _install_block()
    cpu = [i for i, line in enumerate(lines) if "download.pytorch.org/whl/cpu" in line]
    extras = [i for i, line in enumerate(lines) if re.search(r'pip install "\.\[', line)]
    assert cpu and extras, lines
    assert cpu[0] < extras[0], f"the CPU-torch line must come first: {lines}"


def test_the_extras_named_exist() -> None:
    declared = set(
        tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    )
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("### Installing palaestra in your own environment", 1)[1]
    section = section.split("\n## ", 1)[0]
    named = {e for group in re.findall(r'"\.\[([a-z0-9,]+)\]"', section) for e in group.split(",")}
    check = (ROOT / "tests" / "userinstall" / "check.sh").read_text()
    named |= set(re.search(r'extras="([a-z0-9,]+)"', check).group(1).split(","))  # type: ignore[union-attr]
    assert named and named <= declared, sorted(named - declared)
    assert {"train", "box2d", "render", "progress", "sweep", "ray"} <= named


def test_the_check_never_installs_the_reference_libraries() -> None:
    check = (ROOT / "tests" / "userinstall" / "check.sh").read_text()
    installs = [line for line in check.splitlines() if "install" in line and "pip" in line]
    assert installs
    for line in installs:
        assert not re.search(r"gymnasium|stable.baselines|requirements/", line), line
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]
    for name in re.search(r'extras="([a-z0-9,]+)"', check).group(1).split(","):  # type: ignore[union-attr]
        for req in extras[name]:
            assert not re.match(r"(gymnasium|stable-baselines3|pytest)\b", req), (name, req)
