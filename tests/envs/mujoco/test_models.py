"""palaestra's MJCF models: the committed files are the table's output, and each compiles to
the same ``MjModel`` as the model Gymnasium 1.4.0's v5 env loads (every numeric array, every
size, the option/visual/statistic structs and the names), not the same XML text."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.envs.mujoco.cases import MUJOCO_IDS

import palaestra
from palaestra.envs.mujoco import _model_table

mujoco = pytest.importorskip("mujoco")


def model_fields(model: Any) -> dict[str, Any]:
    """Every numeric field of ``model``: its arrays and sizes, and the scalars and arrays of
    its ``opt``, ``vis`` and ``stat`` structs (recursively), plus the names buffer."""
    fields: dict[str, Any] = {"names": model.names}

    def add(obj: Any, prefix: str) -> None:
        for key in dir(obj):
            if key.startswith("_") or key[0].isupper():
                continue  # private, or a nested type (MjVisual.Global), not a field
            value = getattr(obj, key)
            if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
                fields[prefix + key] = value.copy()
            elif isinstance(value, (bool, int, float)):
                fields[prefix + key] = value
            elif type(value).__module__.startswith("mujoco") and prefix:
                add(value, f"{prefix}{key}.")

    add(model, "")
    for struct in ("opt", "vis", "stat"):
        add(getattr(model, struct), f"{struct}.")
    return fields


def differing_fields(a: Any, b: Any) -> list[str]:
    """The names of the fields (``model_fields``) in which two models differ."""
    fa, fb = model_fields(a), model_fields(b)
    diff = sorted(set(fa) ^ set(fb))
    for key in sorted(set(fa) & set(fb)):
        x, y = fa[key], fb[key]
        if isinstance(x, np.ndarray):
            same = x.shape == y.shape and x.dtype == y.dtype and x.tobytes() == y.tobytes()
        else:
            same = type(x) is type(y) and (x == y or (x != x and y != y))
        if not same:
            diff.append(key)
    return diff


def _gymnasium_model(env_id: str, **kwargs: Any) -> Any:
    gymnasium = pytest.importorskip("gymnasium")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gymnasium.make(env_id, **kwargs).unwrapped.model


def test_the_committed_files_are_the_tables_output() -> None:
    files = sorted(p.name for p in _model_table.ASSETS.glob("*.xml"))
    assert files == sorted(_model_table.MODELS)
    for name, model in _model_table.MODELS.items():
        text = (_model_table.ASSETS / name).read_text(encoding="utf-8")
        assert text == _model_table.to_mjcf(model), f"{name}: run the generator again"


def test_the_generator_writes_every_model(tmp_path: Path) -> None:
    written = _model_table.write_all(tmp_path)
    assert sorted(p.name for p in written) == sorted(_model_table.MODELS)
    for path in written:
        assert path.read_bytes() == (_model_table.ASSETS / path.name).read_bytes()


def test_the_comparison_covers_the_model_and_sees_one_changed_number(tmp_path: Path) -> None:
    ours = palaestra.make("Hopper-v5").unwrapped
    fields = model_fields(ours.model)
    assert len(fields) > 500
    for key in (
        "body_mass",
        "body_inertia",
        "geom_size",
        "jnt_range",
        "actuator_gear",
        "opt.timestep",
        "opt.integrator",
        "nq",
        "vis.global_.offwidth",
        "stat.extent",
    ):
        assert key in fields, key
    text = Path(ours.fullpath).read_text().replace('size="0.06 0.195"', 'size="0.06 0.1950001"')
    (tmp_path / "hopper.xml").write_text(text)
    changed = palaestra.make("Hopper-v5", xml_file=str(tmp_path / "hopper.xml")).unwrapped
    assert "geom_size" in differing_fields(ours.model, changed.model)
    assert differing_fields(ours.model, ours.model) == []


@pytest.mark.parametrize("env_id", MUJOCO_IDS)
def test_the_model_equals_gymnasiums(env_id: str) -> None:
    ours = palaestra.make(env_id).unwrapped
    assert Path(ours.fullpath).parent == Path(palaestra.__file__).parent / "envs/mujoco/assets"
    assert differing_fields(ours.model, _gymnasium_model(env_id)) == []


def test_a_copy_of_a_model_given_as_xml_file_is_the_same_model(tmp_path: Path) -> None:
    copy = tmp_path / "my_walker.xml"
    shutil.copy(_model_table.ASSETS / "walker2d_v5.xml", copy)
    ours = palaestra.make("Walker2d-v5", xml_file=str(copy)).unwrapped
    assert ours.fullpath == str(copy)
    assert differing_fields(ours.model, _gymnasium_model("Walker2d-v5")) == []


def test_frame_size_grows_the_offscreen_buffer_as_gymnasiums() -> None:
    ours = palaestra.make("Reacher-v5", width=1000, height=700).unwrapped
    ref = _gymnasium_model("Reacher-v5", width=1000, height=700)
    assert (ours.model.vis.global_.offwidth, ours.model.vis.global_.offheight) == (1000, 700)
    assert differing_fields(ours.model, ref) == []
