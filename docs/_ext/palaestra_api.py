"""The API reference: one page per public module, one entry (with its own anchor) per name in
the module's ``__all__``, written into ``docs/api/`` when the build starts.

The pages are generated so that a name added to ``__all__`` gets its entry without anyone
editing the docs; ``tests/docs/test_site.py`` checks the built anchors against the same lists.
"""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path
from typing import Any

from sphinx.application import Sphinx

# Modules documented in full on the "More modules" page: other pages' docstrings refer to them.
EXTRA_MODULES = ["palaestra.error", "palaestra.spaces", "palaestra.compat"]

DATA = {
    "palaestra.registry": "Every registered environment: a ``dict`` from env id to its "
    ":py:class:`~palaestra.envs.registration.EnvSpec`, filled by :py:func:`palaestra.register`.",
}

MODULES = {
    "palaestra": "The environment API: ``Env``, the wrapper base classes, ``make``, the registry.",
    "palaestra.algos": "The algorithms and what comes with them (Stable-Baselines3's API).",
    "palaestra.vec_env": "Stable-Baselines3's ``VecEnv`` API over palaestra's vector engines.",
    "palaestra.wrappers": "The standard wrappers (Gymnasium's, plus SB3's ``Monitor`` and ``AtariWrapper``).",
}


def public_names(module: str) -> list[str]:
    """The names a module exports, in ``__all__``'s order."""
    return list(importlib.import_module(module).__all__)


def _entry(module: str, name: str) -> str:
    obj = getattr(importlib.import_module(module), name)
    full = f"{module}.{name}"
    if inspect.ismodule(obj):
        # A submodule: its docstring and its own anchor (``module-palaestra.spaces``).
        if obj.__name__ in EXTRA_MODULES:
            # Documented in full on the "More modules" page; here a pointer with its own anchor.
            # Its anchor (``module-{full}``) is on that page; here a pointer.
            return f"``{name}``: the module :py:mod:`{full}`, documented in full on :doc:`more`.\n"
        return f".. automodule:: {full}\n"
    if inspect.isclass(obj):
        return f".. autoclass:: {full}\n   :members:\n   :undoc-members:\n   :exclude-members: __init__, __new__\n"
    if callable(obj):
        return f".. autofunction:: {full}\n"
    # Data (an instance): its type's docstring would describe the type, not the object.
    return f".. py:data:: {name}\n   :module: {module}\n\n   {DATA[full]}\n"


def write_pages(app: Sphinx) -> None:
    out = Path(app.srcdir) / "api"
    out.mkdir(exist_ok=True)
    index = [
        "API reference",
        "=============",
        "",
        "Every public name of palaestra's four main modules, generated from the docstrings.",
        "",
        ".. toctree::",
        "   :maxdepth: 1",
        "",
    ]
    for module, blurb in MODULES.items():
        index.append(f"   {module}")
        lines = [module, "=" * len(module), "", blurb, "", f".. currentmodule:: {module}", ""]
        names = public_names(module)
        lines.append("Names: " + ", ".join(f":py:obj:`{n} <{module}.{n}>`" for n in names) + ".")
        lines.append("")
        for name in names:
            lines += [_entry(module, name), ""]
        _write_if_changed(out / f"{module}.rst", "\n".join(lines))
    index.append("   more")
    more = ["More modules", "============", "", "Modules the pages above refer to, in full.", ""]
    for module in EXTRA_MODULES:
        more += [f".. automodule:: {module}", "   :members:", "   :undoc-members:"]
        # palaestra.Space is documented on the palaestra page (same class, one anchor).
        more += ["   :exclude-members: Space", ""] if module == "palaestra.spaces" else [""]
    _write_if_changed(out / "more.rst", "\n".join(more))
    _write_if_changed(out / "index.rst", "\n".join(index) + "\n")


def _write_if_changed(path: Path, text: str) -> None:
    # Rewriting an unchanged page would make Sphinx read it again on every build.
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def setup(app: Sphinx) -> dict[str, Any]:
    app.connect("builder-inited", write_pages)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
