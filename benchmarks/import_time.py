"""Import time of `palaestra` vs `gymnasium` (fresh interpreter each time, median of 7).

Run: .venv/bin/python benchmarks/import_time.py
"""

from __future__ import annotations

import statistics
import subprocess
import sys

CODE = "import time; t = time.perf_counter(); import {mod}; print(time.perf_counter() - t)"


def import_seconds(module: str, repeats: int = 7) -> float:
    """Median wall time of ``import module`` in a fresh interpreter."""
    times = [
        float(subprocess.run([sys.executable, "-c", CODE.format(mod=module)], capture_output=True,
                             text=True, check=True).stdout)
        for _ in range(repeats)
    ]  # fmt: skip
    return statistics.median(times)


def main() -> None:
    """Print both import times and their ratio."""
    ours, ref = import_seconds("palaestra"), import_seconds("gymnasium")
    print(f"import palaestra: {ours * 1000:6.1f} ms (target < 300 ms)")
    print(f"import gymnasium: {ref * 1000:6.1f} ms")
    print(f"ratio gymnasium / palaestra: {ref / ours:.2f}x")


if __name__ == "__main__":
    main()
