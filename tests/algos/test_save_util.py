"""``palaestra.algos.save_util`` against SB3's ``save_util``: the same values and files, SB3 and
palaestra reading each other's archives, and palaestra's differences: nothing pickled is loaded
unless ``allow_pickle=True`` (or ``custom_objects`` gives it), and files are written atomically."""

from __future__ import annotations

import io
import pathlib
import pickle
import zipfile

import numpy as np
import pytest
import torch
from stable_baselines3 import PPO as SB3PPO
from stable_baselines3.common import save_util as sb3

from palaestra.algos import PPO, save_util
from palaestra.algos.save_util import UnsafeFileError


class Holder:
    def __init__(self) -> None:
        self.inner = types_namespace(name="test", value=3)


def types_namespace(**kwargs: object) -> object:
    import types

    return types.SimpleNamespace(**kwargs)


def test_recursive_getattr_and_setattr_are_sb3s() -> None:
    for module in (save_util, sb3):
        holder = Holder()
        assert module.recursive_getattr(holder, "inner.name") == "test"
        assert module.recursive_getattr(holder, "inner.missing", None) is None
        module.recursive_setattr(holder, "inner.name", "hello")
        module.recursive_setattr(holder, "top", 1)
        assert (holder.inner.name, holder.top) == ("hello", 1)  # type: ignore[attr-defined]
        with pytest.raises(AttributeError):
            module.recursive_getattr(holder, "inner.missing")


@pytest.mark.parametrize(
    "item", [1, 2.5, "a", None, [1, {"b": [True]}], {"x": 1}, np.zeros(2), {1, 2}, Holder, object()]
)
def test_is_json_serializable_is_sb3s(item: object) -> None:
    assert save_util.is_json_serializable(item) is sb3.is_json_serializable(item)


DATA = {
    "gamma": 0.99,
    "net_arch": [64, 64],
    "name": "PPO",
    "array": np.arange(3.0),
    "kwargs": {"activation_fn": torch.nn.ReLU, "n": 2},
    "function": len,
}


def test_data_to_json_writes_sb3s_json() -> None:
    ours = save_util.data_to_json(DATA)
    assert ours == sb3.data_to_json(DATA)
    back = sb3.json_to_data(ours)
    np.testing.assert_array_equal(back.pop("array"), DATA["array"])
    assert back == {k: v for k, v in DATA.items() if k != "array"}


def test_json_to_data_refuses_pickles_unless_allowed() -> None:
    text = sb3.data_to_json(DATA)
    with pytest.raises(UnsafeFileError, match=r"'array' is a pickled <class 'numpy\.ndarray'>"):
        save_util.json_to_data(text)
    given = {"array": "mine", "kwargs": {}, "function": print}
    plain = save_util.json_to_data(text, custom_objects=given)
    assert plain == {"gamma": 0.99, "net_arch": [64, 64], "name": "PPO", **given}
    allowed = save_util.json_to_data(text, allow_pickle=True)
    expected = sb3.json_to_data(text)
    np.testing.assert_array_equal(allowed.pop("array"), expected.pop("array"))
    assert allowed == expected
    with pytest.raises(
        ValueError, match="custom_objects argument must be a dict or None, got list"
    ):
        save_util.json_to_data(text, custom_objects=[])  # type: ignore[arg-type]


def _state() -> dict[str, torch.Tensor]:
    return {"w": torch.arange(6.0).reshape(2, 3), "b": torch.ones(2, dtype=torch.float64)}


def _same(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> None:
    assert a.keys() == b.keys()
    for key in a:
        torch.testing.assert_close(a[key], b[key], rtol=0, atol=0)


def test_sb3_reads_palaestras_archive(tmp_path: pathlib.Path) -> None:
    save_util.save_to_zip_file(
        tmp_path / "m", {"gamma": 0.9}, {"policy": _state()}, {"log_ent_coef": torch.zeros(1)}
    )
    assert (tmp_path / "m.zip").is_file() and not (tmp_path / "m").exists()
    data, params, variables = sb3.load_from_zip_file(tmp_path / "m", device="cpu")
    assert data == {"gamma": 0.9}
    _same(params["policy"], _state())
    _same(variables, {"log_ent_coef": torch.zeros(1)})
    names = zipfile.ZipFile(tmp_path / "m.zip").namelist()
    assert {"data", "policy.pth", "pytorch_variables.pth", "system_info.txt"} <= set(names)


def test_palaestra_reads_sb3s_archive_and_refuses_its_pickles(tmp_path: pathlib.Path) -> None:
    model = torch.nn.Linear(3, 2)
    optimizer = torch.optim.Adam(model.parameters())
    model(torch.ones(3)).sum().backward()
    optimizer.step()
    path = tmp_path / "sb3.zip"
    params = {"policy": model.state_dict(), "policy.optimizer": optimizer.state_dict()}
    sb3.save_to_zip_file(path, {"gamma": 0.9, "f": len}, params, {"v": torch.ones(1)})
    with pytest.raises(UnsafeFileError, match=r"policy\.optimizer\.pth in .* allow_pickle=True"):
        save_util.load_from_zip_file(path, custom_objects={"f": None}, device="cpu")
    with pytest.raises(UnsafeFileError, match=r"'f' is a pickled <class 'builtin_function"):
        save_util.load_from_zip_file(path, device="cpu")
    data, ours, variables = save_util.load_from_zip_file(path, device="cpu", allow_pickle=True)
    sb3_data, theirs, sb3_variables = sb3.load_from_zip_file(path, device="cpu")
    assert data == sb3_data == {"gamma": 0.9, "f": len}
    assert ours.keys() == theirs.keys() == {"policy", "policy.optimizer"}
    _same(ours["policy"], theirs["policy"])
    assert ours["policy.optimizer"]["param_groups"] == theirs["policy.optimizer"]["param_groups"]
    _same(variables, sb3_variables)
    # weights alone need no pickle: a file of state_dicts only
    sb3.save_to_zip_file(tmp_path / "w.zip", {"gamma": 0.5}, {"policy": model.state_dict()})
    data, weights, variables = save_util.load_from_zip_file(tmp_path / "w", device="cpu")
    assert (data, variables) == ({"gamma": 0.5}, None)
    _same(weights["policy"], model.state_dict())
    assert save_util.load_from_zip_file(tmp_path / "w", load_data=False, device="cpu")[0] is None


def test_an_sb3_model_file_reads_as_sb3_reads_it(tmp_path: pathlib.Path) -> None:
    SB3PPO("MlpPolicy", "CartPole-v1", n_steps=16, batch_size=16, device="cpu").save(tmp_path / "p")
    ours = save_util.load_from_zip_file(tmp_path / "p", device="cpu", allow_pickle=True)
    theirs = sb3.load_from_zip_file(tmp_path / "p", device="cpu")
    assert ours[0] is not None and theirs[0] is not None
    assert ours[0].keys() == theirs[0].keys() and ours[0]["n_steps"] == theirs[0]["n_steps"]
    _same(ours[1]["policy"], theirs[1]["policy"])


def test_system_info_is_printed(tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]) -> None:
    save_util.save_to_zip_file(tmp_path / "m.zip", {"a": 1})
    assert save_util.load_from_zip_file(tmp_path / "m.zip", print_system_info=True)[0] == {"a": 1}
    out = capsys.readouterr().out
    assert out.startswith("== SAVED MODEL SYSTEM INFO ==\n") and "palaestra" in out
    with zipfile.ZipFile(tmp_path / "old.zip", "w") as archive:
        archive.writestr("data", "{}")
    with pytest.warns(UserWarning, match=r"saved with SB3 <= 1\.2\.0"):
        save_util.load_from_zip_file(tmp_path / "old.zip", print_system_info=True)


def test_what_is_not_an_sb3_archive_is_named(tmp_path: pathlib.Path) -> None:
    (tmp_path / "x.zip").write_bytes(b"not a zip")
    with pytest.raises(ValueError, match=r"Error: the file .*x\.zip wasn't a zip-file"):
        save_util.load_from_zip_file(tmp_path / "x.zip")
    PPO("MlpPolicy", "CartPole-v1", n_steps=16, batch_size=16).save(tmp_path / "ours")
    with pytest.raises(ValueError, match=r"is a palaestra model file, not an SB3-layout archive"):
        save_util.load_from_zip_file(tmp_path / "ours.zip")


def test_pickles_are_written_and_read_only_when_allowed(tmp_path: pathlib.Path) -> None:
    obj = {"a": np.arange(3), "f": len}
    save_util.save_to_pkl(tmp_path / "obj", obj)
    assert (tmp_path / "obj.pkl").is_file()
    with pytest.raises(UnsafeFileError, match=r"would unpickle the file.*allow_pickle=True"):
        save_util.load_from_pkl(tmp_path / "obj")
    with pytest.raises(UnsafeFileError):  # refused before anything is opened
        save_util.load_from_pkl(tmp_path / "missing")
    for back in (
        save_util.load_from_pkl(tmp_path / "obj", allow_pickle=True),
        sb3.load_from_pkl(tmp_path / "obj"),
    ):
        np.testing.assert_array_equal(back["a"], obj["a"])
        assert back["f"] is len
    buffer = io.BytesIO()
    save_util.save_to_pkl(buffer, [1, 2])
    buffer.seek(0)
    assert save_util.load_from_pkl(buffer, allow_pickle=True) == [1, 2]


def test_open_path_has_sb3s_conveniences(tmp_path: pathlib.Path) -> None:
    with save_util.open_path(str(tmp_path / "a"), "w", suffix="zip") as file:
        file.write(b"x")
    assert (tmp_path / "a.zip").read_bytes() == b"x"
    with save_util.open_path(tmp_path / "a", "r", suffix="zip") as file:  # found as a.zip
        assert file.read() == b"x"
    (tmp_path / "d.zip").mkdir()
    with pytest.warns(UserWarning, match=r"is a folder\. Will save instead to .*d\.zip_2"):
        save_util.open_path(tmp_path / "d.zip", "w").close()
    assert (tmp_path / "d.zip_2").is_file()
    with pytest.warns(UserWarning, match=r"new/sub' does not exist\. Will create it\."):
        save_util.open_path(tmp_path / "new" / "sub" / "f.pkl", "w").close()
    with pytest.raises(FileNotFoundError):
        save_util.open_path(tmp_path / "nothing", "r", suffix="zip")


def test_open_path_checks_file_objects_as_sb3() -> None:
    for module in (save_util, sb3):
        with pytest.raises(TypeError, match="parameter has invalid type"):
            module.open_path(io.StringIO(), "r")
        closed = io.BytesIO()
        closed.close()
        with pytest.raises(ValueError, match="is closed"):
            module.open_path(closed, "w")
        with pytest.raises(ValueError, match="Expected mode to be either 'w' or 'r'"):
            module.open_path(io.BytesIO(), "x")
        reader = io.BufferedReader(io.BytesIO(b"1"))
        with pytest.raises(ValueError, match="Expected a writable file"):
            module.open_path(reader, "write")
        assert module.open_path(reader, "read") is reader


def test_a_failed_write_leaves_the_old_file(tmp_path: pathlib.Path) -> None:
    target = tmp_path / "keep.zip"
    target.write_bytes(b"old")
    with pytest.raises(RuntimeError, match="boom"):
        with save_util.open_path(target, "w") as file:
            file.write(b"half")
            raise RuntimeError("boom")
    assert target.read_bytes() == b"old"
    with pytest.raises((pickle.PicklingError, AttributeError)):  # torch.save cannot
        save_util.save_to_zip_file(target, {"a": 1}, params={"p": {"f": lambda: 0}})
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.zip"]  # no temporary left
