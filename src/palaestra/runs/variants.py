"""The grids of a comparison: variants (settings files, or the preset alone) or algorithms,
each trained on several seeds.

Variant ``v`` on seed ``s`` is the run ``palaestra train ALGO ENV --config v --seed s --out
ROOT/<v's stem>/seed<s>`` would train; algorithm ``a`` on seed ``s`` trains its preset into
``ROOT/a/seed<s>``. :func:`palaestra.runs.grid.run_grid` trains the lists these functions
return (``palaestra compare`` does)::

    runs = variant_runs(["preset", "shaped.yaml"], "dqn", "MountainCar-v0", [0, 1, 2], "runs/c")
    outcomes = run_grid(runs)
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from palaestra.runs.errors import RunError
from palaestra.runs.grid import GridRun
from palaestra.runs.settings import check_algo
from palaestra.runs.spec import resolve_spec

__all__ = ["BASELINE", "algo_runs", "is_variant", "variant_label", "variant_runs"]

BASELINE = "preset"  # the variant that is the preset alone
_SUFFIXES = (".yaml", ".yml", ".json")


def is_variant(item: str) -> bool:
    """Whether ``item`` names a variant to train (a settings file or ``BASELINE``) rather than a
    run folder."""
    return item == BASELINE or Path(item).suffix.lower() in _SUFFIXES


def variant_label(item: str) -> str:
    """A variant's name in tables and folders: its file's stem, or ``BASELINE``."""
    return BASELINE if item == BASELINE else Path(item).stem


def _check_seeds(seeds: Sequence[int]) -> None:
    if len(set(seeds)) < len(seeds):
        raise RunError(f"--seeds repeats a seed: {seeds}", "list each seed once")


def variant_runs(
    variants: Sequence[str],
    algo: str,
    env: str,
    seeds: Sequence[int],
    root: str | Path,
    n_timesteps: int | None = None,
    allow_import: Sequence[str] = (),
) -> list[GridRun]:
    """Each variant on each seed, variant by variant: ``ROOT/<label>/seed<s>``. A settings
    file imports a module only when ``allow_import`` names it (the preset imports none)."""
    labels = [variant_label(v) for v in variants]
    if len(set(labels)) < len(labels):
        raise RunError(f"two variants share a name: {labels}", "give the files different names")
    _check_seeds(seeds)
    root = Path(root)
    runs = []
    for item in variants:
        for seed in seeds:
            spec, _ = resolve_spec(
                algo,
                env,
                config=None if item == BASELINE else item,
                allow_import=() if item == BASELINE else allow_import,
                seed=seed,
                n_timesteps=n_timesteps,
            )
            runs.append(
                GridRun(variant_label(item), spec, root / variant_label(item) / f"seed{seed}")
            )
    return runs


def algo_runs(
    algos: Sequence[str],
    env: str,
    seeds: Sequence[int],
    root: str | Path,
    n_timesteps: int | None = None,
) -> list[GridRun]:
    """Each algorithm on its preset for ``env``, on each seed: ``ROOT/<algo>/seed<s>``."""
    checked = [check_algo(a) for a in algos]
    if len(set(checked)) < len(checked):
        raise RunError(f"--algos repeats an algorithm: {list(algos)}", "list each once")
    _check_seeds(seeds)
    root = Path(root)
    runs = []
    for algo in checked:
        for seed in seeds:
            spec, _ = resolve_spec(algo, env, seed=seed, n_timesteps=n_timesteps)
            runs.append(GridRun(algo, spec, root / algo / f"seed{seed}"))
    return runs
