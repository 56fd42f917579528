"""``VecNormalize`` and ``VecFrameStack`` on Dict observations, side by side with
stable-baselines3 on the same env written twice (palaestra's and gymnasium's classes), plus
the Dict statistics file (format /2), the /1 files it must keep reading, and exact resume.

The cases of SB3's ``tests/test_vec_normalize.py`` and ``tests/test_vec_stacked_obs.py`` that
concern Dict spaces, rewritten here: per-key statistics, ``norm_obs_keys`` subsets and their
errors, image keys, stacking per key with one or several ``channels_order``.
"""

from __future__ import annotations

import copy
from typing import Any

import gymnasium
import numpy as np
import pytest
from stable_baselines3.common import vec_env as sb3

import palaestra as gym
from palaestra import spaces
from palaestra.vec_env import DummyVecEnv, VecFrameStack, VecNormalize

N = 3
STEPS = 200


def _walker(base: Any, space_module: Any) -> Any:
    """A Dict-observation env class of ``base`` (palaestra's or gymnasium's ``Env``): random
    values from ``np_random`` (the same generator in both libraries), episodes of random
    length, and optionally a Discrete key and a channel-first uint8 image key."""

    class DictWalker(base):  # type: ignore[misc, valid-type]
        def __init__(self, extra: tuple[str, ...] = ()) -> None:
            parts = {
                "pos": space_module.Box(-10.0, 10.0, (2,), np.float32),
                "vel": space_module.Box(-1.0, 1.0, (3,), np.float64),
            }
            if "flag" in extra:
                parts["flag"] = space_module.Discrete(3)
            if "image" in extra:
                parts["image"] = space_module.Box(0, 255, (2, 4, 5), np.uint8)
            self.observation_space = space_module.Dict(parts)
            self.action_space = space_module.Discrete(2)

        def _obs(self) -> dict[str, Any]:
            rng = self.np_random
            obs: dict[str, Any] = {
                "pos": (rng.normal(2.0, 3.0, 2) + self.t).astype(np.float32),
                "vel": rng.uniform(-1.0, 1.0, 3),
            }
            if "flag" in self.observation_space.spaces:
                obs["flag"] = int(rng.integers(3))
            if "image" in self.observation_space.spaces:
                obs["image"] = rng.integers(0, 256, (2, 4, 5)).astype(np.uint8)
            return obs

        def reset(self, *, seed: int | None = None, options: Any = None) -> Any:
            super().reset(seed=seed)
            self.t = 0
            return self._obs(), {}

        def step(self, action: Any) -> Any:
            self.t += 1
            reward = float(self.np_random.normal(int(action), 2.0))
            terminated = bool(self.np_random.random() < 0.05)
            return self._obs(), reward, terminated, self.t >= 30, {}

    return DictWalker


OurWalker = _walker(gym.Env, spaces)
TheirWalker = _walker(gymnasium.Env, gymnasium.spaces)


def _pair(extra: tuple[str, ...] = (), seed: int = 7) -> tuple[DummyVecEnv, Any]:
    ours = DummyVecEnv([lambda: OurWalker(extra) for _ in range(N)])
    theirs = sb3.DummyVecEnv([lambda: TheirWalker(extra) for _ in range(N)])
    ours.seed(seed)
    theirs.seed(seed)
    return ours, theirs


def _same_obs(a: Any, b: Any) -> None:
    assert isinstance(a, dict) and isinstance(b, dict) and list(a) == list(b)
    for key in a:
        x, y = np.asarray(a[key]), np.asarray(b[key])
        assert x.dtype == y.dtype, key
        np.testing.assert_array_equal(x, y, err_msg=key)


def _same_stats(ours: VecNormalize, theirs: Any) -> None:
    assert isinstance(ours.obs_rms, dict) and list(ours.obs_rms) == list(theirs.obs_rms)
    for key, rms in ours.obs_rms.items():
        np.testing.assert_array_equal(rms.mean, theirs.obs_rms[key].mean, err_msg=key)
        np.testing.assert_array_equal(rms.var, theirs.obs_rms[key].var, err_msg=key)
        assert rms.count == theirs.obs_rms[key].count
    assert ours.ret_rms.mean == theirs.ret_rms.mean and ours.ret_rms.var == theirs.ret_rms.var
    assert ours.ret_rms.count == theirs.ret_rms.count


def _run_side_by_side(ours: Any, theirs: Any, steps: int = STEPS, check: Any = None) -> int:
    """Step both with the same actions; compare everything; the number of episode ends."""
    _same_obs(ours.reset(), theirs.reset())
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(steps):
        actions = rng.integers(0, 2, N)
        o1, r1, d1, i1 = ours.step(actions)
        o2, r2, d2, i2 = theirs.step(actions)
        _same_obs(o1, o2)
        np.testing.assert_array_equal(r1, r2)
        assert r1.dtype == r2.dtype
        np.testing.assert_array_equal(d1, d2)
        for a, b in zip(i1, i2):
            assert ("terminal_observation" in a) == ("terminal_observation" in b)
            if "terminal_observation" in b:
                _same_obs(a["terminal_observation"], b["terminal_observation"])
                ends += 1
        if check is not None:
            check()
    return ends


# -- VecNormalize ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("extra", "keys"),
    [((), None), (("flag",), ["pos", "vel"]), (("flag",), ["vel"]), (("image",), None)],
)
def test_vec_normalize_dict_matches_sb3(extra: tuple[str, ...], keys: list[str] | None) -> None:
    venv_ours, venv_theirs = _pair(extra)
    ours = VecNormalize(venv_ours, norm_obs_keys=keys)
    theirs = sb3.VecNormalize(venv_theirs, norm_obs_keys=keys)
    assert ours.norm_obs_keys == theirs.norm_obs_keys
    assert list(ours.obs_rms) == (keys or list(venv_ours.observation_space.spaces))
    assert repr(ours.observation_space) == repr(theirs.observation_space)
    ends = _run_side_by_side(ours, theirs, check=lambda: _same_stats(ours, theirs))
    assert ends >= N  # the comparison crossed episode ends (and their terminal observations)
    _same_obs(ours.get_original_obs(), theirs.get_original_obs())
    np.testing.assert_array_equal(ours.get_original_reward(), theirs.get_original_reward())
    original = ours.get_original_obs()
    _same_obs(ours.normalize_obs(original), theirs.normalize_obs(original))
    scaled = ours.normalize_obs(original)
    _same_obs(ours.unnormalize_obs(scaled), theirs.unnormalize_obs(scaled))
    for key in ours.obs_rms:  # up to float32 rounding and clipping, the round trip holds
        np.testing.assert_allclose(ours.unnormalize_obs(scaled)[key], original[key], rtol=1e-5)


def test_only_the_named_keys_are_scaled_and_the_others_are_copies() -> None:
    venv, _ = _pair(("flag",))
    norm = VecNormalize(venv, norm_obs_keys=["vel"], clip_obs=0.5)
    norm.reset()
    for _ in range(20):
        norm.step(np.zeros(N, dtype=np.int64))
    raw = norm.get_original_obs()
    out = norm.normalize_obs(raw)
    assert out["vel"].dtype == np.float32 and np.abs(out["vel"]).max() <= 0.5  # clipped
    assert out["pos"].dtype == np.float32 and np.array_equal(out["pos"], raw["pos"])
    assert out["pos"] is not raw["pos"] and out["flag"] is not raw["flag"]
    out["pos"][...] = 0  # SB3 deep-copies: changing the output leaves the input alone
    assert not np.array_equal(raw["pos"], out["pos"])
    assert set(norm.obs_rms) == {"vel"} and norm.obs_rms["vel"].count > 20 * N
    # not training: the statistics stay as they are
    norm.training = False
    before = copy.deepcopy(norm.obs_rms["vel"])
    norm.step(np.zeros(N, dtype=np.int64))
    norm.reset()
    assert norm.obs_rms["vel"].count == before.count
    np.testing.assert_array_equal(norm.obs_rms["vel"].mean, before.mean)


def test_no_obs_normalisation_passes_any_dict_through() -> None:
    venv, _ = _pair(("flag",))
    norm = VecNormalize(venv, norm_obs=False, norm_obs_keys=["vel"])
    obs = norm.reset()
    assert obs.keys() == {"flag", "pos", "vel"} and obs["flag"].dtype == np.int64
    assert norm.norm_obs_keys == ["vel"]  # kept unused, as SB3 keeps it


def _sb3_error(make: Any) -> BaseException:
    with pytest.raises((ValueError, KeyError, TypeError)) as info:
        make()
    return info.value


def test_bad_keys_are_the_errors_sb3_raises() -> None:
    ours, theirs = _pair(("flag",))
    # default keys include the Discrete one: SB3's ValueError, word for word
    expected = str(_sb3_error(lambda: sb3.VecNormalize(theirs)))
    with pytest.raises(ValueError) as info:
        VecNormalize(ours)
    assert str(info.value) == expected
    assert "but flag is of type Discrete(3)" in expected and "norm_obs_keys" in expected
    with pytest.raises(ValueError, match=r"but flag is of type Discrete\(3\)"):
        VecNormalize(ours, norm_obs_keys=["pos", "flag"])
    # a key the space lacks: a KeyError in both; ours names the key and the keys there are
    assert isinstance(_sb3_error(lambda: sb3.VecNormalize(theirs, norm_obs_keys=["x"])), KeyError)
    missing = r"norm_obs_keys names 'x', which the observation space lacks: its keys are \['flag'"
    with pytest.raises(KeyError, match=missing):
        VecNormalize(ours, norm_obs_keys=["pos", "x"])


def _box_and_tuple_envs() -> list[tuple[Any, Any]]:
    class Ours(gym.Env):
        def __init__(self, space: Any) -> None:
            self.observation_space, self.action_space = space, spaces.Discrete(2)

    class Theirs(gymnasium.Env):
        def __init__(self, space: Any) -> None:
            self.observation_space, self.action_space = space, gymnasium.spaces.Discrete(2)

    box, gbox = spaces.Box(-1, 1, (2,)), gymnasium.spaces.Box(-1, 1, (2,))
    tup = spaces.Tuple((spaces.Discrete(2), box))
    gtup = gymnasium.spaces.Tuple((gymnasium.spaces.Discrete(2), gbox))
    return [
        (DummyVecEnv([lambda: Ours(box)]), sb3.DummyVecEnv([lambda: Theirs(gbox)])),
        (DummyVecEnv([lambda: Ours(tup)]), sb3.DummyVecEnv([lambda: Theirs(gtup)])),
    ]


def test_keys_on_a_box_and_a_tuple_space_are_sb3s_errors() -> None:
    (box, gbox), (tup, gtup) = _box_and_tuple_envs()
    expected = str(_sb3_error(lambda: sb3.VecNormalize(gbox, norm_obs_keys=["a"])))
    with pytest.raises(ValueError) as info:
        VecNormalize(box, norm_obs_keys=["a"])
    assert (
        str(info.value)
        == expected
        == ("`norm_obs_keys` param is applicable only with `gym.spaces.Dict` observation spaces")
    )
    expected = str(_sb3_error(lambda: sb3.VecNormalize(gtup)))
    with pytest.raises(ValueError) as info:
        VecNormalize(tup)
    assert str(info.value) == expected
    assert expected.startswith("VecNormalize only supports `gym.spaces.Box` and `gym.spaces.Dict`")
    VecNormalize(tup, norm_obs=False)  # nothing to normalise: any space, as in SB3


def test_image_key_space_becomes_float_and_the_inner_space_is_untouched() -> None:
    venv, _ = _pair(("image",))
    inner = venv.observation_space
    norm = VecNormalize(venv, clip_obs=5.0)
    image = norm.observation_space.spaces["image"]
    assert isinstance(image, spaces.Box) and image.dtype == np.float32
    assert image.shape == (2, 4, 5) and image.low.min() == -5.0 and image.high.max() == 5.0
    assert inner.spaces["image"].dtype == np.uint8  # SB3 edits it in place; we do not
    assert venv.observation_space is inner
    assert norm.reset()["image"].dtype == np.float32


class InfoSpy(DummyVecEnv):
    """Keeps copies of the info dicts the inner env returned, to compare with the wrapper's."""

    def step_wait(self) -> Any:
        out = super().step_wait()
        self.seen = [dict(info) for info in out[3]]  # the dicts, not the list
        return out


def test_inner_infos_are_not_rewritten() -> None:
    venv = InfoSpy([lambda: OurWalker() for _ in range(N)])
    venv.seed(3)
    norm = VecNormalize(venv)
    norm.reset()
    for _ in range(60):
        _, _, dones, infos = norm.step(np.zeros(N, dtype=np.int64))
        for i in np.flatnonzero(dones):
            inner = venv.seen[i]["terminal_observation"]["pos"]
            assert not np.array_equal(inner, infos[i]["terminal_observation"]["pos"])
            assert inner.dtype == np.float32 and np.abs(inner).max() > 0.1


# -- VecFrameStack --------------------------------------------------------------------------


@pytest.mark.parametrize(
    "order",
    [None, "first", "last", {"pos": "first", "vel": "last", "image": None}],
    ids=["auto", "first", "last", "per-key"],
)
def test_vec_frame_stack_dict_matches_sb3(order: Any) -> None:
    venv_ours, venv_theirs = _pair(("image",))
    ours = VecFrameStack(venv_ours, 3, channels_order=order)
    theirs = sb3.VecFrameStack(venv_theirs, 3, channels_order=order)
    assert repr(ours.observation_space) == repr(theirs.observation_space)
    stacked = ours.observation_space.spaces
    # auto: the channel-first image stacks on its first axis, the vectors on their last
    if order is None:
        assert stacked["image"].shape == (6, 4, 5) and stacked["pos"].shape == (6,)
    assert _run_side_by_side(ours, theirs) >= N


def test_vec_frame_stack_over_vec_normalize_matches_sb3() -> None:
    venv_ours, venv_theirs = _pair(("image",))
    ours_norm = VecNormalize(venv_ours, norm_obs_keys=["vel", "image"])
    theirs_norm = sb3.VecNormalize(venv_theirs, norm_obs_keys=["vel", "image"])
    ours, theirs = VecFrameStack(ours_norm, 2), sb3.VecFrameStack(theirs_norm, 2)
    # the normalised image is a float Box now: stacked on its last axis, as in SB3
    assert ours.observation_space.spaces["image"].shape == (2, 4, 10)
    assert repr(ours.observation_space) == repr(theirs.observation_space)
    check = lambda: _same_stats(ours_norm, theirs_norm)  # noqa: E731
    assert _run_side_by_side(ours, theirs, check=check) >= N


def test_stacks_are_copies_and_the_inner_infos_stay() -> None:
    venv = InfoSpy([lambda: OurWalker() for _ in range(N)])
    venv.seed(1)
    stack = VecFrameStack(venv, 2)
    first = stack.reset()
    kept = {k: v.copy() for k, v in first.items()}
    again = stack.reset()  # new episodes: other values, written into the same stacks
    assert not np.array_equal(again["pos"], kept["pos"])
    _same_obs(first, kept)  # what was handed out before is left alone (SB3 zeroes it)
    ends = 0
    for _ in range(40):
        _, _, dones, infos = stack.step(np.ones(N, dtype=np.int64))
        for i in np.flatnonzero(dones):
            terminal = infos[i]["terminal_observation"]
            assert terminal["pos"].shape == (4,) and terminal["vel"].shape == (6,)
            inner = venv.seen[i]["terminal_observation"]  # still one frame per key
            assert inner["pos"].shape == (2,) and inner["vel"].shape == (3,)
            np.testing.assert_array_equal(terminal["pos"][2:], inner["pos"])
            ends += 1
    assert ends > 0


def test_frame_stack_errors() -> None:
    ours, theirs = _pair(("flag",))
    expected = str(_sb3_error(lambda: sb3.VecFrameStack(theirs, 2)))
    with pytest.raises(TypeError) as info:
        VecFrameStack(ours, 2)
    assert str(info.value) == expected
    assert "StackedObservations only supports Box and Dict" in expected
    box = DummyVecEnv([lambda: gym.make("CartPole-v1")])
    with pytest.raises(TypeError, match="When the observation space is Box, channels_order can't"):
        VecFrameStack(box, 2, channels_order={"a": "last"})
    plain, _ = _pair()
    with pytest.raises(KeyError, match="vel"):  # a per-key order must name every key (SB3)
        VecFrameStack(plain, 2, channels_order={"pos": "last"})
    with pytest.raises(ValueError, match=r"n_stack must be a positive integer, got 0"):
        VecFrameStack(plain, 0)
