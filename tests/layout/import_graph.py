"""palaestra's import graph, read from the source with ``ast``: which module imports which, at
module level or inside a function, and the circles (strongly connected components) that the
run-time imports make.

An edge is an ``import``/``from`` statement, or an ``importlib.import_module("palaestra.…")`` /
``__import__`` call with a constant name, that names a palaestra module. Imports under
``if TYPE_CHECKING:`` are not edges: they never run. ``from palaestra.x import y`` is an edge to
``palaestra.x.y`` when that is a module, else to ``palaestra.x``; importing ``palaestra.a.b``
also runs ``palaestra.a``'s ``__init__``, which counts as an edge too.

Run::

    .venv/bin/python tests/layout/import_graph.py          # counts, and the circles
"""

from __future__ import annotations

import ast
import dataclasses
import sys
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SRC = ROOT / "src"


@dataclasses.dataclass(frozen=True)
class Edge:
    """One import of a palaestra module by another."""

    source: str
    target: str
    line: int
    function_level: bool  # inside a def (runs when called), else at import time
    dynamic: bool  # importlib.import_module / __import__
    comment: str  # the comment on the import's line, for the reason tag


def module_names(src: Path = SRC) -> dict[str, Path]:
    """``palaestra.x.y`` -> its file, for every module of the package."""
    out = {}
    for path in sorted((src / "palaestra").rglob("*.py")):
        parts = list(path.relative_to(src).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _resolve(name: str, modules: dict[str, Path]) -> str | None:
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _walk(node: ast.AST, in_function: bool) -> Iterator[tuple[ast.AST, bool]]:
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.If) and _is_type_checking(child.test):
            for sub in child.orelse:
                yield sub, in_function
                yield from _walk(sub, in_function)
            continue
        inner = in_function or isinstance(
            child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)
        )
        yield child, inner
        yield from _walk(child, inner)


def edges_of(module: str, path: Path, modules: dict[str, Path]) -> list[Edge]:
    """The palaestra modules ``module`` imports."""
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines()
    tree = ast.parse(text)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out: list[Edge] = []

    def add(target: str | None, node: ast.AST, fn: bool, dynamic: bool = False) -> None:
        if target is None or not target.startswith("palaestra") or target == module:
            return
        lineno = getattr(node, "lineno", 0)
        line = lines[lineno - 1] if lineno else ""
        comment = line.split("#", 1)[1].strip() if "#" in line else ""
        # the parents' __init__ run first
        parts = target.split(".")
        for i in range(1, len(parts) + 1):
            name = ".".join(parts[:i])
            if name in modules and name != module and not module.startswith(name + "."):
                out.append(Edge(module, name, lineno, fn, dynamic, comment))

    for node, fn in _walk(tree, False):
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(_resolve(alias.name, modules), node, fn)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            for alias in node.names:
                full = f"{base}.{alias.name}"
                add(full if full in modules else _resolve(base, modules), node, fn)
        elif isinstance(node, ast.Call):
            func = node.func
            name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if name in ("import_module", "__import__") and node.args:
                arg = node.args[0]
                if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                    add(_resolve(arg.value, modules), node, fn, dynamic=True)
    return out


def all_edges(src: Path = SRC) -> list[Edge]:
    """Every import edge between palaestra's modules."""
    modules = module_names(src)
    return [e for m, p in modules.items() for e in edges_of(m, p, modules)]


def circles(edges: list[Edge]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    graph: dict[str, set[str]] = {}
    for e in edges:
        graph.setdefault(e.source, set()).add(e.target)
        graph.setdefault(e.target, set())
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    out: list[list[str]] = []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        out.append(sorted(component))
    return sorted(out, key=len, reverse=True)


def main() -> int:
    edges = all_edges()
    statements = {(e.source, e.line) for e in edges if e.function_level}
    tagged = {
        (e.source, e.line) for e in edges if e.function_level and e.comment.startswith("lazy:")
    }
    dynamic = {(e.source, e.line) for e in edges if e.dynamic}
    print(f"modules: {len(module_names())}, edges: {len(edges)}")
    print(f"function-level imports of palaestra modules: {len(statements)} ({len(tagged)} tagged)")
    print(f"importlib/__import__ calls naming palaestra modules: {len(dynamic)}")
    print(f"circles at run time (all edges): {[len(c) for c in circles(edges)]}")
    top = [e for e in edges if not e.function_level]
    print(f"circles at import time (module-level edges): {[len(c) for c in circles(top)]}")
    for component in circles(edges):
        print(f"  {len(component)}: {' '.join(component)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
