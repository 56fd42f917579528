"""What a sweep leaves in its folder: the ranked ``trials.csv`` (each trial's state: complete,
pruned, failed or interrupted, and for the last three the reason), ``best.yaml`` (a ``train
--config`` file) and the ``history.png`` and ``importance.png`` plots."""

from __future__ import annotations

import csv
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from palaestra.runs import curves
from palaestra.runs.space import Param, settings_of
from palaestra.runs.spec import RunSpec, resolve_spec
from palaestra.utils.atomic_write import atomic_write

__all__ = ["BEST_FILE", "TRIALS_FILE", "write_outputs"]

TRIALS_FILE = "trials.csv"
BEST_FILE = "best.yaml"


def write_outputs(
    study: Any,
    space: Mapping[str, Param],
    folder: Path,
    base: RunSpec,
    preset: str | None,
) -> tuple[list[dict[str, Any]], dict[str, Any] | None, Path | None]:
    """Write the folder's table, best settings and plots; ``(rows best first, best row, best
    file)``."""
    from optuna.trial import TrialState

    rows = []
    for trial in study.get_trials(deepcopy=False):
        if trial.state == TrialState.RUNNING:
            continue
        rows.append(
            {
                "number": trial.number,
                "state": _state(trial),
                "value": trial.value,
                "params": settings_of(trial.params, space),
                # "error": what studies written before the reasons were recorded kept
                "reason": trial.user_attrs.get("reason") or trial.user_attrs.get("error"),
            }
        )
    # Complete trials by value, then pruned ones, then failed and interrupted ones.
    order = {"complete": 0, "pruned": 1}
    rows.sort(key=lambda r: (order.get(r["state"], 2), -(r["value"] or 0.0), r["number"]))
    _write_table(rows, folder / TRIALS_FILE)
    best = next((r for r in rows if r["state"] == "complete"), None)
    best_file = None
    if best is not None:
        spec = resolve_spec(
            base.algo, base.env_id, preset, overrides=best["params"], n_timesteps=base.n_timesteps
        )[0]
        best_file = folder / BEST_FILE
        _write_best(spec, best, best_file)
    _plots(study, folder)
    return rows, best, best_file


def _state(trial: Any) -> str:
    """``complete``, ``pruned``, ``failed`` or ``interrupted`` (a failed trial that a stop or
    a killed sweep ended; the next call runs it again)."""
    name = trial.state.name.lower()
    if name == "fail":
        return "interrupted" if trial.user_attrs.get("interrupted") else "failed"
    return str(name)


def _write_table(rows: list[dict[str, Any]], path: Path) -> None:

    with atomic_write(path, "w", encoding="utf-8", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(["rank", "trial", "state", "value", "params", "reason"])
        for rank, row in enumerate(rows, 1):
            value = "" if row["value"] is None else f"{row['value']:.4f}"
            writer.writerow(
                [
                    rank,
                    row["number"],
                    row["state"],
                    value,
                    json.dumps(row["params"], sort_keys=True),
                    row["reason"] or "",
                ]
            )


def _write_best(spec: RunSpec, best: dict[str, Any], path: Path) -> None:
    """The best settings as a ``train --config`` file (YAML, or JSON without PyYAML)."""
    config = spec.to_config()
    for key in ("seed", "device", "palaestra_version", "preset"):
        config.pop(key, None)
    header = (
        f"# palaestra sweep: best of the trials, trial {best['number']}, mean return "
        f"{best['value']:.2f}\n# palaestra train {spec.algo} {spec.env_id} --config {path.name}\n"
    )
    try:
        import yaml

        text = header + yaml.safe_dump(config, sort_keys=False)
    except ImportError:
        text = json.dumps(config, indent=2) + "\n"
    with atomic_write(path, "w", encoding="utf-8") as file:
        file.write(text)


def _plots(study: Any, folder: Path) -> None:
    """``history.png`` (each trial's value and the best so far) and ``importance.png``
    (Optuna's fANOVA importances), when matplotlib is installed and the trials allow."""
    import importlib.util

    from optuna.trial import TrialState

    if importlib.util.find_spec("matplotlib") is None:
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    trials = study.get_trials(deepcopy=False)
    complete = [t for t in trials if t.state == TrialState.COMPLETE]
    # A pruned trial has no final score: it is drawn at its last evaluation (first seed).
    pruned = [t for t in trials if t.state == TrialState.PRUNED and t.intermediate_values]
    if not complete and not pruned:
        return
    fig, ax = plt.subplots(figsize=(8, 4.5))
    if complete:
        numbers = [t.number for t in complete]
        values = [t.value for t in complete]
        best = [max(values[: i + 1]) for i in range(len(values))]
        ax.scatter(numbers, values, label="complete: mean return over seeds", color="tab:blue")
        ax.step(numbers, best, where="post", label="best so far", color="tab:orange")
    if pruned:
        last = [t.intermediate_values[max(t.intermediate_values)] for t in pruned]
        ax.scatter(
            [t.number for t in pruned],
            last,
            marker="x",
            color="tab:gray",
            label="pruned: its last evaluation (first seed)",
        )
    counts = {"complete": len(complete), "pruned": len(pruned)}
    others = sum(t.state == TrialState.FAIL for t in trials)
    summary = ", ".join(f"{n} {state}" for state, n in counts.items())
    if others:
        summary += f", {others} failed or interrupted (not drawn)"
    ax.set_xlabel("trial")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # trials are numbered
    ax.set_ylabel("return")
    ax.set_title(f"{study.study_name}: {summary}", fontsize=10)
    ax.legend()
    curves.save_figure(fig, folder / "history.png")
    if len(complete) < 2 or not complete[0].params:
        return
    import optuna

    try:
        importances = optuna.importance.get_param_importances(study)
    except (RuntimeError, ValueError):  # too few distinct trials to tell
        return
    fig, ax = plt.subplots(figsize=(8, 0.6 * len(importances) + 1.5))
    names = list(importances)[::-1]
    ax.barh(names, [importances[n] for n in names], color="tab:green")
    ax.set_xlabel("importance (fANOVA)")
    ax.set_title(f"{study.study_name}: hyperparameter importance")
    fig.tight_layout()
    curves.save_figure(fig, folder / "importance.png")
