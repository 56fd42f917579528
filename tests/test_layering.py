"""palaestra's import graph has no circles and its packages import only downwards.

The graph is read from the source (:mod:`tests.layout.import_graph`): an ``import``/``from`` at
module level or inside a function, or an ``importlib.import_module``/``__import__`` call with a
constant palaestra name, is an edge; an import under ``if TYPE_CHECKING:`` is not (it never
runs). Importing ``palaestra.a.b`` also runs ``palaestra.a``'s ``__init__``: an edge too.

The layers, bottom up (a package imports only from the packages below it):

- ``spaces`` imports only ``palaestra.error``, ``palaestra.logger`` and ``palaestra.utils``'s
  basics (``utils.seeding``; the ``utils`` package ``__init__`` that importing it runs);
- ``vector`` never imports the env packages (``palaestra.envs``): a registry entry hands it the
  classes of a native batch; nor the wrappers (``palaestra.wrappers``): the vector wrappers,
  built on the single-env ones, live in ``palaestra.wrappers.vector`` (Gymnasium's layout), and
  ``make_vec`` wraps the real envs it builds for a native batch that would have to render;
- ``envs`` never imports ``compat`` (which fills the registry's ``"gymnasium:"`` prefix),
  ``algos``, ``runs`` or ``cli``;
- ``algos`` never imports ``runs`` or ``cli``.

The rules are checked on everything a package reaches (the transitive closure of its edges),
so a detour through a third package breaks them too.
"""

from __future__ import annotations

import functools

import pytest
from tests.layout.import_graph import Edge, all_edges, circles

# package -> packages (or modules) it must never reach; "spaces" is checked by an allow-list.
FORBIDDEN: dict[str, tuple[str, ...]] = {
    "palaestra.vector": ("palaestra.envs", "palaestra.wrappers"),
    "palaestra.envs": ("palaestra.compat", "palaestra.algos", "palaestra.runs", "palaestra.cli"),
    "palaestra.algos": ("palaestra.runs", "palaestra.cli"),
}
SPACES_MAY_IMPORT = ("palaestra.error", "palaestra.logger", "palaestra.utils.seeding")


@functools.cache
def _edges() -> tuple[Edge, ...]:
    return tuple(all_edges())


def _inside(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def _reached(package: str) -> dict[str, Edge]:
    """Every palaestra module outside ``package`` that it reaches -> the edge that got there
    first (breadth first, so the edge is on a shortest path)."""
    graph: dict[str, list[Edge]] = {}
    for edge in _edges():
        graph.setdefault(edge.source, []).append(edge)
    todo = [m for m in graph if _inside(m, package)]
    seen = set(todo)
    found: dict[str, Edge] = {}
    while todo:
        module = todo.pop(0)
        for edge in graph.get(module, []):
            if edge.target in seen:
                continue
            seen.add(edge.target)
            found[edge.target] = edge
            todo.append(edge.target)
    return {m: e for m, e in found.items() if not _inside(m, package)}


def _describe(module: str, edge: Edge) -> str:
    where = "inside a function" if edge.function_level else "at module level"
    return f"{module} (via {edge.source} line {edge.line}, {where})"


def test_the_graph_is_read() -> None:
    # A reader that finds nothing would pass every other test here.
    edges = _edges()
    assert len(edges) > 1000
    assert any(e.source == "palaestra.core" and e.target == "palaestra.env_spec" for e in edges)
    assert any(e.dynamic for e in edges)  # importlib calls are edges too


def test_no_import_circles() -> None:
    found = circles(list(_edges()))
    assert not found, f"import circles: {found}"


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_a_package_never_reaches_above_itself(package: str) -> None:
    reached = _reached(package)
    bad = [
        _describe(module, edge)
        for module, edge in sorted(reached.items())
        if any(_inside(module, above) for above in FORBIDDEN[package])
    ]
    assert not bad, f"{package} reaches {bad}"


def test_spaces_imports_only_the_basics() -> None:
    direct = {
        e.target
        for e in _edges()
        if _inside(e.source, "palaestra.spaces") and not _inside(e.target, "palaestra.spaces")
    }
    # importing palaestra.utils.seeding runs the palaestra.utils package's __init__
    assert direct <= {*SPACES_MAY_IMPORT, "palaestra.utils"}, direct
    above = ("core", "env_spec", "envs", "wrappers", "vector", "vec_env", "compat", "rendering")
    above += ("algos", "runs", "cli", "presets")
    reached = _reached("palaestra.spaces")
    bad = [
        _describe(module, edge)
        for module, edge in sorted(reached.items())
        if any(_inside(module, f"palaestra.{name}") for name in above)
    ]
    assert not bad, f"palaestra.spaces reaches {bad}"
