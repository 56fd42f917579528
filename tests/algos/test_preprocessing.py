"""``palaestra.algos.preprocessing`` gives SB3's ``common.preprocessing`` results on the same
spaces (ported in spirit from SB3's ``tests/test_preprocessing.py`` and ``test_spaces.py``)."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pytest
import torch

from palaestra import spaces
from palaestra.algos import preprocessing as ours

sb3_pre = pytest.importorskip("stable_baselines3.common.preprocessing")
to_gym = pytest.importorskip("palaestra.compat").to_gymnasium_space

SPACES: dict[str, Any] = {
    "box": spaces.Box(-1, 1, (3, 2)),
    "rgb_hwc": spaces.Box(0, 255, (20, 24, 3), np.uint8),
    "gray_chw": spaces.Box(0, 255, (1, 20, 24), np.uint8),
    "stack_hwc": spaces.Box(0, 255, (20, 24, 12), np.uint8),
    "float_image": spaces.Box(0, 1, (3, 20, 24), np.float32),
    "bad_bounds": spaces.Box(0, 100, (20, 24, 3), np.uint8),
    "discrete": spaces.Discrete(5),
    "multidiscrete": spaces.MultiDiscrete([2, 3, 4]),
    "multibinary": spaces.MultiBinary(4),
    "multibinary_2d": spaces.MultiBinary([2, 3]),
    "dict": spaces.Dict({"a": spaces.Discrete(3), "b": spaces.Box(-1, 1, (2,))}),
}


@pytest.mark.parametrize("key", sorted(SPACES))
def test_image_checks_as_sb3(key: str) -> None:
    space = SPACES[key]
    for check_channels in (False, True):
        for normalized in (False, True):
            got = ours.is_image_space(
                space, check_channels=check_channels, normalized_image=normalized
            )
            want = sb3_pre.is_image_space(
                to_gym(space), check_channels=check_channels, normalized_image=normalized
            )
            assert got == want, (check_channels, normalized)


@pytest.mark.parametrize("key", sorted(SPACES))
def test_shapes_and_dims_as_sb3(key: str) -> None:
    space, theirs = SPACES[key], to_gym(SPACES[key])
    assert ours.get_obs_shape(space) == sb3_pre.get_obs_shape(theirs)
    assert ours.get_flattened_obs_dim(space) == sb3_pre.get_flattened_obs_dim(theirs)
    if key == "multibinary_2d":
        with pytest.raises(ValueError, match="Multi-dimensional MultiBinary"):
            ours.get_action_dim(space)
    elif key != "dict":
        assert ours.get_action_dim(space) == sb3_pre.get_action_dim(theirs)
    else:
        with pytest.raises(NotImplementedError, match="action space is not supported"):
            ours.get_action_dim(space)


@pytest.mark.parametrize("key", sorted(SPACES))
def test_preprocess_obs_as_sb3(key: str) -> None:
    space = SPACES[key]
    space.seed(0)
    batch = [space.sample() for _ in range(4)]
    if isinstance(space, spaces.Dict):
        obs: Any = {k: torch.as_tensor(np.stack([b[k] for b in batch])) for k in space.spaces}
    else:
        obs = torch.as_tensor(np.stack(batch))
    for normalize in (True, False):
        got = ours.preprocess_obs(obs, space, normalize_images=normalize)
        want = sb3_pre.preprocess_obs(obs, to_gym(space), normalize_images=normalize)
        for g, w in zip(*(v.values() if isinstance(v, dict) else [v] for v in (got, want))):
            assert g.dtype == w.dtype and torch.equal(g, w)


def test_channels_first_and_nested() -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert not ours.is_image_space_channels_first(spaces.Box(0, 255, (20, 3, 24), np.uint8))
    assert "second dimension was smallest" in str(caught[0].message)
    assert ours.is_image_space_channels_first(SPACES["gray_chw"])
    ours.check_for_nested_spaces(SPACES["dict"])
    nested = spaces.Tuple((spaces.Discrete(2), spaces.Dict({"x": spaces.Discrete(2)})))
    with pytest.raises(NotImplementedError, match="Nested observation spaces"):
        ours.check_for_nested_spaces(nested)
    with pytest.raises(NotImplementedError, match="Nested observation spaces"):
        sb3_pre.check_for_nested_spaces(to_gym(nested))


def test_bad_inputs() -> None:
    with pytest.raises(TypeError, match="Expecting a torch Tensor"):
        ours.preprocess_obs(np.zeros((1, 2)), SPACES["box"])
    with pytest.raises(TypeError, match="Expected dict"):
        ours.preprocess_obs(torch.zeros(1, 2), SPACES["dict"])
    with pytest.raises(NotImplementedError, match="Preprocessing not implemented"):
        ours.preprocess_obs(torch.zeros(1), spaces.Text(3))
    with pytest.raises(NotImplementedError, match="observation space is not supported"):
        ours.get_obs_shape(spaces.Text(3))
