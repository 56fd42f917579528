"""Model files saved before ``algos/`` was split into ``common/`` and one package per algorithm
load and predict as they did then: the classes they name (``module:qualname``) at their old
paths resolve through the permanent alias table in ``model_io``."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from palaestra.algos import A2C, DDPG, DQN, PPO, SAC, TD3

DATA = Path(__file__).parent / "data" / "pre_layout"
CLASSES = {"dqn": DQN, "ppo": PPO, "a2c": A2C, "sac": SAC, "td3": TD3, "ddpg": DDPG}


@pytest.mark.parametrize("algo", sorted(CLASSES))
def test_files_saved_before_the_layout_move_load_and_predict_the_same(algo: str) -> None:
    expected = json.loads((DATA / "predictions.json").read_text())[algo]
    model = CLASSES[algo].load(DATA / f"{algo}.zip")
    obs = np.asarray(expected["obs"], np.float32)
    actions = model.predict(obs, deterministic=True)[0]
    np.testing.assert_allclose(actions, expected["actions"], rtol=1e-6, atol=1e-6)


def test_the_files_name_classes_at_their_old_paths() -> None:
    """Guards the fixture: the refs the alias table must resolve are really in the files."""
    refs = set()
    for path in DATA.glob("*.zip"):
        with zipfile.ZipFile(path) as zf:
            for name in zf.namelist():
                if name.endswith(".json"):
                    text = zf.read(name).decode()
                    refs.update(part.split('"')[0] for part in text.split('"__class__": "')[1:])
    assert {
        "palaestra.algos.off_policy_policies:DQNPolicy",
        "palaestra.algos.off_policy_policies:SACPolicy",
        "palaestra.algos.off_policy_policies:TD3Policy",
        "palaestra.algos.policies:ActorCriticPolicy",
        "palaestra.algos.networks:FlattenExtractor",
    } <= refs
