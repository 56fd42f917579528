"""Every registered env id has the gallery's prose (docs/_ext/env_notes.py), checked in the
default suite so that a new env is caught before ``make docs`` fails on it."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

import palaestra

NOTES = Path(__file__).resolve().parents[2] / "docs" / "_ext" / "env_notes.py"
_spec = importlib.util.spec_from_file_location("env_notes", NOTES)
assert _spec is not None and _spec.loader is not None
env_notes = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(env_notes)


@pytest.mark.parametrize("env_id", sorted(palaestra.registry))
def test_every_registered_id_has_notes(env_id: str) -> None:
    notes = env_notes.notes_for(env_id)
    assert notes is not None, f"{env_id!r} has no entry in docs/_ext/env_notes.py"
    for field in ("summary", "rewards", "end", "versions"):
        assert notes[field].strip(), (env_id, field)


def test_an_unknown_id_has_none() -> None:
    assert env_notes.notes_for("NoSuchEnv-v0") is None
    assert env_notes.notes_for("ALE/Pong-v4") is None


def test_atari_ids_name_their_game_and_version() -> None:
    assert "Pong" in env_notes.notes_for("ALE/Pong-v5")["summary"]
    assert env_notes.notes_for("ALE/Pong-v5")["versions"].startswith("v5")
    assert env_notes.notes_for("PongNoFrameskip-v4")["versions"].startswith("v4")
