"""An import of a palaestra module inside a function says why it is not at the top.

A function-level ``import``/``from`` of a palaestra module, or an ``importlib.import_module`` /
``__import__`` call naming one (the edges of :mod:`tests.layout.import_graph`), carries a tag on
its first line::

    from palaestra.vec_env import VecEnv  # lazy: import-time — cloudpickle

with one of three reasons: ``import-time`` (a module that must stay light — ``import palaestra``,
the CLI parser, ``from_sb3`` — would otherwise load the named thing), ``optional-dep`` (an extra
that may be missing) or ``cycle`` (a circle that cannot be cut). Everything else goes to the top
of its module. There are at most :data:`MAX_FUNCTION_LEVEL_IMPORTS` of them.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path

import pytest
from tests.layout.import_graph import Edge, all_edges, edges_of, module_names

TAG = re.compile(r"^lazy: (import-time|optional-dep|cycle) — \S")
MAX_FUNCTION_LEVEL_IMPORTS = 60


@functools.cache
def _statements() -> dict[tuple[str, int], Edge]:
    """One edge per function-level import statement or call: ``(module, line) -> edge``."""
    out: dict[tuple[str, int], Edge] = {}
    for edge in all_edges():
        if edge.function_level:
            out.setdefault((edge.source, edge.line), edge)
    return out


def _untagged(statements: dict[tuple[str, int], Edge]) -> list[str]:
    return [
        f"{module}:{line} imports {edge.target} ({edge.comment or 'no comment'!r})"
        for (module, line), edge in sorted(statements.items())
        if not TAG.match(edge.comment)
    ]


def test_every_function_level_import_says_why() -> None:
    checked = _statements()
    assert checked, "no function-level imports found: is the graph read?"
    untagged = _untagged(checked)
    assert untagged == [], (
        "move these to the top of their module, or tag them "
        "'# lazy: <import-time|optional-dep|cycle> — <what>':\n" + "\n".join(untagged)
    )


def test_at_most_60_function_level_imports() -> None:
    counted = list(_statements())
    assert len(counted) <= MAX_FUNCTION_LEVEL_IMPORTS, sorted(counted)


@pytest.mark.parametrize(
    ("line", "tagged"),
    [
        ("    from palaestra.b import x  # lazy: import-time — torch", True),
        ("    from palaestra.b import x  # lazy: optional-dep — ray", True),
        ("    from palaestra.b import x  # lazy: cycle — palaestra.b", True),
        ("    importlib.import_module('palaestra.b')  # lazy: cycle — palaestra.b", True),
        ("    from palaestra.b import x", False),
        ("    from palaestra.b import x  # lazy: because", False),
        ("    from palaestra.b import x  # lazy: import-time", False),
        ("    from palaestra.b import x  # lazy: speed — torch", False),
        ("    importlib.import_module('palaestra.b')", False),
    ],
)
def test_the_tag_check_reads_a_module(tmp_path: Path, line: str, tagged: bool) -> None:
    package = tmp_path / "palaestra"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "b.py").write_text("x = 1\n")
    (package / "a.py").write_text(f"import importlib\n\n\ndef f():\n{line}\n")
    modules = module_names(tmp_path)
    edges = [e for e in edges_of("palaestra.a", package / "a.py", modules) if e.function_level]
    assert {e.target for e in edges} == {"palaestra.b"}
    statements = {(e.source, e.line): e for e in edges}
    assert _untagged(statements) == (
        []
        if tagged
        else [f"palaestra.a:5 imports palaestra.b ({edges[0].comment or 'no comment'!r})"]
    )
