"""The README's environment table names every registered id with its source (issue 15)."""

from __future__ import annotations

import re
from pathlib import Path

import palaestra

README = Path(__file__).resolve().parents[2] / "README.md"


def _table_rows() -> list[tuple[str, str]]:
    """``(ids cell, source cell)`` of each row of the table under ``## Environments``."""
    text = README.read_text(encoding="utf-8")
    section = text.split("\n## Environments\n", 1)[1].split("\n## ", 1)[0]
    lines = [line for line in section.splitlines() if line.startswith("| ")][1:]  # no header
    cells = [[cell.strip() for cell in line.strip("|").split("|")] for line in lines]
    return [(row[0], row[1]) for row in cells]


def _named_ids(cell: str) -> set[str]:
    """The ids a cell lists: ``CartPole-v0/v1`` names both versions."""
    out = set()
    for name in re.findall(r"`([^`]+)`", cell):
        base, _, versions = name.rpartition("-")
        for version in versions.split("/"):
            out.add(f"{base}-{version}")
    return out


def test_every_registered_id_is_in_the_readme_table_with_its_source() -> None:
    rows = _table_rows()
    listed = {i: source for ids, source in rows for i in _named_ids(ids)}
    missing = []
    for env_id, spec in palaestra.registry.items():
        module = spec.entry_point if isinstance(spec.entry_point, str) else ""
        if module.startswith("palaestra.envs.atari"):
            # One row stands for ale-py's games: ALE/<Game>-v5 and <Game>NoFrameskip-v4.
            assert re.fullmatch(r"ALE/\w+-v5|\w+NoFrameskip-v4", env_id), env_id
            continue
        if env_id not in listed:
            missing.append(env_id)
        else:
            assert listed[env_id].startswith("palaestra native"), (env_id, listed[env_id])
            assert module.startswith("palaestra.envs."), (env_id, module)
    assert not missing, f"registered ids missing from README's table: {sorted(missing)}"
    sources = [source for _, source in rows]
    assert any(s.startswith("ALE (ale-py") for s in sources)
    assert any(s.startswith("Gymnasium bridge") for s in sources)


def test_the_table_lists_no_id_palaestra_does_not_register() -> None:
    for ids, source in _table_rows():
        if source.startswith("palaestra native"):
            for env_id in _named_ids(ids):
                assert env_id in palaestra.registry, env_id
