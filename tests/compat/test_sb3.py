"""``from_sb3``: SB3 DQN/PPO MlpPolicy files load with SB3's exact weights (same greedy actions,
Q-values, values and log-probs), nothing in them is unpickled, and other files are refused."""

from __future__ import annotations

import io
import json
import warnings
import zipfile
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest
import torch
from tests.compat.crafted import call_global, payload, torch_zip
from tests.compat.toys import ReachDict

import palaestra
from palaestra.algos import DQN, PPO, ModelFileError
from palaestra.compat import UnsafeFileError, from_sb3, to_gymnasium

sb3 = pytest.importorskip("stable_baselines3")


@pytest.fixture(autouse=True)
def _quiet() -> object:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def _train(kind: str) -> Any:
    """Tiny SB3 models, a few hundred steps each: enough to move the weights off their init."""
    if kind == "dqn":
        return sb3.DQN(
            "MlpPolicy", "CartPole-v1", learning_starts=50, train_freq=4, target_update_interval=50,
            policy_kwargs={"net_arch": [32, 32]}, seed=0,
        ).learn(300)  # fmt: skip
    if kind == "dqn_taxi":  # Discrete observations: one-hot inputs
        return sb3.DQN("MlpPolicy", "Taxi-v4", learning_starts=50, seed=0).learn(200)
    if kind == "ppo":
        return sb3.PPO(
            "MlpPolicy", "CartPole-v1", n_steps=128, batch_size=64, n_epochs=2, seed=0
        ).learn(256)
    if kind == "ppo_box":  # Gaussian head (log_std), ReLU, different pi/vf widths
        return sb3.PPO(
            "MlpPolicy", "Pendulum-v1", n_steps=128, batch_size=64, n_epochs=2, seed=0,
            policy_kwargs={"net_arch": {"pi": [32], "vf": [16, 16]},
                           "activation_fn": torch.nn.ReLU},
        ).learn(256)  # fmt: skip
    if kind == "a2c":
        return sb3.A2C("MlpPolicy", "CartPole-v1", n_steps=8, seed=0).learn(16)
    if kind == "ppo_dict":
        return sb3.PPO("MultiInputPolicy", to_gymnasium(ReachDict()), n_steps=64, batch_size=32)
    raise KeyError(kind)


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> Any:
    cache: dict[str, tuple[Any, Path]] = {}

    def get(kind: str) -> tuple[Any, Path]:
        if kind not in cache:
            model = _train(kind)
            path = tmp_path_factory.mktemp("sb3") / f"{kind}.zip"
            model.save(path)
            cache[kind] = (model, path)
        return cache[kind]

    return get


def _observations(env_id: str, n: int = 200) -> np.ndarray:
    """States a policy actually meets: a random rollout."""
    env = gymnasium.make(env_id)
    env.action_space.seed(0)
    obs, _ = env.reset(seed=0)
    out = []
    for _ in range(n):
        out.append(obs)
        obs, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            obs, _ = env.reset()
    return np.stack(out) if isinstance(obs, np.ndarray) else np.array(out)


@pytest.mark.parametrize(("kind", "env_id"), [("dqn", "CartPole-v1"), ("dqn_taxi", "Taxi-v4")])
def test_dqn_predictions_and_q_values_equal_sb3(saved: Any, kind: str, env_id: str) -> None:
    reference, path = saved(kind)
    model = from_sb3(path)
    assert isinstance(model, DQN)
    obs = _observations(env_id)
    ours, _ = model.predict(obs, deterministic=True)
    theirs, _ = reference.predict(obs, deterministic=True)
    np.testing.assert_array_equal(ours, theirs)
    with torch.no_grad():
        q_ours = model.q_net(torch.as_tensor(obs)).numpy()
        q_theirs = reference.q_net(reference.policy.obs_to_tensor(obs)[0]).numpy()
        target_ours = model.q_net_target(torch.as_tensor(obs)).numpy()
        target_theirs = reference.q_net_target(reference.policy.obs_to_tensor(obs)[0]).numpy()
    np.testing.assert_allclose(q_ours, q_theirs, rtol=0, atol=1e-6)
    np.testing.assert_allclose(target_ours, target_theirs, rtol=0, atol=1e-6)
    assert model.exploration_rate == pytest.approx(reference.exploration_rate)
    assert model.num_timesteps == reference.num_timesteps


@pytest.mark.parametrize(("kind", "env_id"), [("ppo", "CartPole-v1"), ("ppo_box", "Pendulum-v1")])
def test_ppo_predictions_values_and_log_probs_equal_sb3(saved: Any, kind: str, env_id: str) -> None:
    reference, path = saved(kind)
    model = from_sb3(path)
    assert isinstance(model, PPO)
    obs = _observations(env_id)
    ours, _ = model.predict(obs, deterministic=True)
    theirs, _ = reference.predict(obs, deterministic=True)
    if ours.dtype.kind == "f":
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-6)
    else:
        np.testing.assert_array_equal(ours, theirs)
    obs_t = torch.as_tensor(obs)
    with torch.no_grad():
        values, log_prob, entropy = model.policy.evaluate_actions(obs_t, torch.as_tensor(theirs))
        ref = reference.policy.evaluate_actions(obs_t, torch.as_tensor(theirs))
    np.testing.assert_allclose(values.numpy(), ref[0].numpy()[:, 0], rtol=0, atol=1e-6)
    np.testing.assert_allclose(log_prob.numpy(), ref[1].numpy(), rtol=0, atol=1e-5)
    np.testing.assert_allclose(entropy.numpy(), ref[2].numpy(), rtol=0, atol=1e-5)


def test_settings_and_architecture_come_from_the_file(saved: Any) -> None:
    _, path = saved("ppo_box")
    model = from_sb3(path)
    assert model.policy_kwargs["net_arch"] == {"pi": [32], "vf": [16, 16]}
    assert model.policy_kwargs["activation_fn"] is torch.nn.ReLU
    assert (model.n_steps, model.batch_size, model.n_epochs) == (128, 64, 2)
    assert model.clip_range(1.0) == 0.2  # a pickled ConstantSchedule, read from its repr
    assert model.observation_space == palaestra.make("Pendulum-v1").observation_space
    assert model.action_space == palaestra.make("Pendulum-v1").action_space
    assert from_sb3(path, n_epochs=5).n_epochs == 5


def test_with_an_env_it_keeps_training(saved: Any) -> None:
    reference, path = saved("dqn")
    model = from_sb3(path, env=palaestra.make("CartPole-v1"), learning_starts=0)
    model.learn(100, reset_num_timesteps=False)
    assert model.num_timesteps == reference.num_timesteps + 100
    from_sb3(path, env=gymnasium.make("CartPole-v1"))  # a Gymnasium env is adapted


def test_a_mismatched_env_is_refused(saved: Any) -> None:
    _, path = saved("dqn")
    with pytest.raises(ValueError, match=r"env's observation space Box\(.*\(2,\).* does not"):
        from_sb3(path, env=palaestra.make("MountainCar-v0"))
    with pytest.raises(TypeError, match=r"env must be an id string, a palaestra Env or VecEnv"):
        from_sb3(path, env=object())


def _rewrite(src: Path, dst: Path, **replace: bytes) -> Path:
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for name in zin.namelist():
            zout.writestr(name, replace.get(name.replace(".", "_"), zin.read(name)))
    return dst


def test_malicious_policy_pth_is_refused_and_does_not_run(saved: Any, tmp_path: Path) -> None:
    _, path = saved("dqn")
    marker = tmp_path / "pwned"
    evil = torch_zip(payload(call_global("os", "system", f"touch {marker}")))
    bad = _rewrite(path, tmp_path / "evil.zip", policy_pth=evil)
    with pytest.raises(UnsafeFileError, match=r"refers to os.system, which a tensor state_dict"):
        from_sb3(bad)
    assert not marker.exists()


def _edit_data(src: Path, dst: Path, **changes: Any) -> Path:
    with zipfile.ZipFile(src) as zf:
        data = json.loads(zf.read("data"))
    data.update(changes)
    return _rewrite(src, dst, data=json.dumps(data).encode())


def _edit_policy(src: Path, dst: Path, **extra: torch.Tensor) -> Path:
    with zipfile.ZipFile(src) as zf:
        state = torch.load(io.BytesIO(zf.read("policy.pth")), weights_only=True)
    state.update({k.replace("__", "."): v for k, v in extra.items()})
    buf = io.BytesIO()
    torch.save(state, buf)
    return _rewrite(src, dst, policy_pth=buf.getvalue())


def test_unsupported_models_are_refused_with_reasons(saved: Any, tmp_path: Path) -> None:
    _, dqn = saved("dqn")
    _, ppo = saved("ppo")
    _, a2c = saved("a2c")
    with pytest.raises(ModelFileError, match=r"holds an SB3 A2C model; from_sb3 reads DQN and PPO"):
        from_sb3(a2c)
    cnn = _edit_policy(
        dqn, tmp_path / "cnn.zip", q_net__features_extractor__cnn__0__weight=torch.ones(1)
    )
    with pytest.raises(ModelFileError, match=r"parameters \['q_net.features_extractor.cnn.0.we"):
        from_sb3(cnn)
    sde = _edit_data(ppo, tmp_path / "sde.zip", use_sde=True)
    with pytest.raises(ModelFileError, match=r"gSDE \(use_sde=True\) models are not supported"):
        from_sb3(sde)
    custom = _edit_data(
        ppo, tmp_path / "fe.zip", policy_kwargs={"features_extractor_class": "<class 'x.Mine'>"}
    )
    with pytest.raises(ModelFileError, match=r"features_extractor_class <class 'x.Mine'> is not"):
        from_sb3(custom)
    odd = _edit_data(ppo, tmp_path / "kw.zip", policy_kwargs={"n_quantiles": 5})
    with pytest.raises(ModelFileError, match=r"policy_kwargs \['n_quantiles'\] are not supported"):
        from_sb3(odd)
    evil_class = _edit_data(
        ppo, tmp_path / "act.zip", policy_kwargs={"activation_fn": "<class 'os.system'>"}
    )
    with pytest.raises(ModelFileError, match=r"names class 'os:system', which palaestra will not"):
        from_sb3(evil_class)


def test_multi_input_policy_is_refused(saved: Any) -> None:
    _, path = saved("ppo_dict")
    with pytest.raises(ModelFileError, match=r"observation space Dict is not supported"):
        from_sb3(path)
    with pytest.raises(ModelFileError, match=r"not MultiInputPolicy ones"):
        from_sb3(path, env=ReachDict())


def test_files_that_are_not_sb3_models(tmp_path: Path) -> None:
    plain = tmp_path / "plain.zip"
    with zipfile.ZipFile(plain, "w") as zf:
        zf.writestr("readme.txt", "hello")
    with pytest.raises(ModelFileError, match=r"is a zip archive, not a Stable-Baselines3 model"):
        from_sb3(plain)
    ours = tmp_path / "ours.zip"
    DQN("MlpPolicy", "CartPole-v1").save(ours)
    with pytest.raises(ModelFileError, match=r"is a palaestra model file, not a Stable-Baselines3"):
        from_sb3(ours)
    text = tmp_path / "text.zip"
    text.write_text("not a zip")
    with pytest.raises(ModelFileError, match=r"not a zip archive, so not an SB3 model file"):
        from_sb3(text)
    with pytest.raises(FileNotFoundError, match=r"no SB3 model file at '.*missing'"):
        from_sb3(tmp_path / "missing")


def test_summarised_bounds_ask_for_an_env(saved: Any, tmp_path: Path) -> None:
    _, path = saved("dqn")
    with zipfile.ZipFile(path) as zf:
        space = json.loads(zf.read("data"))["observation_space"]
    space["low"] = "[0. 0. ... 0. 0.]"
    bad = _edit_data(path, tmp_path / "summary.zip", observation_space=space)
    with pytest.raises(ModelFileError, match=r"printed in summarised form\); pass env=\.\.\."):
        from_sb3(bad)
    assert isinstance(from_sb3(bad, env="CartPole-v1"), DQN)


def test_algo_load_of_an_sb3_file_points_to_from_sb3(saved: Any) -> None:
    _, path = saved("dqn")
    with pytest.raises(ModelFileError, match=r"palaestra.compat.from_sb3\(path\) reads the weig"):
        DQN.load(path)


def test_needs_neither_sb3_nor_gymnasium(saved: Any) -> None:
    import subprocess
    import sys

    _, path = saved("ppo_box")
    code = (
        "import sys\n"
        "for name in ('gymnasium', 'stable_baselines3', 'cloudpickle'): sys.modules[name] = None\n"
        "from palaestra.compat import from_sb3\n"
        f"model = from_sb3({str(path)!r})\n"
        "print(type(model).__name__, model.action_space)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.strip() == "PPO Box(-2.0, 2.0, (1,), float32)", out.stderr
