"""The MuJoCo envs' contract: lazy import, ids and specs, checks, copies and bad input."""

from __future__ import annotations

import copy
import pickle
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.envs.mujoco.cases import MUJOCO_IDS

import palaestra
from palaestra import error
from palaestra.envs.mujoco import _base
from palaestra.utils.env_checker import check_env

pytest.importorskip("mujoco")


def test_import_palaestra_does_not_import_mujoco() -> None:
    code = "import sys, palaestra, palaestra.envs; print('mujoco' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", out.stderr


@pytest.mark.parametrize("env_id", ["HalfCheetah-v5", "Humanoid-v5"])
def test_missing_mujoco_names_the_extra(env_id: str) -> None:
    code = (
        "import sys\n"
        "sys.modules['mujoco'] = None  # import mujoco now raises ImportError\n"
        "import palaestra\n"
        "from palaestra import error\n"
        "try:\n"
        f"    palaestra.make({env_id!r})\n"
        "except error.DependencyNotInstalled as e:\n"
        "    print('raised:', e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == (
        'raised: mujoco is not installed, run `pip install "palaestra[mujoco]"` (needed for the '
        "MuJoCo environments: Ant, HalfCheetah, Hopper, Humanoid, HumanoidStandup, "
        "InvertedDoublePendulum, InvertedPendulum, Pusher, Reacher, Swimmer, Walker2d)"
    ), out.stderr


@pytest.mark.parametrize("env_id", MUJOCO_IDS)
@pytest.mark.parametrize("old", [2, 3, 4])
def test_older_versions_raise_naming_v5(env_id: str, old: int) -> None:
    name = env_id[: -len("-v5")]
    with (
        pytest.warns(DeprecationWarning, match=f"{name}-v{old} is out of date"),
        pytest.raises(error.DeprecatedEnv, match=f"Please use `{name}-v5` instead"),
    ):
        palaestra.make(f"{name}-v{old}")


@pytest.mark.parametrize("env_id", MUJOCO_IDS)
def test_spec_and_spaces_match_gymnasium(env_id: str) -> None:
    gymnasium = pytest.importorskip("gymnasium")
    ours, ref = palaestra.make(env_id), gymnasium.make(env_id)
    assert ours.spec is not None and ref.spec is not None
    assert ours.spec.max_episode_steps == ref.spec.max_episode_steps
    assert ours.spec.reward_threshold == ref.spec.reward_threshold
    for a, b in (
        (ours.action_space, ref.action_space),
        (ours.observation_space, ref.observation_space),
    ):
        assert (a.shape, a.dtype) == (b.shape, b.dtype)
        assert a.low.tobytes() == b.low.tobytes() and a.high.tobytes() == b.high.tobytes()
    assert ours.unwrapped.metadata["render_fps"] == ref.unwrapped.metadata["render_fps"]
    assert ours.unwrapped.dt == ref.unwrapped.dt
    structure = getattr(ref.unwrapped, "observation_structure", None)
    assert getattr(ours.unwrapped, "observation_structure", None) == structure


@pytest.mark.parametrize("env_id", MUJOCO_IDS)
def test_check_env_passes(env_id: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # Gymnasium's checker says the same of its own MuJoCo envs: infinite observation
        # bounds, and action bounds other than [-1, 1] (the actuators' control ranges)
        warnings.filterwarnings("ignore", message=".*Box observation space m.* is -?infinity")
        warnings.filterwarnings("ignore", message=".*we recommend using a symmetric and norm")
        check_env(palaestra.make(env_id).unwrapped, skip_render_check=True)


def _run(env: Any, actions: list[np.ndarray]) -> list[tuple[bytes, float, bool]]:
    out = []
    for action in actions:
        obs, reward, terminated, truncated, _ = env.step(action)
        out.append((obs.tobytes(), float(reward), bool(terminated)))
        if terminated or truncated:
            break
    return out


@pytest.mark.parametrize("env_id", MUJOCO_IDS)
def test_copies_continue_the_trajectory(env_id: str) -> None:
    env = palaestra.make(env_id)
    env.reset(seed=3)
    env.action_space.seed(0)
    _run(env, [env.action_space.sample() for _ in range(10)])
    clones = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    later = [env.action_space.sample() for _ in range(10)]
    want = _run(env, later)
    for clone in clones:
        assert clone.unwrapped.data is not env.unwrapped.data
        assert _run(clone, later) == want
        state = clone.unwrapped.np_random.bit_generator.state
        assert state == env.unwrapped.np_random.bit_generator.state
    # unseeded resets continue each one's generator: the same draws
    first = env.reset()[0].tobytes()
    assert all(clone.reset()[0].tobytes() == first for clone in clones)


@pytest.mark.parametrize(
    "action, why",
    [
        (np.array([np.nan, 0, 0, 0, 0, 0], np.float32), "finite"),
        (np.array([0, 0, np.inf, 0, 0, 0]), "finite"),
        (np.zeros(5, np.float32), r"expected shape \(6,\), got \(5,\)"),
        (np.zeros((1, 6), np.float32), r"expected shape \(6,\), got \(1, 6\)"),
        (0.5, r"got \(\)"),
        (["a"] * 6, "real numeric"),
        (np.zeros(6, complex), "real numeric"),
    ],
)
def test_bad_actions_raise_naming_action_and_space(action: Any, why: str) -> None:
    env = palaestra.make("HalfCheetah-v5")
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=why) as info:
        env.step(action)
    message = str(info.value)
    assert repr(action)[:20] in message and "Box(-1.0, 1.0, (6,), float32)" in message


def test_out_of_bound_actions_are_clamped_by_mujoco_as_in_gymnasium() -> None:
    env = palaestra.make("Hopper-v5")
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.full(3, 5.0, np.float32))
    assert info["reward_ctrl"] == -1e-3 * np.sum(np.square(np.full(3, 5.0, np.float32)))


def test_a_missing_xml_file_names_the_path(tmp_path: Path) -> None:
    missing = tmp_path / "nope.xml"
    with pytest.raises(FileNotFoundError, match=f"xml_file '{missing}': no MJCF file"):
        palaestra.make("Hopper-v5", xml_file=str(missing))
    with pytest.raises(FileNotFoundError, match=r"'no_such_model.xml': no MJCF file at '.*assets"):
        palaestra.make("Ant-v5", xml_file="no_such_model.xml")


def test_an_xml_file_that_does_not_compile_names_the_path_and_mujocos_message(
    tmp_path: Path,
) -> None:
    bad = tmp_path / "bad.xml"
    bad.write_text('<mujoco><worldbody><geom type="sphere" size="-1"/></worldbody></mujoco>')
    with pytest.raises(
        error.InvalidModelFile, match=f"xml_file '{bad}' .* does not compile: "
    ) as e:
        palaestra.make("Hopper-v5", xml_file=str(bad))
    assert "size" in str(e.value).lower()
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody>")
    with pytest.raises(error.InvalidModelFile, match=r"broken\.xml"):
        palaestra.make("Swimmer-v5", xml_file=str(broken))


@pytest.mark.parametrize(
    "env_id, kwargs, kind, match",
    [
        ("Hopper-v5", {"frame_skip": 0}, ValueError, "frame_skip must be >= 1, got 0"),
        ("Hopper-v5", {"frame_skip": 2.0}, TypeError, "frame_skip must be an int, got 2.0"),
        (
            "Hopper-v5",
            {"healthy_z_range": (1.0, 0.5)},
            ValueError,
            r"low <= high, got \(1.0, 0.5\)",
        ),
        ("Walker2d-v5", {"healthy_angle_range": 1.0}, TypeError, "a \\(low, high\\) pair, got 1.0"),
        ("Ant-v5", {"contact_force_range": (float("nan"), 1)}, ValueError, "must not hold NaN"),
        (
            "HalfCheetah-v5",
            {"ctrl_cost_weight": float("nan")},
            ValueError,
            "ctrl_cost_weight must be finite",
        ),
        (
            "HalfCheetah-v5",
            {"forward_reward_weight": "1"},
            TypeError,
            "must be a real number, got '1'",
        ),
        (
            "Swimmer-v5",
            {"exclude_current_positions_from_observation": "no"},
            TypeError,
            "must be a bool, got 'no'",
        ),
        ("Ant-v5", {"main_body": "nose"}, ValueError, "main_body 'nose' is not a body of"),
        ("Ant-v5", {"main_body": 99}, ValueError, "main_body 99 is not a body of"),
        ("Reacher-v5", {"bogus": 1}, TypeError, "unexpected keyword argument 'bogus'"),
    ],
)
def test_bad_kwargs_raise_naming_the_value(
    env_id: str, kwargs: dict[str, Any], kind: type[Exception], match: str
) -> None:
    with pytest.raises(kind, match=match):
        palaestra.make(env_id, **kwargs)


def test_instability_is_a_warning_and_in_info_not_a_silent_reset() -> None:
    env = palaestra.make("HalfCheetah-v5")
    env.reset(seed=0)
    raw = env.unwrapped
    raw.set_state(raw.init_qpos, np.full(raw.model.nv, 1e300))
    with pytest.warns(_base.MujocoWarning, match="HalfCheetahEnv: MuJoCo reported mjWARN_BAD"):
        _, _, _, _, info = env.step(np.zeros(6, np.float32))
    assert info["mujoco_warnings"] and all(
        w.startswith("mjWARN_BAD") for w in info["mujoco_warnings"]
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a calm step after the reset says nothing
        env.reset(seed=1)
        _, _, _, _, info = env.step(np.zeros(6, np.float32))
    assert "mujoco_warnings" not in info


def test_another_mujoco_version_warns_once(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_base, "_version_checked", False)
    monkeypatch.setattr(_base, "PARITY_MUJOCO_VERSION", "0.0.1")
    with pytest.warns(UserWarning, match="checked .* bit for bit on mujoco 0.0.1 only"):
        palaestra.make("InvertedPendulum-v5")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        palaestra.make("InvertedPendulum-v5")


@pytest.mark.parametrize(
    "env_id", ["HalfCheetah-v5", "Hopper-v5", "InvertedDoublePendulum-v5", "Pusher-v5"]
)
def test_default_camera_config_none_is_no_camera_config_as_in_gymnasium(env_id: str) -> None:
    """Left out: the env's own camera settings; an explicit None: none (Gymnasium's rule)."""
    gymnasium = pytest.importorskip("gymnasium")
    ours = palaestra.make(env_id, default_camera_config=None).unwrapped
    theirs = gymnasium.make(env_id, default_camera_config=None).unwrapped
    assert ours._renderer.default_camera_config is None
    assert theirs.mujoco_renderer.default_cam_config is None
    ours_default = palaestra.make(env_id).unwrapped._renderer.default_camera_config
    theirs_default = gymnasium.make(env_id).unwrapped.mujoco_renderer.default_cam_config
    if theirs_default is None:  # InvertedDoublePendulum's default is None
        assert ours_default is None
        return
    assert set(ours_default) == set(theirs_default)
    for key, value in theirs_default.items():
        assert np.array_equal(ours_default[key], value), key
