"""palaestra's public paths, from the one data file (``src/palaestra/algos/public_paths.json``):
every public module of SB3 has its row and its substituted path is that palaestra module itself
(never a copy); SB3's public names palaestra lacks are exactly the recorded list (which only
shrinks); the README's import table is the generated one; and every path the README, SPEC and
``tests/test_public_names_issue16.py`` document resolves."""

from __future__ import annotations

import ast
import importlib
import json
import sys
import types

import pytest
from tests.algos import public_names
from tests.algos.public_names import COMMAND, MISSING_FILE, README

from palaestra.algos import public_paths

DATA = json.loads(public_paths.DATA_FILE.read_text(encoding="utf-8"))
MAPPED = sorted((k, v) for k, v in public_paths.SB3_MODULES.items() if v is not None)
NOT_YET = sorted(k for k, v in public_paths.SB3_MODULES.items() if v is None)


def _resolve(path: str) -> object:
    """What a documented entry names: a statement runs in a fresh namespace (each name it binds
    must be set); ``a.b.*`` is module ``a.b``; ``a.b.c`` is module ``a.b.c`` or attribute ``c``."""
    if " " in path:
        namespace: dict[str, object] = {}
        exec(path, namespace)
        (statement,) = ast.parse(path).body
        assert isinstance(statement, (ast.Import, ast.ImportFrom)), path
        bound = [a.asname or a.name.split(".")[0] for a in statement.names]
        assert all(namespace[name] is not None for name in bound), path
        return namespace
    path = path.removesuffix(".*")
    try:
        return importlib.import_module(path)
    except ModuleNotFoundError as exc:
        if exc.name != path:
            raise
        module, _, name = path.rpartition(".")
        return getattr(importlib.import_module(module), name)


def _root(entry: str) -> str:
    """The top package an entry is in (``from stable_baselines3 import A2C``: stable_baselines3)."""
    words = entry.split()
    return (words[1] if len(words) > 1 else words[0]).split(".")[0]


# -- the data file's shape: a typo in a key must not drop a row silently ----------------------
def test_the_data_file_has_its_tables_and_nothing_else() -> None:
    assert list(DATA) == [
        "about",
        "sb3_modules",
        "aliases",
        "notes",
        "moved_modules",
        "moved_classes",
        "readme_table",
        "documented",
    ]
    for row in public_paths.README_TABLE:
        assert set(row) <= {"theirs", "ours", "names", "note"}, row
        assert row["theirs"] and row["ours"], row
    public = {*public_paths.MODULE_ALIASES, *map(public_paths.sb3_path, public_paths.SB3_MODULES)}
    assert set(DATA["notes"]) <= public  # a note is about a path the file lists


# -- the SB3 module table: no SB3 needed --------------------------------------------------------
def test_sb3_path_is_the_one_substitution() -> None:
    assert public_paths.sb3_path("stable_baselines3") == "palaestra.algos"
    assert public_paths.sb3_path("stable_baselines3.common.noise") == "palaestra.algos.noise"
    assert public_paths.sb3_path("stable_baselines3.her.her_replay_buffer") == (
        "palaestra.algos.her.her_replay_buffer"
    )
    with pytest.raises(ValueError, match=r"not a stable_baselines3 module: 'gymnasium\.spaces'"):
        public_paths.sb3_path("gymnasium.spaces")


def test_no_two_sb3_modules_share_a_palaestra_path() -> None:
    paths = [public_paths.sb3_path(name) for name in public_paths.SB3_MODULES]
    assert len(paths) == len(set(paths)) == len(public_paths.SB3_MODULES)


@pytest.mark.parametrize(("theirs", "real"), MAPPED)
def test_an_sb3_path_is_the_module_itself(theirs: str, real: str) -> None:
    path = public_paths.sb3_path(theirs)
    module = importlib.import_module(path)
    assert module is importlib.import_module(real) is sys.modules[path]
    assert module.__name__ == module.__spec__.name == real  # not a copy run under a 2nd name
    parent, _, leaf = path.rpartition(".")
    if parent.startswith(
        "palaestra.algos"
    ):  # and an attribute of its package, as `import` makes it
        assert getattr(importlib.import_module(parent), leaf) is module


def test_every_sb3_module_has_a_palaestra_module() -> None:
    """Every public module of the installed SB3 has its palaestra module (its row in
    public_paths.json is no longer null), so every path the README's rule maps imports."""
    assert NOT_YET == []


def test_no_palaestra_module_is_loaded_twice() -> None:
    """An alias is the module object itself: after importing every public path, each source
    file of palaestra backs one module object."""
    for theirs, _ in MAPPED:
        importlib.import_module(public_paths.sb3_path(theirs))
    for alias in public_paths.MODULE_ALIASES:
        importlib.import_module(alias)
    by_file: dict[str, dict[int, str]] = {}
    for module in list(sys.modules.values()):
        file = getattr(module, "__file__", None)
        if isinstance(module, types.ModuleType) and file and "palaestra" in module.__name__:
            by_file.setdefault(file, {})[id(module)] = module.__name__
    copies = {f: sorted(names.values()) for f, names in by_file.items() if len(names) > 1}
    assert copies == {}, "one file run as several modules (a copy, not an alias)"


# -- against the installed SB3 ------------------------------------------------------------------
def test_every_public_sb3_module_has_a_row() -> None:
    pytest.importorskip("stable_baselines3")
    modules = public_names.sb3_public_modules()
    assert len(modules) >= 60
    unmapped = sorted(set(modules) - set(public_paths.SB3_MODULES))
    assert unmapped == [], (
        f"SB3 modules without a row in {public_paths.DATA_FILE.name} (sb3_modules): {unmapped}"
    )


def test_the_missing_names_are_the_recorded_list() -> None:
    """Fails both when a listed name arrives (the list only shrinks: regenerate it) and when a
    name goes missing that was there."""
    sb3 = pytest.importorskip("stable_baselines3")
    recorded = json.loads(MISSING_FILE.read_text(encoding="utf-8"))
    if sb3.__version__ != recorded["stable_baselines3"]:
        pytest.skip(f"list recorded for SB3 {recorded['stable_baselines3']}, not {sb3.__version__}")
    now = public_names.missing_names()
    then = recorded["missing"]
    arrived = {m: sorted(set(n) - set(now.get(m, []))) for m, n in then.items()}
    gone = {m: sorted(set(n) - set(then.get(m, []))) for m, n in now.items()}
    arrived = {m: n for m, n in arrived.items() if n}
    gone = {m: n for m, n in gone.items() if n}
    assert (arrived, gone) == ({}, {}), (
        f"SB3 names palaestra now has (arrived) or lost (gone) at their substituted paths; "
        f"if arrived, regenerate the list: {COMMAND}"
    )


def test_public_names_of_a_module_without_all() -> None:
    pytest.importorskip("stable_baselines3")
    a2c_policies = importlib.import_module("stable_baselines3.a2c.policies")
    assert public_names.public_names(a2c_policies) == ["CnnPolicy", "MlpPolicy", "MultiInputPolicy"]
    base = public_names.public_names(importlib.import_module("stable_baselines3.common.base_class"))
    assert base == ["BaseAlgorithm", "maybe_make_env"]  # no TypeVar, no imported names


# -- README, SPEC and the issue-16 test ---------------------------------------------------------
def test_the_readme_table_is_the_generated_one() -> None:
    text = README.read_text(encoding="utf-8")
    assert public_names.readme_with_table(text, public_paths.markdown_table()) == text, (
        f"README.md's import table differs from src/palaestra/algos/public_paths.json; "
        f"regenerate it: {COMMAND}"
    )


def test_the_readme_needs_its_markers() -> None:
    with pytest.raises(ValueError, match=r"README\.md needs each import-table marker once"):
        public_names.readme_with_table("| a | b |\n", "| c | d |\n")


OURS = sorted({p for row in public_paths.README_TABLE for p in row["ours"]})
DOCUMENTED = sorted({p for paths in DATA["documented"].values() for p in paths})


@pytest.mark.parametrize("path", OURS + DOCUMENTED)
def test_a_documented_path_resolves(path: str) -> None:
    assert _resolve(path) is not None


@pytest.mark.filterwarnings("ignore:.*matplotlib is not installed")  # gymnasium.utils.play's
@pytest.mark.parametrize("row", public_paths.README_TABLE, ids=lambda row: row["theirs"][0])
def test_a_readme_row_names_real_things_on_both_sides(row: dict[str, list[str]]) -> None:
    """The Gymnasium/SB3 side exists there too, and the names a ``.*`` row lists are in every
    module of the row."""
    for root in sorted({_root(entry) for entry in row["theirs"]}):
        pytest.importorskip(root)
    resolved = {entry: _resolve(entry) for entry in [*row["theirs"], *row["ours"]]}
    for name in row.get("names", []):
        lacking = [e for e, obj in resolved.items() if e.endswith(".*") and not hasattr(obj, name)]
        assert lacking == [], name


def test_the_issue16_statements_are_in_the_data_file() -> None:
    from tests.test_public_names_issue16 import STATEMENTS

    assert DATA["documented"]["tests/test_public_names_issue16.py"] == STATEMENTS
