"""How much can the learning criterion "palaestra's IQM over 5 seeds >= SB3's minus 10% of
|SB3's|" say at a budget? Reads per-seed returns of two libraries (the lines
``benchmarks/learning.py`` prints) and reports:

* the criterion on each block of 5 consecutive seeds and on all seeds together;
* the Mann-Whitney U statistic of the two samples (U = n*m/2 when neither tends to be larger)
  with its exact two-sided p-value (by enumerating every relabelling of the pooled seeds);
* a bootstrap 95% interval of the IQM difference (palaestra - SB3);
* the criterion's false-failure rate: split one library's own seeds into two halves every way
  and count how often one half fails the criterion against the other.

Run from the repository root, with the outputs of ``learning.py`` (any number of files)::

    .venv/bin/python benchmarks/iqm_noise.py --algo sac_mujoco RESULTS.txt [MORE.txt ...]
"""

from __future__ import annotations

import argparse
import itertools
import random
import re
import statistics
from pathlib import Path

LINE = re.compile(r"^(\w+) +(palaestra|sb3) +seed=(\d+) .*mean_return= *(-?[\d.]+)")


def iqm(values: list[float]) -> float:
    """Interquartile mean, as ``learning.py``'s: ``int(n / 4)`` values dropped from each end."""
    ordered = sorted(values)
    cut = len(ordered) // 4
    return statistics.fmean(ordered[cut : len(ordered) - cut])


def meets(ours: list[float], theirs: list[float]) -> bool:
    """The issue's criterion."""
    line = iqm(theirs)
    return iqm(ours) >= line - 0.1 * abs(line)


def mann_whitney_u(a: list[float], b: list[float]) -> float:
    """Pairs (x in a, y in b) with x > y, ties counting a half."""
    return sum((x > y) + 0.5 * (x == y) for x in a for y in b)


def exact_two_sided_p(a: list[float], b: list[float]) -> float:
    """Share of the pooled seeds' relabellings whose U is at least as far from n*m/2."""
    pooled, n = a + b, len(a)
    centre = len(a) * len(b) / 2
    observed = abs(mann_whitney_u(a, b) - centre)
    hits = total = 0
    for chosen in itertools.combinations(range(len(pooled)), n):
        rest = [pooled[i] for i in range(len(pooled)) if i not in chosen]
        u = mann_whitney_u([pooled[i] for i in chosen], rest)
        hits += abs(u - centre) >= observed - 1e-9
        total += 1
    return hits / total


def split_half_failures(values: list[float]) -> tuple[int, int]:
    """``(failing, all)`` ordered splits of one library's seeds into two halves."""
    half = len(values) // 2
    failing = total = 0
    for chosen in itertools.combinations(range(len(values)), half):
        first = [values[i] for i in chosen]
        second = [values[i] for i in range(len(values)) if i not in chosen][:half]
        failing += not meets(first, second)
        total += 1
    return failing, total


def read(paths: list[Path], algo: str) -> dict[str, dict[int, float]]:
    """``{lib: {seed: mean_return}}`` of ``algo`` from learning.py's per-seed lines."""
    found: dict[str, dict[int, float]] = {"palaestra": {}, "sb3": {}}
    for path in paths:
        for line in path.read_text().splitlines():
            match = LINE.match(line.strip())
            if match and match.group(1) == algo:
                found[match.group(2)][int(match.group(3))] = float(match.group(4))
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--algo", default="sac_mujoco")
    parser.add_argument("--bootstrap", type=int, default=20_000)
    parser.add_argument("results", nargs="+", type=Path, help="learning.py outputs")
    args = parser.parse_args()
    found = read(args.results, args.algo)
    seeds = sorted(set(found["palaestra"]) & set(found["sb3"]))
    if len(seeds) < 5:
        raise SystemExit(f"need both libraries on >= 5 common seeds, have {seeds}")
    ours = [found["palaestra"][s] for s in seeds]
    theirs = [found["sb3"][s] for s in seeds]
    blocks = [seeds[i : i + 5] for i in range(0, len(seeds) - 4, 5)]
    for block in [*blocks, seeds] if len(blocks) > 1 else blocks:
        a = [found["palaestra"][s] for s in block]
        b = [found["sb3"][s] for s in block]
        line = iqm(b) - 0.1 * abs(iqm(b))
        print(
            f"seeds {block[0]}-{block[-1]} ({len(block)}): IQM palaestra {iqm(a):.1f}, "
            f"sb3 {iqm(b):.1f}, line {line:.1f}: {'met' if meets(a, b) else 'NOT met'}; "
            f"means {statistics.fmean(a):.1f} / {statistics.fmean(b):.1f}"
        )
    u = mann_whitney_u(ours, theirs)
    print(
        f"Mann-Whitney U (palaestra > sb3) = {u:.1f} of {len(ours) * len(theirs)}, "
        f"exact two-sided p = {exact_two_sided_p(ours, theirs):.3f}"
    )
    rng = random.Random(0)
    diffs = sorted(
        iqm(rng.choices(ours, k=len(ours))) - iqm(rng.choices(theirs, k=len(theirs)))
        for _ in range(args.bootstrap)
    )
    low, high = diffs[int(0.025 * len(diffs))], diffs[int(0.975 * len(diffs)) - 1]
    print(
        f"IQM difference palaestra - sb3: {iqm(ours) - iqm(theirs):.1f}, "
        f"bootstrap 95% [{low:.1f}, {high:.1f}]"
    )
    for lib, values in (("sb3", theirs), ("palaestra", ours)):
        failing, total = split_half_failures(values)
        print(
            f"{lib} against itself: {failing} of {total} splits into halves of "
            f"{len(values) // 2} seeds fail the criterion ({failing / total:.0%})"
        )


if __name__ == "__main__":
    main()
