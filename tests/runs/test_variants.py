"""``palaestra.runs.variants``: the grids ``palaestra compare`` trains, built as calls."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from palaestra.runs import RunError, resolve_spec
from palaestra.runs.grid import GridRun
from palaestra.runs.variants import (
    BASELINE,
    algo_runs,
    is_variant,
    variant_label,
    variant_runs,
)


@pytest.mark.parametrize(
    ("item", "expected"),
    [("preset", True), ("a.yaml", True), ("b.YML", True), ("dir/c.json", True),
     ("runs/ppo", False), ("notes.txt", False), ("presets", False)],
)  # fmt: skip
def test_is_variant(item: str, expected: bool) -> None:
    assert is_variant(item) is expected


def test_variant_label_is_the_file_stem() -> None:
    assert variant_label(BASELINE) == "preset"
    assert variant_label("configs/shaped.yaml") == "shaped"


def test_variant_runs_are_each_variant_on_each_seed(tmp_path: Path) -> None:
    gamma = tmp_path / "gamma.json"
    gamma.write_text(json.dumps({"gamma": 0.9}))
    runs = variant_runs(
        [BASELINE, str(gamma)], "ppo", "CartPole-v1", [3, 1], tmp_path / "grid", n_timesteps=64
    )
    assert [(r.label, r.spec.seed, r.run_dir) for r in runs] == [
        ("preset", 3, tmp_path / "grid" / "preset" / "seed3"),
        ("preset", 1, tmp_path / "grid" / "preset" / "seed1"),
        ("gamma", 3, tmp_path / "grid" / "gamma" / "seed3"),
        ("gamma", 1, tmp_path / "grid" / "gamma" / "seed1"),
    ]
    assert all(isinstance(r, GridRun) and r.spec.n_timesteps == 64 for r in runs)
    # each run's spec is what `palaestra train ppo CartPole-v1 --config v --seed s` trains
    preset, _ = resolve_spec("ppo", "CartPole-v1", seed=3, n_timesteps=64)
    shaped, _ = resolve_spec("ppo", "CartPole-v1", config=gamma, seed=1, n_timesteps=64)
    assert runs[0].spec == preset and runs[3].spec == shaped
    assert runs[3].spec.hyperparams["gamma"] == 0.9 != runs[1].spec.hyperparams["gamma"]


def test_a_variant_file_imports_only_what_is_allowed(tmp_path: Path) -> None:
    wrapped = tmp_path / "wrapped.yaml"
    wrapped.write_text("env_wrapper: no_such_mod:Shaping\n")
    with pytest.raises(RunError, match="no_such_mod") as info:
        variant_runs([str(wrapped)], "dqn", "MountainCar-v0", [0], tmp_path)
    assert "--allow-import" in info.value.line()


@pytest.mark.parametrize(
    ("variants", "seeds", "line"),
    [
        (["a/x.json", "b/x.yaml"], [0], "two variants share a name: ['x', 'x'] "
                                        "(give the files different names)"),
        ([BASELINE], [0, 1, 0], "--seeds repeats a seed: [0, 1, 0] (list each seed once)"),
    ],
)  # fmt: skip
def test_variant_runs_refuse_ambiguous_grids(
    variants: list[str], seeds: list[int], line: str, tmp_path: Path
) -> None:
    with pytest.raises(RunError) as info:
        variant_runs(variants, "ppo", "CartPole-v1", seeds, tmp_path)
    assert info.value.line() == line and info.value.code == 2


def test_algo_runs_are_each_algorithm_on_its_preset(tmp_path: Path) -> None:
    runs = algo_runs(["PPO", "a2c"], "CartPole-v1", [0, 2], "cmp", n_timesteps=128)
    assert [(r.label, r.spec.algo, r.spec.seed, r.run_dir) for r in runs] == [
        ("ppo", "ppo", 0, Path("cmp/ppo/seed0")),
        ("ppo", "ppo", 2, Path("cmp/ppo/seed2")),
        ("a2c", "a2c", 0, Path("cmp/a2c/seed0")),
        ("a2c", "a2c", 2, Path("cmp/a2c/seed2")),
    ]
    assert runs[2].spec == resolve_spec("a2c", "CartPole-v1", seed=0, n_timesteps=128)[0]
    assert runs[0].spec.preset == "default"


@pytest.mark.parametrize(
    ("algos", "seeds", "line"),
    [
        (["ppo", "PPO"], [0], "--algos repeats an algorithm: ['ppo', 'PPO'] (list each once)"),
        (["ppo"], [2, 2], "--seeds repeats a seed: [2, 2] (list each seed once)"),
    ],
)
def test_algo_runs_refuse_repeats(algos: list[str], seeds: list[int], line: str) -> None:
    with pytest.raises(RunError) as info:
        algo_runs(algos, "CartPole-v1", seeds, "cmp")
    assert info.value.line() == line


def test_algo_runs_name_an_unknown_algorithm() -> None:
    with pytest.raises(RunError, match=r"^unknown algorithm 'a3c'"):
        algo_runs(["ppo", "a3c"], "CartPole-v1", [0], "cmp")
