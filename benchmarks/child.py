"""Run one measurement in a fresh interpreter and read back the JSON it prints last.

A fresh process per measurement keeps imports, caches and allocator state of one library or
tree from colouring another's figures.
"""

from __future__ import annotations

import json
import subprocess
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any


def last_json_line(
    argv: Sequence[str], env: Mapping[str, str] | None = None, cwd: Path | None = None
) -> Any:
    """The JSON value on the last line ``argv`` writes to stdout; raises if it exits non-zero."""
    out = subprocess.run(list(argv), env=env, check=True, capture_output=True, text=True, cwd=cwd)
    return json.loads(out.stdout.strip().splitlines()[-1])
