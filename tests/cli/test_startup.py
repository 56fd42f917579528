"""A fast start (issue 12 #7): the learning curve is drawn off the training path, written
atomically; ``eval`` imports neither matplotlib nor torch's compiler."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import palaestra
from palaestra.error import DependencyNotInstalled
from palaestra.runs import curves

from .conftest import Result, run_cli, wait_for_file

PNG = b"\x89PNG\r\n\x1a\n"


def _episodes_only(run: Path, tmp_path: Path) -> Path:
    """A run folder holding only ``run``'s episodes.csv (what the drawing reads)."""
    folder = tmp_path / "run"
    folder.mkdir()
    shutil.copy(run / "episodes.csv", folder / "episodes.csv")
    return folder


def test_eval_imports_neither_matplotlib_nor_the_torch_compiler(
    ppo_run: tuple[Path, Result],
) -> None:
    run, _ = ppo_run
    code = (
        "import sys\nfrom palaestra.cli import main\n"
        f"code = main(['eval', {str(run)!r}, '--episodes', '1'])\n"
        "print(code, [m for m in ('matplotlib', 'torch._dynamo') if m in sys.modules])\n"
    )
    src = str(Path(palaestra.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == "0 []"


def test_background_drawing_replaces_the_png_whole(
    ppo_run: tuple[Path, Result], tmp_path: Path
) -> None:
    folder = _episodes_only(ppo_run[0], tmp_path)
    (folder / "learning_curve.png").write_bytes(b"an older curve")
    proc = curves.draw_learning_curve(folder, "PPO on CartPole-v1", background=True)
    assert proc is not None and proc.wait(timeout=120) == 0
    assert (folder / "learning_curve.png").read_bytes()[:8] == PNG
    assert sorted(p.name for p in folder.iterdir()) == ["episodes.csv", "learning_curve.png"]


def test_failed_background_drawing_leaves_no_file(tmp_path: Path) -> None:
    """No episodes to read: the drawing process fails, and nothing is left behind."""
    proc = curves.draw_learning_curve(tmp_path, "nothing", background=True)
    assert proc is not None and proc.wait(timeout=120) != 0
    assert list(tmp_path.iterdir()) == []


def test_drawn_in_place_when_pyplot_is_loaded(ppo_run: tuple[Path, Result], tmp_path: Path) -> None:
    pytest.importorskip("matplotlib.pyplot")
    folder = _episodes_only(ppo_run[0], tmp_path)
    assert curves.draw_learning_curve(folder, "PPO on CartPole-v1") is None
    assert (folder / "learning_curve.png").read_bytes()[:8] == PNG


def test_train_lists_the_curve_as_drawing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Without pyplot loaded, ``train`` returns before the curve is drawn, and says so."""
    monkeypatch.delitem(sys.modules, "matplotlib.pyplot", raising=False)
    out = tmp_path / "run"
    result = run_cli("train", "ppo", "CartPole-v1", "--timesteps", 64, "--seed", 0,
                     "--set", "n_steps=8", "--set", "batch_size=64", "--eval-episodes", 0,
                     "--out", out, "--progress", "none")  # fmt: skip
    assert result.code == 0, result.err
    assert "learning_curve.png (drawing)," in result.out.splitlines()[-1]
    assert "matplotlib.pyplot" not in sys.modules
    assert wait_for_file(out / "learning_curve.png").read_bytes()[:8] == PNG


def test_missing_matplotlib_is_named_before_any_process_starts(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util,
        "find_spec",
        lambda name, *a: None if name == "matplotlib" else find_spec(name, *a),
    )
    with pytest.raises(DependencyNotInstalled, match=r"matplotlib.*pip install"):
        curves.draw_learning_curve(tmp_path, "t", background=True)
    assert list(tmp_path.iterdir()) == []


def test_failed_save_keeps_the_previous_plot(ppo_run: tuple[Path, Result], tmp_path: Path) -> None:
    """A plot that cannot be written (here: an unknown format) leaves the old file as it was
    and no temporary file."""
    episodes = curves.read_episodes(ppo_run[0])
    band = curves.variant_band("ppo", [episodes])
    assert band is not None
    path = tmp_path / "curves.nosuchformat"
    path.write_bytes(b"old")
    with pytest.raises(ValueError, match="nosuchformat"):
        curves.plot_compare([band], path, "t")
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == [path.name]
