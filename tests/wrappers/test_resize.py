"""``resize_area`` / ``ResizeObservation`` reproduce OpenCV's ``INTER_AREA`` bytes.

The digests below are of ``cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA)`` (OpenCV 5.0)
on the seeded images built here; where OpenCV is importable the test also compares directly,
and with Gymnasium's ``ResizeObservation``.
"""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np
import pytest
from tests.wrappers.conftest import GYM, assert_same, make_toy, pal, rollout

from palaestra.wrappers.resize import resize_area

# (input shape, output (h, w), sha256 prefix of OpenCV's output); odd rows use a 4-level image
# full of exact .5 ties, where a wrong rounding rule would show.
CV2_DIGESTS = [
    ((210, 160, 3), (84, 84), "ad32a9f3659b79384c160de0ece35907"),
    ((210, 160), (84, 84), "804064f09f3423bc88e54cc94a9d58f0"),
    ((96, 96, 3), (64, 64), "1f296103093e8ed56fd69872a7197269"),
    ((100, 80, 3), (50, 40), "3247052c040b02f65c2c590f07023922"),
    ((99, 77, 3), (33, 30), "737889420364b6be01c1403d9e6ff113"),
    ((210, 160, 3), (105, 80), "db8b2507ea55e4f18a1659d02c38d7d1"),
    ((64, 64, 3), (21, 16), "4dda3a7e6fb721d5051e1c8c2f64d0a2"),
    ((90, 60, 1), (30, 30), "5dbd71c5f32ecad9afe994df921b2c78"),
    ((50, 50, 3), (1, 1), "b6143ba693f094d997a054d3d1ee90dc"),
]


def _image(i: int, shape: tuple[int, ...]) -> np.ndarray:
    img = np.random.default_rng(i).integers(0, 256, shape, dtype=np.uint8)
    return (img // 64 * 64).astype(np.uint8) if i % 2 else img


@pytest.mark.parametrize("i", range(len(CV2_DIGESTS)))
def test_bytes_match_opencv(i: int) -> None:
    shape, out_hw, digest = CV2_DIGESTS[i]
    out = resize_area(_image(i, shape), out_hw)
    assert out.shape == out_hw + shape[2:] and out.dtype == np.uint8
    assert hashlib.sha256(out.tobytes()).hexdigest()[:32] == digest


def test_against_opencv_when_installed() -> None:
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(5)
    for shape, (h, w), _ in CV2_DIGESTS:
        img = rng.integers(0, 256, shape, dtype=np.uint8)
        expected = cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA)
        assert np.array_equal(resize_area(img, (h, w)).reshape(expected.shape), expected)


def test_identity_and_constant_images() -> None:
    img = _image(0, (6, 5, 3))
    assert np.array_equal(resize_area(img, (6, 5)), img)
    flat = np.full((210, 160, 3), 77, dtype=np.uint8)
    assert np.all(resize_area(flat, (84, 84)) == 77)


def test_upscaling_is_refused() -> None:
    with pytest.raises(ValueError, match=r"only downscales: cannot resize \(4, 4\) to \(8, 2\)"):
        resize_area(np.zeros((4, 4), np.uint8), (8, 2))
    with pytest.raises(ValueError, match=r"only downscales"):
        pal().W.ResizeObservation(make_toy(pal(), "ToyImage"), (12, 2))
    with pytest.raises(TypeError, match="shape to be a tuple"):
        pal().W.ResizeObservation(make_toy(pal(), "ToyImage"), [3, 2])
    with pytest.raises(TypeError, match="requires a Box"):
        pal().W.ResizeObservation(make_toy(pal(), "ToyChain"), (3, 2))


def test_wrapper_matches_gymnasium_when_opencv_is_installed() -> None:
    pytest.importorskip("cv2")

    def wrap(e: Any, L: Any) -> Any:
        return L.W.ResizeObservation(e, (4, 3))

    theirs, expected = rollout(GYM, "ToyImage", wrap)
    ours, got = rollout(pal(), "ToyImage", wrap)
    assert repr(ours.observation_space) == repr(theirs.observation_space)
    assert_same(got, expected)


def test_wrapper_space_and_observations() -> None:
    env = pal().W.ResizeObservation(make_toy(pal(), "ToyImage"), (3, 2))
    assert repr(env.observation_space) == "Box(0, 255, (3, 2, 3), uint8)"
    obs, _ = env.reset(seed=0)
    raw, _ = make_toy(pal(), "ToyImage").reset(seed=0)
    assert np.array_equal(obs, resize_area(raw, (3, 2)))
