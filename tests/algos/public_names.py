"""SB3's public modules and names against palaestra's public paths (``public_paths.json``),
and the command that writes what is generated from that file. From the repository root,

    python -m tests.algos.public_names --write

prints how much of SB3's public surface palaestra has and writes the README's import table
(between its markers) and ``data/sb3_missing_names.json``, the SB3 names palaestra does not
have yet at their substituted paths (needs SB3 installed; without ``--write`` it only prints).
"""

from __future__ import annotations

import argparse
import ast
import importlib
import inspect
import json
import pkgutil
import sys
import types
from pathlib import Path

from palaestra.algos import public_paths
from palaestra.utils.atomic_write import atomic_write

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
MISSING_FILE = Path(__file__).parent / "data" / "sb3_missing_names.json"
COMMAND = "python -m tests.algos.public_names --write"
BEGIN = (
    f"<!-- import table: generated from src/palaestra/algos/public_paths.json by `{COMMAND}` -->"
)
END = "<!-- end of import table -->"


def sb3_public_modules() -> list[str]:
    """Every module of the installed ``stable_baselines3`` without a ``_`` in its path."""
    import stable_baselines3  # lazy: optional-dep — stable_baselines3

    names = [stable_baselines3.__name__]
    for info in pkgutil.walk_packages(stable_baselines3.__path__, "stable_baselines3."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return sorted(names)


def public_names(module: types.ModuleType) -> list[str]:
    """The names ``module`` offers: its ``__all__``, else the classes, functions and values its
    own source binds at top level (``MlpPolicy = ActorCriticPolicy`` counts; imports and
    ``TypeVar``s do not), without a leading ``_``."""
    if hasattr(module, "__all__"):
        return sorted(module.__all__)
    tree = ast.parse(Path(inspect.getfile(module)).read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            value = node.value
            if (
                isinstance(value, ast.Call)
                and isinstance(value.func, (ast.Name, ast.Attribute))
                and (getattr(value.func, "id", None) or getattr(value.func, "attr", ""))
                == "TypeVar"
            ):
                continue
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names.update(t.id for t in targets if isinstance(t, ast.Name))
    return sorted(name for name in names if not name.startswith("_"))


def _is_typevar(value: ast.expr | None) -> bool:
    """``TypeVar(...)`` or ``typing.TypeVar(...)``: a typing helper, not an API name."""
    if not isinstance(value, ast.Call):
        return False
    func = value.func
    return (isinstance(func, ast.Name) and func.id == "TypeVar") or (
        isinstance(func, ast.Attribute) and func.attr == "TypeVar"
    )


def palaestra_module(sb3_module: str) -> types.ModuleType | None:
    """The module at SB3 module's substituted path, or None where palaestra has none."""
    try:
        return importlib.import_module(public_paths.sb3_path(sb3_module))
    except ModuleNotFoundError:
        return None


def missing_names() -> dict[str, list[str]]:
    """SB3 module -> its public names palaestra lacks at the substituted path (modules it has
    all of are left out)."""
    missing: dict[str, list[str]] = {}
    for name in sb3_public_modules():
        ours = palaestra_module(name)
        lacking = [n for n in public_names(importlib.import_module(name)) if not hasattr(ours, n)]
        if lacking:
            missing[name] = lacking
    return missing


def readme_with_table(text: str, table: str) -> str:
    """``text`` with the part between the import table's markers replaced by ``table``."""
    if text.count(BEGIN) != 1 or text.count(END) != 1:
        raise ValueError(f"README.md needs each import-table marker once: {BEGIN!r}, {END!r}")
    head, rest = text.split(BEGIN, 1)
    return f"{head}{BEGIN}\n{table}\n{END}{rest.split(END, 1)[1]}"


def summary(missing: dict[str, list[str]]) -> str:
    """How much of SB3's public surface palaestra has at the substituted paths."""
    import stable_baselines3  # lazy: optional-dep — stable_baselines3

    modules = sb3_public_modules()
    absent = [m for m in modules if public_paths.SB3_MODULES.get(m) is None]
    names = sum(len(public_names(importlib.import_module(m))) for m in modules)
    lacking = sum(len(n) for n in missing.values())
    lines = [
        f"stable_baselines3 {stable_baselines3.__version__}: {len(modules)} public modules, "
        f"{len(modules) - len(absent)} at their palaestra path, {len(absent)} not yet",
        f"{names} public names, {names - lacking} in palaestra, {lacking} missing:",
        *(f"  {m}: {len(n)}" for m, n in missing.items()),
    ]
    return "\n".join(lines) + "\n"


def missing_file_text(missing: dict[str, list[str]]) -> str:
    """The missing-names file: ``missing`` with the SB3 version it was measured on."""
    import stable_baselines3  # lazy: optional-dep — stable_baselines3

    data = {
        "about": f"generated by `{COMMAND}`; SB3's public names palaestra lacks at their "
        "substituted paths (src/palaestra/algos/public_paths.json). The list only shrinks.",
        "stable_baselines3": stable_baselines3.__version__,
        "missing": missing,
    }
    return json.dumps(data, indent=2) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Write (``--write``) the README's table and the missing-names file; print a summary."""
    parser = argparse.ArgumentParser(prog="python -m tests.algos.public_names")
    parser.add_argument("--write", action="store_true", help="write README.md and the list")
    args = parser.parse_args(argv)
    missing = missing_names()
    sys.stdout.write(summary(missing))
    if args.write:
        readme = README.read_text(encoding="utf-8")
        readme = readme_with_table(readme, public_paths.markdown_table())
        for path, text in [(README, readme), (MISSING_FILE, missing_file_text(missing))]:
            with atomic_write(path, "w", encoding="utf-8", newline="\n") as file:
                file.write(text)
            sys.stdout.write(f"wrote {path.relative_to(ROOT)}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
