"""The site's build fails on a broken cross-reference and on a code block that raises.

Each test builds a one-page site with the real ``docs/conf.py`` settings (strict, nitpicky, the
executed-code extension) but without the API and gallery extensions, which are slow and not
what is checked here, and runs ``sphinx -W`` as ``make docs`` does. Run by ``make docs``
(``PALAESTRA_DOCS_BUILT=1``); skipped where Sphinx is not installed (the default suite).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

if os.environ.get("PALAESTRA_DOCS_BUILT") != "1":
    pytest.importorskip("sphinx", reason="make docs installs Sphinx (requirements/docs.txt)")

ROOT = Path(__file__).resolve().parents[2]
# Each builds a small site (3-5 s); ``make docs`` runs them with ``-m "slow or not slow"``.
pytestmark = pytest.mark.slow

CONF = f"""
__file__ = {str(ROOT / "docs" / "conf.py")!r}
exec(open({str(ROOT / "docs" / "conf.py")!r}).read())
extensions = [e for e in extensions if e not in ("palaestra_api", "palaestra_gallery")]
exclude_patterns = ["_build"]
"""


def _build(tmp_path: Path, page: str) -> subprocess.CompletedProcess[str]:
    src = tmp_path / "src"
    src.mkdir()
    (src / "_static").mkdir()
    (src / "_static" / "palaestra.css").write_text("")
    (src / "conf.py").write_text(CONF)
    (src / "index.md").write_text(page)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), str(ROOT)]))
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-b",
            "html",
            "-W",
            "--keep-going",
            "-n",
            "-q",
            str(src),
            str(tmp_path / "out"),
        ],
        capture_output=True,
        text=True,
        env=env,
        check=False,
        timeout=300,
    )


GOOD = """# Page

```{run}
import palaestra as gym
print(gym.make("CartPole-v1").action_space)
```

A link to this page's own section resolves: [the page](#page).
"""


def test_a_good_page_builds_and_shows_the_output(tmp_path: Path) -> None:
    done = _build(tmp_path, GOOD)
    assert done.returncode == 0, done.stderr
    html = (tmp_path / "out" / "index.html").read_text()
    assert "Discrete(2)" in html


def test_a_broken_cross_reference_fails_the_build(tmp_path: Path) -> None:
    done = _build(
        tmp_path, "# Page\n\nSee {py:func}`palaestra.no_such_function` and {doc}`no-such-page`.\n"
    )
    assert done.returncode != 0
    assert "py:func reference target not found: palaestra.no_such_function" in done.stderr
    assert "unknown document: 'no-such-page'" in done.stderr


def test_a_code_block_that_raises_fails_the_build(tmp_path: Path) -> None:
    page = '# Page\n\n```{run}\nimport palaestra as gym\ngym.make("NoSuchEnv-v0")\n```\n'
    done = _build(tmp_path, page)
    assert done.returncode != 0
    # Where, what, and the traceback down to palaestra's own error.
    assert "index.md:3: WARNING: code block raised NameNotFound" in done.stderr
    assert "Traceback" in done.stderr
    assert "palaestra.error.NameNotFound: Environment `NoSuchEnv` doesn't exist." in done.stderr


def test_a_block_that_should_raise_but_does_not_fails_the_build(tmp_path: Path) -> None:
    page = "# Page\n\n```{run}\n:raises: InvalidAction\nx = 1\n```\n"
    done = _build(tmp_path, page)
    assert done.returncode != 0
    assert "code block should raise InvalidAction but raised nothing" in done.stderr
