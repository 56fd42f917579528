"""Executed code blocks: ```` ```{run} ```` runs its Python when the site is built and shows its output.

Every block of a page runs, in order, in one namespace per page, in a scratch folder per page
(``docs/_build/exec/<page>``) so files a block saves (``model.save("dqn_mountaincar")``) are
there for the next block. Nothing is skipped and nothing is cached: a block that raises is a
build warning carrying the traceback, which ``-W`` turns into a failed build. A block that
is meant to raise says which exception with ``:raises: InvalidAction``; it then fails the build
if it does not raise that exception, and shows the exception's line as its output.

Each page's namespace starts with ``ROOT`` (the repository) and ``SRCDIR`` (the docs source
folder): a block can read the repository's data files and write a figure under
``SRCDIR/_generated`` that the page shows with ``{image}``.

Options:
    ``:raises: NAME``   the block must raise an exception whose class name is NAME.
    ``:hide-code:``     run the block and show only its output (set-up code).
    ``:hide-output:``   run the block and show only the code.
    ``:shell:``         the block is a shell command line (the ``palaestra`` command), run with
                        bash in the page's folder; a non-zero exit status fails the build.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shutil
import subprocess
import sys
import time
import traceback
import warnings
from pathlib import Path
from typing import Any, ClassVar

from docutils import nodes
from docutils.parsers.rst import directives
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)
_ROOT = Path(__file__).resolve().parents[2]

# Per page: the namespace its blocks share, and the seconds they took (for the build log).
_NAMESPACES: dict[str, dict[str, Any]] = {}
TIMINGS: dict[str, float] = {}


class _Tee(io.StringIO):
    """Collects what a block prints; tqdm and palaestra's progress lines write to stderr."""

    def isatty(self) -> bool:
        return False


_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def _format_output(text: str) -> str:
    # Progress bars redraw with carriage returns: keep the last state of each line; colour
    # codes (palaestra's logger colours its warnings) do not belong in a web page.
    lines = [_ANSI.sub("", line.rsplit("\r", 1)[-1]) for line in text.splitlines()]
    return "\n".join(line.rstrip() for line in lines).strip("\n")


class RunDirective(SphinxDirective):
    has_content = True
    option_spec: ClassVar[dict[str, Any]] = {
        "raises": directives.unchanged_required,
        "hide-code": directives.flag,
        "hide-output": directives.flag,
        "shell": directives.flag,
    }

    def run(self) -> list[nodes.Node]:
        docname = self.env.docname
        code = "\n".join(self.content)
        workdir = Path(self.env.app.outdir).parent / "exec" / docname
        if docname not in _NAMESPACES:
            # The page's first block: a fresh namespace and an empty folder, so a page never
            # depends on what an earlier build left (a run folder, a saved model).
            # ROOT and SRCDIR let a block read the repository's files and write a figure
            # that the page then shows with an image directive.
            _NAMESPACES[docname] = {
                "__name__": "__main__",
                "ROOT": str(_ROOT),
                "SRCDIR": str(self.env.srcdir),
            }
            shutil.rmtree(workdir, ignore_errors=True)
        namespace = _NAMESPACES[docname]
        workdir.mkdir(parents=True, exist_ok=True)
        expected = self.options.get("raises")
        out = _Tee()
        error: BaseException | None = None
        tb = ""
        start = time.perf_counter()
        cwd = os.getcwd()
        try:
            os.chdir(workdir)
            with (
                contextlib.redirect_stdout(out),
                contextlib.redirect_stderr(out),
                warnings.catch_warnings(),
            ):
                warnings.simplefilter("default")
                warnings.showwarning = lambda m, c, f, ln, file=None, line=None: print(
                    f"{c.__name__}: {m}", file=out
                )
                if "shell" in self.options:
                    _run_shell(code, out)
                else:
                    compiled = compile(code, f"<{docname}.md:{self.lineno}>", "exec")
                    exec(compiled, namespace)
        except BaseException as exc:
            error = exc
            tb = traceback.format_exc()
        finally:
            os.chdir(cwd)
            TIMINGS[docname] = TIMINGS.get(docname, 0.0) + time.perf_counter() - start
        text = _format_output(out.getvalue())
        location = (docname, self.lineno)
        if expected is not None:
            if error is None or type(error).__name__ != expected:
                got = "nothing" if error is None else f"{type(error).__name__}: {error}"
                logger.warning(
                    "code block should raise %s but raised %s\n%s",
                    expected,
                    got,
                    tb,
                    location=location,
                    type="palaestra",
                    subtype="exec",
                )
            else:
                text = (
                    text + "\n" if text else ""
                ) + f"{type(error).__module__}.{type(error).__name__}: {error}"
        elif error is not None:
            logger.warning(
                "code block raised %s: %s\n%s",
                type(error).__name__,
                error,
                tb,
                location=location,
                type="palaestra",
                subtype="exec",
            )
        result: list[nodes.Node] = []
        if "hide-code" not in self.options:
            shell = "shell" in self.options
            shown = _with_prompts(code) if shell else code
            block = nodes.literal_block(shown, shown, language="console" if shell else "python")
            self.set_source_info(block)
            result.append(block)
        if text and "hide-output" not in self.options:
            container = nodes.container(classes=["palaestra-output"])
            container += nodes.rubric("", "Output", classes=["palaestra-output-label"])
            output = nodes.literal_block(text, text, language="text")
            container += output
            result.append(container)
        return result


def _with_prompts(command: str) -> str:
    """Show a command line as typed: ``$`` before each command, none on continuation lines."""
    shown, continued = [], False
    for line in command.splitlines():
        shown.append(line if continued else f"$ {line}")
        continued = line.endswith("\\")
    return "\n".join(shown)


def _run_shell(command: str, out: io.StringIO) -> None:
    """Run ``command`` with the build's Python first on PATH (its ``palaestra`` command)."""
    env = dict(os.environ)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    env["PYTHONPATH"] = os.pathsep.join(
        p for p in [str(_ROOT / "src"), env.get("PYTHONPATH", "")] if p
    )
    done = subprocess.run(
        ["bash", "-o", "pipefail", "-c", command],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    out.write(done.stdout + done.stderr)
    if done.returncode != 0:
        raise RuntimeError(
            f"command exited with status {done.returncode}: {command}\n{done.stdout}{done.stderr}"
        )


def _forget(app: Sphinx, env: Any, docname: str) -> None:
    _NAMESPACES.pop(docname, None)
    TIMINGS.pop(docname, None)


def _drop_namespace(app: Sphinx, doctree: Any) -> None:
    # A page's objects (trained models, envs) are not needed once the page is read.
    _NAMESPACES.pop(app.env.docname, None)


def _report(app: Sphinx, exception: BaseException | None) -> None:
    if TIMINGS:
        total = sum(TIMINGS.values())
        slow = ", ".join(
            f"{d} {t:.1f} s" for d, t in sorted(TIMINGS.items(), key=lambda x: -x[1])[:5]
        )
        logger.info("executed code blocks: %.1f s (%s)", total, slow)


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("run", RunDirective)
    app.connect("env-purge-doc", _forget)
    app.connect("doctree-read", _drop_namespace)
    app.connect("build-finished", _report)
    # Pages execute in one process, in order; the namespaces are per page.
    return {"version": "1", "parallel_read_safe": False, "parallel_write_safe": True}
