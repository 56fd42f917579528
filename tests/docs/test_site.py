"""Checks on the built documentation site (docs/_build/html, made by ``make docs``).

``make docs`` runs these right after building, with ``PALAESTRA_DOCS_BUILT=1``; a missing site
is a failure. The default suite leaves this file out (tests/docs/conftest.py).
"""

from __future__ import annotations

import importlib
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

import palaestra

ROOT = Path(__file__).resolve().parents[2]
SITE = ROOT / "docs" / "_build" / "html"
API_MODULES = ["palaestra", "palaestra.algos", "palaestra.vec_env", "palaestra.wrappers"]

if not (SITE / "index.html").exists():
    raise RuntimeError(f"no built site at {SITE}: run `make docs`")


class _Collector(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.ids: set[str] = set()
        self.images: list[str] = []
        self.external: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if values.get("id"):
            self.ids.add(values["id"] or "")
        if tag == "img" and values.get("src"):
            self.images.append(values["src"] or "")
        # What a browser fetches by itself: scripts, stylesheets, fonts, images, frames.
        url = values.get("src") if tag in ("script", "img", "iframe") else None
        if tag == "link" and (values.get("rel") or "") in (
            "stylesheet",
            "preload",
            "icon",
            "preconnect",
        ):
            url = values.get("href")
        if url and re.match(r"^(https?:)?//", url):
            self.external.append(f"<{tag}> {url}")


def _parse(path: Path) -> _Collector:
    collector = _Collector()
    collector.feed(path.read_text(encoding="utf-8"))
    return collector


def _public_names(module: str) -> list[str]:
    return list(importlib.import_module(module).__all__)


@pytest.mark.parametrize("module", API_MODULES)
def test_every_public_name_has_its_own_anchor(module: str) -> None:
    page = SITE / "api" / f"{module}.html"
    ids = _parse(page).ids | _parse(SITE / "api" / "more.html").ids
    missing = []
    for name in _public_names(module):
        full = f"{module}.{name}"
        if full not in ids and f"module-{full}" not in ids:
            missing.append(full)
    assert not missing, f"public names with no anchor in {page.name}: {missing}"


def test_no_page_fetches_anything_from_the_web() -> None:
    found = []
    for page in SITE.rglob("*.html"):
        found += [f"{page.relative_to(SITE)}: {url}" for url in _parse(page).external]
    for css in (SITE / "_static").rglob("*.css"):
        text = css.read_text(encoding="utf-8", errors="replace")
        found += [
            f"{css.relative_to(SITE)}: {m}"
            for m in re.findall(r"(?:@import|url\()\s*['\"]?(?:https?:)?//[^)'\"]+", text)
        ]
    for js in (SITE / "_static").rglob("*.js"):
        text = js.read_text(encoding="utf-8", errors="replace")
        found += [
            f"{js.relative_to(SITE)}: {m}"
            for m in re.findall(r"(?:fetch|importScripts)\(\s*['\"]https?://[^'\"]+", text)
        ]
    assert not found, "the site loads from the web:\n" + "\n".join(found)


def test_every_registered_env_has_a_gallery_entry_with_its_own_animation() -> None:
    import sys

    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    from docutils.nodes import make_id
    from palaestra_gallery import file_stem, gallery_ids

    animations: dict[str, bytes] = {}
    problems = []
    for family, ids in gallery_ids().items():
        page = _parse(SITE / "envs" / f"{family}.html")
        for env_id in ids:
            stem = file_stem(env_id)
            if make_id(f"env-{stem}") not in page.ids:
                problems.append(f"{env_id}: no anchor env-{stem} on envs/{family}.html")
            images = [src for src in page.images if src.endswith(f"/{stem}.gif")]
            if not images:
                problems.append(f"{env_id}: no animation on envs/{family}.html")
                continue
            gif = (SITE / "envs" / images[0]).resolve()
            data = gif.read_bytes() if gif.exists() else b""
            if not data.startswith(b"GIF8"):
                problems.append(f"{env_id}: {images[0]} is not a GIF")
            animations[env_id] = data
    assert not problems, "\n".join(problems)
    assert len(animations) == len(palaestra.registry)
    # Each env has its own animation, not a shared placeholder.
    assert len(set(animations.values())) == len(animations)
