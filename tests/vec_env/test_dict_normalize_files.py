"""The ``VecNormalize`` statistics file for Dict observations (``palaestra.VecNormalize/2``):
round trip, the /1 files of Box runs still read exactly as before, and every damaged or
crafted /2 file a ``ModelFileError`` naming the file and what is wrong."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.compat.crafted import npy, zip_of
from tests.vec_env.test_dict_normalize import N, OurWalker

from palaestra.utils.bounded_zip import ModelFileError
from palaestra.vec_env import DummyVecEnv, VecNormalize, make_vec_env


def _venv(extra: tuple[str, ...] = ("flag",), seed: int = 4) -> DummyVecEnv:
    venv = DummyVecEnv([lambda: OurWalker(extra) for _ in range(N)])
    venv.seed(seed)
    return venv


def _trained(keys: list[str] | None = None, steps: int = 50) -> VecNormalize:
    norm = VecNormalize(_venv(), norm_obs_keys=keys or ["vel", "pos"], clip_obs=7.5, gamma=0.9)
    norm.reset()
    for i in range(steps):
        norm.step(np.full(N, i % 2))
    return norm


def _settings_of(path: Path) -> dict[str, Any]:
    with np.load(path) as data:
        return json.loads(str(data["settings"][()]))


def test_round_trip_keeps_every_statistic_and_setting(tmp_path: Path) -> None:
    norm = _trained()
    path = tmp_path / "stats.npz"
    norm.save(path)
    settings = _settings_of(path)
    assert settings["format"] == "palaestra.VecNormalize/2"
    assert settings["norm_obs_keys"] == ["vel", "pos"]  # the order they were given in
    with zipfile.ZipFile(path) as zf:
        assert sorted(zf.namelist()) == sorted(
            ["settings.npy", "ret_mean.npy", "ret_var.npy"]
            + [f"obs_{s}_{i}.npy" for i in range(2) for s in ("mean", "var")]
        )
    loaded = VecNormalize.load(path, _venv())
    assert loaded.norm_obs_keys == ["vel", "pos"] and list(loaded.obs_rms) == ["vel", "pos"]
    assert isinstance(loaded.obs_rms, dict) and isinstance(norm.obs_rms, dict)
    for key, rms in norm.obs_rms.items():
        assert loaded.obs_rms[key].mean.tobytes() == rms.mean.tobytes()
        assert loaded.obs_rms[key].var.tobytes() == rms.var.tobytes()
        assert loaded.obs_rms[key].count == rms.count == 51 * N + 1e-4
    assert loaded.ret_rms.mean == norm.ret_rms.mean and loaded.ret_rms.var == norm.ret_rms.var
    assert loaded.ret_rms.count == norm.ret_rms.count
    assert (loaded.clip_obs, loaded.gamma, loaded.training) == (7.5, 0.9, True)
    # the loaded wrapper scales as the saved one did
    raw = norm.get_original_obs()
    for key, value in norm.normalize_obs(raw).items():
        np.testing.assert_array_equal(loaded.normalize_obs(raw)[key], value)


def test_box_statistics_are_still_written_as_format_1(tmp_path: Path) -> None:
    norm = VecNormalize(make_vec_env("MountainCar-v0", n_envs=2, seed=0))
    norm.reset()
    norm.step(np.array([0, 2]))
    norm.save(tmp_path / "box.npz")
    settings = _settings_of(tmp_path / "box.npz")
    assert list(settings) == [
        "format", "training", "norm_obs", "norm_reward", "clip_obs", "clip_reward", "gamma",
        "epsilon", "obs_count", "ret_count",
    ]  # fmt: skip
    assert settings["format"] == "palaestra.VecNormalize/1"
    with zipfile.ZipFile(tmp_path / "box.npz") as zf:
        names = zf.namelist()
    assert names == ["settings.npy", "obs_mean.npy", "obs_var.npy", "ret_mean.npy", "ret_var.npy"]


# A /1 file as palaestra wrote them before Dict support, member by member: values whose bits
# any rounding would change.
OBS_MEAN = np.array([0.1 + 0.2, -1 / 3])
OBS_VAR = np.array([np.nextafter(2.0, 3.0), 1e-300])
V1_SETTINGS = {
    "format": "palaestra.VecNormalize/1", "training": False, "norm_obs": True,
    "norm_reward": True, "clip_obs": 5.0, "clip_reward": 3.0, "gamma": 0.97,
    "epsilon": 1e-8, "obs_count": 1234.0001, "ret_count": 77.0001,
}  # fmt: skip


def _v1_file(path: Path, **changes: Any) -> Path:
    path.write_bytes(
        zip_of(
            {
                "settings.npy": npy(np.array(json.dumps({**V1_SETTINGS, **changes}))),
                "obs_mean.npy": npy(OBS_MEAN),
                "obs_var.npy": npy(OBS_VAR),
                "ret_mean.npy": npy(np.array(0.25)),
                "ret_var.npy": npy(np.array(1 / 7)),
            }
        )
    )
    return path


def test_a_format_1_file_loads_bit_for_bit(tmp_path: Path) -> None:
    norm = VecNormalize.load(_v1_file(tmp_path / "v1.npz"), make_vec_env("MountainCar-v0"))
    assert not isinstance(norm.obs_rms, dict) and norm.norm_obs_keys is None
    assert norm.obs_rms.mean.tobytes() == OBS_MEAN.tobytes()
    assert norm.obs_rms.var.tobytes() == OBS_VAR.tobytes()
    assert norm.obs_rms.count == 1234.0001 and norm.ret_rms.count == 77.0001
    assert norm.ret_rms.mean == 0.25 and norm.ret_rms.var == 1 / 7
    assert (norm.training, norm.clip_obs, norm.clip_reward, norm.gamma) == (False, 5.0, 3.0, 0.97)
    # saved again, it is the same /1 file (statistics and settings)
    norm.save(tmp_path / "again.npz")
    assert _settings_of(tmp_path / "again.npz") == V1_SETTINGS
    with np.load(tmp_path / "again.npz") as data:
        assert data["obs_mean"].tobytes() == OBS_MEAN.tobytes()
        assert data["obs_var"].tobytes() == OBS_VAR.tobytes()


def test_files_and_envs_that_do_not_fit_are_clear_errors(tmp_path: Path) -> None:
    v1 = _v1_file(tmp_path / "v1.npz")
    box_file = (
        r"holds statistics of Box observations \(format palaestra.VecNormalize/1\), but the "
        r"env's observations are Dict"
    )
    with pytest.raises(ModelFileError, match=box_file):
        VecNormalize.load(v1, _venv(()))
    # a Box file without observation statistics fits a Dict env (nothing to normalise)
    VecNormalize(make_vec_env("MountainCar-v0"), norm_obs=False).save(tmp_path / "off.npz")
    plain = VecNormalize.load(tmp_path / "off.npz", _venv())
    assert plain.norm_obs is False and plain.reset().keys() == {"flag", "pos", "vel"}
    v2 = tmp_path / "v2.npz"
    _trained().save(v2)
    dict_file = r"holds statistics of Dict observation keys \['vel', 'pos'\], but the env's .* Box"
    with pytest.raises(ModelFileError, match=dict_file):
        VecNormalize.load(v2, make_vec_env("MountainCar-v0"))
    other = DummyVecEnv([lambda: _Renamed()])
    lacking = (
        r"holds statistics of observation keys \['vel'\] that the env's observations lack "
        r"\(they have \['flag', 'pos', 'speed'\]"
    )
    with pytest.raises(ModelFileError, match=lacking):
        VecNormalize.load(v2, other)
    for path in (v1, v2):
        with pytest.raises(ModelFileError) as info:
            VecNormalize.load(path, _venv(()) if path is v1 else other)
        assert str(path) in str(info.value)


class _Renamed(OurWalker):  # type: ignore[misc, valid-type]
    """The walker with its "vel" key called "speed"."""

    def __init__(self) -> None:
        super().__init__(("flag",))
        from palaestra import spaces

        parts = dict(self.observation_space.spaces)
        parts["speed"] = parts.pop("vel")
        self.observation_space = spaces.Dict(parts)


@pytest.fixture(scope="module")
def members(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """The members of a /2 file ``save`` wrote, for the tests to damage one at a time."""
    path = tmp_path_factory.mktemp("dictnorm") / "stats.npz"
    _trained(steps=5).save(path)
    with zipfile.ZipFile(path) as zf:
        return {n: zf.read(n) for n in zf.namelist()}


def _settings(**changes: Any) -> bytes:
    settings = {
        "format": "palaestra.VecNormalize/2", "training": True, "norm_obs": True,
        "norm_reward": True, "clip_obs": 10.0, "clip_reward": 10.0, "gamma": 0.99,
        "epsilon": 1e-8, "norm_obs_keys": ["vel", "pos"], "obs_counts": [5.0, 5.0],
        "ret_count": 5.0,
    }  # fmt: skip
    settings.update(changes)
    return npy(np.array(json.dumps({k: v for k, v in settings.items() if v is not ...})))


CASES = {
    "wrong shape": ({"obs_mean_1.npy": npy(np.zeros(3))},
                    r"saved 'obs_mean' statistics of key 'pos' have shape \(3,\), but the env's "
                    r"'pos' observations have shape \(2,\)"),
    "swapped keys": ({"settings.npy": _settings(norm_obs_keys=["pos", "vel"])},
                     r"saved 'obs_mean' statistics of key 'pos' have shape \(3,\)"),
    "missing member": ({"obs_var_0.npy": None},
                       r"the 'obs_var' statistics of key 'vel' are missing"),
    "negative variance": ({"obs_var_1.npy": npy(np.array([1.0, -2.0]))},
                          r"the 'obs_var' statistics of key 'pos' hold negative variances"),
    "infinite mean": ({"obs_mean_0.npy": npy(np.array([0.0, np.inf, 0.0]))},
                      r"the 'obs_mean' statistics of key 'vel' hold NaN or infinite values"),
    "object array": ({"obs_mean_0.npy": npy(np.array([object()] * 3, dtype=object))},
                     r"member 'obs_mean_0.npy' holds dtype object, not <f4, <f8"),
    "too few counts": ({"settings.npy": _settings(obs_counts=[5.0])},
                       r"setting 'obs_counts' is \[5.0\], expected 2 finite numbers > 0, one per"),
    "zero count": ({"settings.npy": _settings(obs_counts=[5.0, 0])},
                   r"setting 'obs_counts' is \[5.0, 0\], expected 2 finite numbers > 0"),
    "counts not a list": ({"settings.npy": _settings(obs_counts="5")},
                          r"setting 'obs_counts' is '5', expected 2 finite numbers > 0"),
    "duplicate keys": ({"settings.npy": _settings(norm_obs_keys=["vel", "vel"])},
                       r"setting 'norm_obs_keys' is \['vel', 'vel'\], expected a non-empty list "
                       r"of distinct strings"),
    "no keys": ({"settings.npy": _settings(norm_obs_keys=[], obs_counts=[])},
                r"setting 'norm_obs_keys' is \[\], expected a non-empty list of distinct"),
    "key not a string": ({"settings.npy": _settings(norm_obs_keys=["vel", 3])},
                         r"setting 'norm_obs_keys' is \['vel', 3\], expected a non-empty list"),
    "keys missing": ({"settings.npy": _settings(norm_obs_keys=...)},
                     r"setting 'norm_obs_keys' is None, expected a non-empty list"),
    "non-Box key": ({"settings.npy": _settings(norm_obs_keys=["vel", "flag"])},
                    r"its settings do not fit the env \(VecNormalize only supports `gym.spaces."
                    r"Box` observation spaces but flag is of type Discrete\(3\)"),
    "norm_obs off": ({"settings.npy": _settings(norm_obs=False)},
                     r"setting 'norm_obs' is False, expected true in a palaestra.VecNormalize/2"),
    "nan count": ({"settings.npy": _settings(ret_count=float("nan"))},
                  r"setting 'ret_count' is nan, expected a finite number > 0"),
    "unknown format": ({"settings.npy": _settings(format="palaestra.VecNormalize/3")},
                       r"is not a palaestra VecNormalize file"),
    "oversized member": ({"obs_var_1.npy": npy(np.zeros(1 << 20))},
                         r"member 'obs_var_1.npy' declares 8388608 bytes of data \(shape "
                         r"\(1048576,\)\), more than the limit of 65552 bytes"),
}  # fmt: skip


@pytest.mark.parametrize("case", list(CASES))
def test_bad_dict_files_are_clear_errors(
    case: str, members: dict[str, bytes], tmp_path: Path
) -> None:
    changes, message = CASES[case]
    edited = {k: v for k, v in {**members, **changes}.items() if v is not None}  # None: gone
    path = tmp_path / "bad.npz"
    path.write_bytes(zip_of(edited))
    with pytest.raises(ModelFileError, match=message) as info:
        VecNormalize.load(path, _venv())
    assert str(path) in str(info.value)


def test_the_undamaged_members_load(members: dict[str, bytes], tmp_path: Path) -> None:
    path = tmp_path / "good.npz"
    path.write_bytes(zip_of(members))
    norm = VecNormalize.load(path, _venv())
    assert isinstance(norm.obs_rms, dict)
    assert [rms.count for rms in norm.obs_rms.values()] == [6 * N + 1e-4] * 2
