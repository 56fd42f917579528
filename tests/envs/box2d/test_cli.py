"""The Box2D ids through the command line: listed by ``envs``, trainable by ``train``."""

from __future__ import annotations

import contextlib
import io
import os
from pathlib import Path

import pytest

from palaestra.cli import main

pytest.importorskip("Box2D")


def _run(*argv: str) -> tuple[int, str]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        code = main(list(argv))
    return code, out.getvalue()


def test_envs_lists_lunar_lander_one_row_each() -> None:
    code, out = _run("envs", "--filter", "lunar")
    assert code == 0
    rows = out.splitlines()[2:-1]
    assert [r.split()[:4] for r in rows] == [
        ["LunarLander-v3", "Discrete(4)", "200", "1000"],
        ["LunarLanderContinuous-v3", "Box(-1.0,", "1.0,", "(2,),"],
    ]
    # numpy wraps the 8 bounds over lines; the table keeps each space on its row.
    assert all(r.endswith("(8,), float32)") for r in rows)


@pytest.mark.slow
def test_train_ppo_on_lunar_lander(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("torch")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", os.environ.get("MPLBACKEND", "Agg"))
    # The preset collects 16 envs x 1024 steps per rollout; 2 envs make one rollout 2,048.
    code, out = _run("train", "ppo", "LunarLander-v3", "--n-envs", "2", "--timesteps", "2048")
    assert code == 0, out
    assert "trained ppo on LunarLander-v3: 2,048 steps" in out
    (run,) = (tmp_path / "runs").iterdir()
    assert (run / "model.zip").is_file()
