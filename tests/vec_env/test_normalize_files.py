"""``VecNormalize.load`` on damaged and crafted files: each is a ``ModelFileError`` (a
``ValueError``) naming the file and what is wrong, never a KeyError, a pickle or a silent NaN."""

from __future__ import annotations

import json
import time
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.compat.crafted import forge_size, npy, zip_of

from palaestra.utils.bounded_zip import ModelFileError
from palaestra.vec_env import VecNormalize, make_vec_env


def _venv() -> Any:
    return make_vec_env("MountainCar-v0", n_envs=1)


@pytest.fixture(scope="module")
def members(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """The members of a file ``save`` wrote, for the tests to damage one at a time."""
    path = tmp_path_factory.mktemp("norm") / "stats.npz"
    norm = VecNormalize(_venv())
    norm.reset()
    norm.step(np.array([2]))
    norm.save(path)
    with zipfile.ZipFile(path) as zf:
        return {n: zf.read(n) for n in zf.namelist()}


def _settings(**changes: Any) -> bytes:
    settings = {
        "format": "palaestra.VecNormalize/1", "training": True, "norm_obs": True,
        "norm_reward": True, "clip_obs": 10.0, "clip_reward": 10.0, "gamma": 0.99,
        "epsilon": 1e-8, "obs_count": 2.0, "ret_count": 2.0,
    }  # fmt: skip
    settings.update(changes)
    return npy(np.array(json.dumps({k: v for k, v in settings.items() if v is not ...})))


CASES = {
    "negative variance": ({"obs_var.npy": npy(np.array([1.0, -0.5]))},
                          r"'obs_var' statistics hold negative variances"),
    "nan mean": ({"obs_mean.npy": npy(np.array([np.nan, 0.0]))},
                 r"'obs_mean' statistics hold NaN or infinite values"),
    "wrong shape": ({"obs_mean.npy": npy(np.zeros(4))},
                    r"saved 'obs_mean' statistics have shape \(4,\), but the env's observations "
                    r"have shape \(2,\)"),
    "missing statistics": ({"ret_var.npy": None}, r"the 'ret_var' statistics are missing"),
    "missing settings": ({"settings.npy": None}, r"not a palaestra VecNormalize file \(no settin"),
    "missing key": ({"settings.npy": _settings(gamma=...)},
                    r"setting 'gamma' is None, expected a number in \[0, 1\]"),
    "negative count": ({"settings.npy": _settings(obs_count=-1.0)},
                       r"setting 'obs_count' is -1.0, expected a finite number > 0"),
    "string flag": ({"settings.npy": _settings(norm_obs="yes")},
                    r"setting 'norm_obs' is 'yes', expected true or false"),
    "huge int": ({"settings.npy": _settings(clip_obs=10**400)},
                 r"setting 'clip_obs' is 1000000000.*, expected a finite number > 0"),
    "pickle": ({"obs_mean.npy": npy(np.array([object(), 1], dtype=object))},
               r"member 'obs_mean.npy' holds dtype object, not <f4, <f8"),
    "pickled settings": ({"settings.npy": npy(np.array({"format": 1}, dtype=object))},
                         r"member 'settings.npy' holds dtype object, not a plain numeric array"),
    "oversized member": ({"obs_var.npy": npy(np.zeros(1 << 20))},
                         r"member 'obs_var.npy' declares 8388608 bytes of data \(shape "
                         r"\(1048576,\)\), more than the limit of 65552 bytes"),
}  # fmt: skip


@pytest.mark.parametrize("case", list(CASES))
def test_bad_files_are_clear_errors(case: str, members: dict[str, bytes], tmp_path: Path) -> None:
    changes, message = CASES[case]
    edited = {k: v for k, v in {**members, **changes}.items() if v is not None}  # None: gone
    path = tmp_path / "bad.npz"
    path.write_bytes(zip_of(edited))
    with pytest.raises(ModelFileError, match=message) as info:
        VecNormalize.load(path, _venv())
    assert str(path) in str(info.value)


def test_the_original_loads_and_damage_is_refused(
    members: dict[str, bytes], tmp_path: Path
) -> None:
    path = tmp_path / "good.npz"
    path.write_bytes(zip_of(members))
    assert VecNormalize.load(path, _venv()).obs_rms.count == pytest.approx(2.0001)
    start = time.process_time()
    path.write_bytes(forge_size(zip_of(members), "obs_var.npy", 3_000_000_000))
    with pytest.raises(ModelFileError, match=r"member 'obs_var.npy' declares 3000000000 bytes"):
        VecNormalize.load(path, _venv())
    assert time.process_time() - start < 0.5
    path.write_bytes(zip_of(members)[:-40])
    with pytest.raises(ModelFileError, match=r"is not a palaestra VecNormalize file"):
        VecNormalize.load(path, _venv())
