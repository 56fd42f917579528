"""The run's env pipeline settings, checked before anything is built."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from tests.cli.conftest import Result


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        ("4611686018427387904", "frame_stack=4611686018427387904 would need 4,611,686,018,"),
        ('"4"', "frame_stack must be a positive integer, got '4' (str)"),
        ("2.7", "frame_stack must be a positive integer, got 2.7 (float)"),
        ("true", "frame_stack must be a positive integer, got True (bool)"),
        ("0", "frame_stack must be a positive integer, got 0"),
    ],
)
def test_bad_frame_stack_is_one_line_before_training(
    cli: Callable[..., Result], tmp_path: Path, value: str, expected: str
) -> None:
    # 2**62 used to crash the interpreter inside numpy once the env was built.
    result = cli("train", "ppo", "CartPole-v1", "--set", f"frame_stack={value}",
                 "--out", tmp_path / "r")  # fmt: skip
    assert result.code == 2
    assert result.err.count("\n") == 1 and result.err.startswith("palaestra: error: "), result.err
    assert expected in result.err and result.err.endswith("(e.g. 4, or null for no stack)\n")
    assert not (tmp_path / "r").exists()
