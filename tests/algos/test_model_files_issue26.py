"""Issue 26, model files: whatever ``save`` writes, ``load`` reads (no fixed weight cap, a file
bounded by its own size), streamed both ways, and ``load``'s SB3 keywords (``print_system_info``,
``policy_kwargs`` equal to the stored one, ``custom_objects``), side by side with SB3."""

from __future__ import annotations

import importlib.util
import json
import tracemalloc
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from palaestra.algos import A2C, PPO, TD3, ModelFileError
from palaestra.algos.common import hyperparams as hp
from palaestra.algos.common.model_io import read_arrays, read_manifest, write_archive

HAS_SB3 = importlib.util.find_spec("stable_baselines3") is not None
needs_sb3 = pytest.mark.skipif(not HAS_SB3, reason="stable-baselines3 (dev dependency) missing")
MIB = 1 << 20


def _raised(fn: Any) -> BaseException | None:
    try:
        fn()
    except BaseException as exc:  # the exception is the result
        return exc
    return None


# -- above the old cap -------------------------------------------------------------------------
WIDE = 10_001  # one 10001 x 10001 layer: 100,020,001 weights, over the old 10**8 cap


def test_a_model_above_the_old_weight_cap_saves_and_loads_streamed(tmp_path: Path) -> None:
    """SB3's large-model test, at the smallest model the old cap refused (a 400 MB file): it
    loads, with its weights, and neither save nor load holds a second copy of them (numpy's
    allocations, which tracemalloc sees, stay far below the model's size)."""
    assert WIDE * WIDE > hp.MAX_NET_PARAMETERS
    kwargs = {
        "policy_kwargs": {"net_arch": {"pi": [WIDE, WIDE], "vf": []}, "ortho_init": False},
        "device": "cpu",
    }
    model = A2C("MlpPolicy", "Pendulum-v1", seed=0, **kwargs)
    weight = model.policy.state_dict()["pi_net.2.weight"]
    assert weight.shape == (WIDE, WIDE)
    probe = weight[::997, ::991].clone()
    tracemalloc.start()
    try:
        model.save(tmp_path / "wide")
        _, save_peak = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        loaded = A2C.load(tmp_path / "wide", **kwargs)  # SB3's call: the same policy_kwargs
        _, load_peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert (tmp_path / "wide.zip").stat().st_size > 400 * 1000**2
    with zipfile.ZipFile(tmp_path / "wide.zip") as zf:  # stored, as SB3's: no deflate cost
        assert {i.compress_type for i in zf.infolist() if i.filename.endswith(".npy")} == {0}
    torch.testing.assert_close(
        loaded.policy.state_dict()["pi_net.2.weight"][::997, ::991], probe, rtol=0, atol=0
    )
    assert save_peak < 64 * MIB, save_peak
    assert load_peak < 64 * MIB, load_peak
    obs = np.zeros((2, 3), dtype=np.float32)
    np.testing.assert_array_equal(
        loaded.predict(obs, deterministic=True)[0], model.predict(obs, deterministic=True)[0]
    )


def test_loading_reads_weights_straight_into_the_parameters(tmp_path: Path) -> None:
    """The same stream on a small model (the default suite): the loaded parameters are the
    saved ones, and loading allocates (in numpy, which tracemalloc sees) no more than building
    the model does, not another copy of its weights."""
    kwargs = {"policy_kwargs": {"net_arch": [1024, 1024]}, "seed": 1}
    model = PPO("MlpPolicy", "CartPole-v1", **kwargs)
    model.save(tmp_path / "m")
    PPO.load(tmp_path / "m")  # imports done: they are not what is measured

    def peak_of(fn: Any) -> tuple[Any, int]:
        tracemalloc.start()
        try:
            result = fn()
            return result, tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    _, build_peak = peak_of(lambda: PPO("MlpPolicy", "CartPole-v1", **kwargs))
    loaded, load_peak = peak_of(lambda: PPO.load(tmp_path / "m"))
    params = sum(p.numel() * 4 for p in model.policy.parameters())
    # what is left: the zip reader's 1 MiB chunks, whatever the model's size
    assert params > 8 * MIB and load_peak < build_peak + params / 2, (params, build_peak, load_peak)
    for key, value in model.policy.state_dict().items():
        torch.testing.assert_close(loaded.policy.state_dict()[key], value, rtol=0, atol=0)


def test_a_file_must_hold_the_network_it_declares(tmp_path: Path) -> None:
    """No fixed cap, and no bomb either: a small file naming a huge net_arch is refused before
    the network is built (it must hold the weights it asks for)."""
    model = TD3("MlpPolicy", "Pendulum-v1", policy_kwargs={"net_arch": [8]})
    model.save(tmp_path / "m")
    with zipfile.ZipFile(tmp_path / "m.zip") as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    manifest = json.loads(members["palaestra.json"])
    manifest["meta"]["policy_kwargs"]["net_arch"] = [65_536] * 64
    members["palaestra.json"] = json.dumps(manifest).encode()
    forged = tmp_path / "forged.zip"
    with zipfile.ZipFile(forged, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    tracemalloc.start()
    try:
        error = _raised(lambda: TD3.load(forged))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert isinstance(error, ModelFileError)
    held = sum(p.numel() for p in model.policy.state_dict().values())
    assert str(error) == (
        f"{forged}: policy_kwargs net_arch=[65536, 65536, 65536, 65536, 65536, 65536, ...] needs "
        f"at least {63 * 65_536**2} weights, but the file's parameters hold {held}"
    )
    assert peak < 16 * MIB


def test_only_deflated_bytes_count_against_max_bytes(tmp_path: Path) -> None:
    """A stored member holds its bytes on disk: a model file is never refused for its size."""
    big = {"w": np.ones((256, 1024), dtype=np.float32)}  # 1 MiB
    write_archive(tmp_path / "stored.zip", "model", {}, big, compress=False)
    write_archive(tmp_path / "deflated.zip", "model", {}, big)
    assert read_arrays(read_manifest(tmp_path / "stored.zip", "model", max_bytes=1000))["w"].sum()
    with pytest.raises(ModelFileError, match=r"its deflated arrays declare 1048576 bytes in all"):
        read_manifest(tmp_path / "deflated.zip", "model", max_bytes=1000)


def test_write_archive_takes_tensors_and_writes_np_save_bytes(tmp_path: Path) -> None:
    """Tensors are written as they are (no host copy made up front), as ``np.save`` would."""
    tensor = torch.arange(12, dtype=torch.float32).reshape(3, 4)
    write_archive(tmp_path / "t.zip", "model", {}, {"t": tensor, "b": np.array([True])})
    with zipfile.ZipFile(tmp_path / "t.zip") as zf:
        raw = zf.read("arrays/00000.npy")
    import io

    expected = io.BytesIO()
    np.save(expected, tensor.numpy())
    assert raw == expected.getvalue()
    with pytest.raises(TypeError, match=r"cannot store array 'x' of dtype torch\.bfloat16"):
        write_archive(tmp_path / "b.zip", "model", {}, {"x": tensor.bfloat16()})


# -- load's SB3 keywords -----------------------------------------------------------------------
@needs_sb3
def test_load_print_system_info_and_custom_objects_as_sb3(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """SB3's test_exclude_include_saved_params call: custom objects the model saves replace
    the file's, others are ignored, and both system infos are printed."""
    from stable_baselines3 import PPO as SB3PPO

    custom = {"learning_rate": 2e-5, "dummy": 1.0}
    for cls, path in ((PPO, tmp_path / "ours"), (SB3PPO, tmp_path / "sb3")):
        cls("MlpPolicy", "CartPole-v1", policy_kwargs={"net_arch": [16]}, verbose=2).save(path)
        capsys.readouterr()
        model = cls.load(f"{path}.zip", custom_objects=custom, print_system_info=True)
        out = capsys.readouterr().out
        assert model.verbose == 2 and model.learning_rate == 2e-5
        assert not hasattr(model, "dummy")
        assert out.index("== CURRENT SYSTEM INFO ==") < out.index("== SAVED MODEL SYSTEM INFO ==")
        assert "- PyTorch: " in out and "- Numpy: " in out.split("== SAVED")[1]


@needs_sb3
@pytest.mark.parametrize("same", [True, False])
def test_load_with_policy_kwargs_as_sb3(tmp_path: Path, same: bool) -> None:
    """SB3's test_save_load_env_cnn / large-model call: ``policy_kwargs`` equal to the stored
    ones is accepted; a different value is SB3's ValueError."""
    from stable_baselines3 import TD3 as SB3TD3

    given = {"net_arch": [32, 32]} if same else {"net_arch": [64]}
    errors = []
    for cls, path in ((TD3, tmp_path / "ours"), (SB3TD3, tmp_path / "sb3")):
        cls("MlpPolicy", "Pendulum-v1", policy_kwargs={"net_arch": [32, 32]}).save(path)
        load = lambda c=cls, p=path: c.load(f"{p}.zip", policy_kwargs=given, device="cpu")  # noqa: E731
        errors.append(_raised(load))
    ours, theirs = errors
    if same:
        assert ours is None and theirs is None
        return
    assert type(ours) is type(theirs) is ValueError
    assert str(ours) == (
        "The specified policy kwargs do not equal the stored policy kwargs.Stored kwargs: "
        "{'net_arch': [32, 32]}, specified kwargs: {'net_arch': [64]}"
    )


def test_a_file_without_system_info_prints_its_versions(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Files saved before ``system_info`` was recorded print the versions they name."""
    PPO("MlpPolicy", "CartPole-v1").save(tmp_path / "m")
    with zipfile.ZipFile(tmp_path / "m.zip") as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    manifest = json.loads(members["palaestra.json"])
    del manifest["meta"]["system_info"]
    members["palaestra.json"] = json.dumps(manifest).encode()
    with zipfile.ZipFile(tmp_path / "old.zip", "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    PPO.load(tmp_path / "old.zip", print_system_info=True)
    saved = capsys.readouterr().out.split("== SAVED MODEL SYSTEM INFO ==\n")[1]
    assert saved.startswith(f"- palaestra: {manifest['meta']['palaestra_version']}\n- PyTorch: ")
