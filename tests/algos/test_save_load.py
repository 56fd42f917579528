"""save -> load gives identical predictions; resuming continues schedules and the replay
buffer; the same seed gives bit-identical parameters; bad files get clear errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

import palaestra as gym
from palaestra.algos import DQN, PPO, ModelFileError
from palaestra.algos.callbacks import BaseCallback, CheckpointCallback
from palaestra.algos.schedules import LinearSchedule

from .toys import Toy

OBS = np.random.default_rng(0).normal(size=(32, 4)).astype(np.float32)


class _RecordLR(BaseCallback):
    """The optimizer's learning rate at the start of each collection."""

    def __init__(self, out: list[float]) -> None:
        super().__init__()
        self.out = out

    def _on_rollout_start(self) -> None:
        self.out.append(self.model.optimizer.param_groups[0]["lr"])

    def _on_step(self) -> bool:
        return True


def _dqn(**kw: object) -> DQN:
    args = {
        "learning_starts": 50,
        "batch_size": 16,
        "buffer_size": 1000,
        "seed": 3,
        "target_update_interval": 20,
        "exploration_fraction": 0.5,
        **kw,
    }
    return DQN("MlpPolicy", "CartPole-v1", **args)  # type: ignore[arg-type]


def _ppo(**kw: object) -> PPO:
    args = {"n_steps": 32, "batch_size": 16, "n_epochs": 2, "seed": 3, **kw}
    return PPO("MlpPolicy", "CartPole-v1", **args)  # type: ignore[arg-type]


@pytest.mark.parametrize("make", [_dqn, _ppo])
def test_save_load_identical_predict(tmp_path: Path, make) -> None:  # type: ignore[no-untyped-def]
    model = make().learn(200)
    model.save(tmp_path / "model")
    assert (tmp_path / "model.zip").exists()
    loaded = type(model).load(tmp_path / "model")
    np.testing.assert_array_equal(
        model.predict(OBS, deterministic=True)[0], loaded.predict(OBS, deterministic=True)[0]
    )
    assert loaded.num_timesteps == model.num_timesteps and loaded.get_env() is None
    for (k, a), (_, b) in zip(
        model.policy.state_dict().items(), loaded.policy.state_dict().items()
    ):
        assert torch.equal(a, b), k
    with pytest.raises(ValueError, match="no environment"):
        loaded.learn(10)
    other = PPO if isinstance(model, DQN) else DQN
    with pytest.raises(ModelFileError, match=f"load it with {type(model).__name__}.load"):
        other.load(tmp_path / "model")
    with pytest.raises(ValueError, match="Observation spaces do not match"):
        type(model).load(tmp_path / "model", env=gym.make("MountainCar-v0"))


def test_schedules_and_custom_objects_survive(tmp_path: Path) -> None:
    model = _ppo(learning_rate=lambda p: 1e-3 * p, clip_range=LinearSchedule(0.3, 0.1))
    model.save(tmp_path / "m.zip")
    loaded = PPO.load(tmp_path / "m.zip", env="CartPole-v1")
    assert loaded.lr_schedule(0.5) == pytest.approx(5e-4)
    assert loaded.clip_range == LinearSchedule(0.3, 0.1)
    custom = PPO.load(tmp_path / "m.zip", custom_objects={"learning_rate": 0.0, "n_epochs": 1})
    assert custom.lr_schedule(1.0) == 0.0 and custom.n_epochs == 1


def test_get_set_parameters_roundtrip() -> None:
    a, b = _dqn(seed=1), _dqn(seed=2)
    b.set_parameters(a.get_parameters())
    np.testing.assert_array_equal(
        a.predict(OBS, deterministic=True)[0], b.predict(OBS, deterministic=True)[0]
    )
    with pytest.raises(ValueError, match="policy"):
        b.set_parameters({"weights": {}})


def test_resume_continues_schedules_and_replay_buffer(tmp_path: Path) -> None:
    # Uninterrupted: 400 steps. Interrupted: checkpoint at 200, reload, 200 more steps.
    full = _dqn(learning_rate=LinearSchedule(1e-3, 0.0), exploration_fraction=1.0)
    full.learn(400, callback=CheckpointCallback(200, str(tmp_path), save_replay_buffer=True))
    ckpt = tmp_path / "rl_model_200_steps.zip"
    resumed = DQN.load(ckpt, env="CartPole-v1")
    # The checkpoint runs inside step 200, before that step's epsilon update (SB3's order).
    assert resumed.exploration_rate == pytest.approx(1.0 - 0.95 * 199 / 400)  # not 1.0
    resumed.load_replay_buffer(tmp_path / "rl_model_replay_buffer_200_steps.zip")
    assert (
        resumed.replay_buffer is not None and resumed.replay_buffer.size() == 199
    )  # step 200 not stored yet
    resumed.learn(200, reset_num_timesteps=False)
    assert resumed.num_timesteps == full.num_timesteps == 400
    assert resumed.exploration_rate == full.exploration_rate == pytest.approx(0.05)
    assert resumed.optimizer.param_groups[0]["lr"] == pytest.approx(
        full.optimizer.param_groups[0]["lr"]
    )
    assert resumed.replay_buffer.size() == 399
    # A finished run given 100 more steps trains as a 500-step run would from step 400:
    # progress 0.2, so the linear learning rate is 2e-4, not a silent 0 (as SB3).
    again = DQN.load(tmp_path / "rl_model_400_steps.zip", env="CartPole-v1")
    again.load_replay_buffer(tmp_path / "rl_model_replay_buffer_400_steps.zip")
    before = [p.detach().clone() for p in again.q_net.parameters()]
    lrs: list[float] = []
    again.learn(100, callback=_RecordLR(lrs), reset_num_timesteps=False)
    assert lrs[1] == pytest.approx(1e-3 * (1 - 404 / 500))  # set by the first update
    assert not all(torch.equal(a, b) for a, b in zip(before, again.q_net.parameters()))
    assert again.exploration_rate == pytest.approx(0.05)


@pytest.mark.parametrize("make", [_dqn, _ppo])
def test_same_seed_bit_identical(make) -> None:  # type: ignore[no-untyped-def]
    a, b = make().learn(300), make().learn(300)
    for (k, x), (_, y) in zip(a.policy.state_dict().items(), b.policy.state_dict().items()):
        assert torch.equal(x, y), k
    c = make(seed=4).learn(300)
    assert not all(torch.equal(x, y) for x, y in zip(a.policy.parameters(), c.policy.parameters()))


def test_corrupt_model_file(tmp_path: Path) -> None:
    path = tmp_path / "m.zip"
    _ppo().save(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(ModelFileError):
        PPO.load(path)
    (tmp_path / "x.zip").write_text("not a zip")
    with pytest.raises(ModelFileError):
        DQN.load(tmp_path / "x.zip")


def test_malicious_sb3_model_does_not_run(tmp_path: Path) -> None:
    import os
    import pickle
    import zipfile

    class Evil:
        def __reduce__(self):  # type: ignore[no-untyped-def]
            return (exec, ("import os; os.environ['PALAESTRA_PWNED_MODEL'] = '1'",))

    with zipfile.ZipFile(tmp_path / "sb3.zip", "w") as zf:
        zf.writestr("data", pickle.dumps(Evil()))
        zf.writestr("policy.pth", pickle.dumps(Evil()))
        zf.writestr("pytorch_variables.pth", pickle.dumps(Evil()))
    with pytest.raises(ModelFileError, match="Stable-Baselines3"):
        DQN.load(tmp_path / "sb3")
    assert "PALAESTRA_PWNED_MODEL" not in os.environ


def test_set_env_with_toy_env_after_load(tmp_path: Path) -> None:
    model = PPO("MlpPolicy", Toy(), n_steps=16, batch_size=8, seed=0)
    model.save(tmp_path / "toy")
    loaded = PPO.load(tmp_path / "toy", env=Toy())
    loaded.learn(16)
    assert loaded.num_timesteps == 16


class TinyExtractor(torch.nn.Module):
    """A user features extractor (outside palaestra.algos): needs custom_objects on load."""

    def __init__(self, observation_space: object, features_dim: int = 8) -> None:
        super().__init__()
        self.features_dim = features_dim
        self.net = torch.nn.Linear(4, features_dim)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return torch.relu(self.net(obs))


def test_policy_kwargs_roundtrip_and_custom_classes(tmp_path: Path) -> None:
    kwargs = {
        "net_arch": {"pi": [16], "vf": [8, 8]},
        "activation_fn": torch.nn.ReLU,
        "ortho_init": False,
        "optimizer_class": torch.optim.RMSprop,
        "optimizer_kwargs": {"alpha": 0.9},
        "features_extractor_class": TinyExtractor,
    }
    model = _ppo(policy_kwargs=kwargs)
    assert isinstance(model.optimizer, torch.optim.RMSprop)
    model.learn(64)
    model.save(tmp_path / "custom")
    with pytest.raises(ModelFileError, match="custom_objects"):
        PPO.load(tmp_path / "custom")
    loaded = PPO.load(tmp_path / "custom", custom_objects={"TinyExtractor": TinyExtractor})
    assert loaded.policy_kwargs["activation_fn"] is torch.nn.ReLU
    np.testing.assert_array_equal(
        model.predict(OBS, deterministic=True)[0], loaded.predict(OBS, deterministic=True)[0]
    )


def _with_array(src: Path, dst: Path, name: str, shape: tuple[int, ...]) -> Path:
    """``src`` with array ``name`` replaced by float32 zeros of ``shape`` (deflated: 16 MiB
    take ~16 KB), its manifest entry declaring that shape."""
    import json
    import zipfile

    from tests.compat.crafted import npy_header

    with zipfile.ZipFile(src) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    manifest = json.loads(members["palaestra.json"])
    entry = manifest["arrays"][name]
    entry["shape"] = list(shape)
    members[entry["file"]] = npy_header("<f4", shape) + bytes(4 * int(np.prod(shape)))
    members["palaestra.json"] = json.dumps(manifest).encode()
    with zipfile.ZipFile(dst, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for n, raw in members.items():
            zf.writestr(n, raw)
    return dst


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("policy/pi_net.0.weight", r"parameter 'pi_net.0.weight' has shape \(4096, 1024\), "
         r"this model expects \(64, 4\)"),
        ("optimizer/0/exp_avg", r"optimizer state 'optimizer/0/exp_avg' \(4096, 1024\) does "
         r"not fit this model's parameters"),
    ],
)  # fmt: skip
def test_oversized_parameters_are_refused_before_they_are_read(
    tmp_path: Path, name: str, message: str
) -> None:
    import time

    model = _ppo().learn(64)
    model.save(tmp_path / "good.zip")
    bad = _with_array(tmp_path / "good.zip", tmp_path / "bad.zip", name, (4096, 1024))
    assert bad.stat().st_size < 1 << 20  # declares 16 MiB
    start = time.process_time()
    with pytest.raises(ModelFileError, match=message):
        PPO.load(bad)
    with pytest.raises(ModelFileError, match=message):
        model.set_parameters(str(bad))
    assert time.process_time() - start < 1.0  # refused from the manifest, nothing inflated
