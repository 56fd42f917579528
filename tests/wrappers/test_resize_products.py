"""The matrix-product area resize gives the term-by-term (OpenCV-order) bytes (issue 16, item 14).

``resize_area_f32`` takes :mod:`palaestra.wrappers.resize_products` where the scale factors are
small fractions (Atari's 210x160 -> 84x84); ``resize_area_terms`` is the OpenCV-order path that
``tests/wrappers/test_resize.py`` pins to OpenCV's bytes. They must agree on every pixel,
exact ties included; where OpenCV is installed, real game frames are compared with it too.
"""

from __future__ import annotations

import numpy as np
import pytest

import palaestra
from palaestra.wrappers import resize_products
from palaestra.wrappers.atari import WarpFrame, _gray_f32
from palaestra.wrappers.resize import _integer_plan, resize_area, resize_area_f32, resize_area_terms

# (source h, w), (output h, w): sizes whose factors are small fractions on both axes.
PRODUCT_SIZES = [((210, 160), (84, 84)), ((100, 80), (40, 32)), ((90, 60), (36, 40))]


def _images(shape: tuple[int, ...], n: int, seed: int) -> list[np.ndarray]:
    """Random images, full range (with exact ties at 210x160 -> 84x84), every other one on a
    few levels (flat areas and hard edges, like game frames)."""
    rng = np.random.default_rng(seed)
    levels = np.array([0, 1, 3, 100, 101, 250, 255], np.uint8)
    images = []
    for i in range(n):
        if i % 2:
            images.append(rng.choice(levels, shape))
        else:
            images.append(rng.integers(0, 256, shape, dtype=np.uint8))
    return images


def _counting_ties(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Patch the tie fix-up to record how many pixels it recomputes per call."""
    counts: list[int] = []
    fix = resize_products._opencv_order

    def counted(src: np.ndarray, plan: object, flat: np.ndarray) -> np.ndarray:
        counts.append(len(flat))
        return fix(src, plan, flat)  # type: ignore[arg-type]

    monkeypatch.setattr(resize_products, "_opencv_order", counted)
    return counts


def test_plans_exist_only_where_the_products_are_safe() -> None:
    assert _integer_plan(210, 160, 84, 84, 1) is not None
    assert _integer_plan(210, 160, 84, 84, 3) is not None
    # 210/64 = 105/32 and 160/48 = 10/3: D = 1050, too close to OpenCV's float32 noise.
    assert _integer_plan(210, 160, 64, 48, 1) is None
    # 97 is prime: D = 97 * 160/84's 40 = 3880.
    assert _integer_plan(97, 160, 1, 84, 1) is None


@pytest.mark.parametrize(("src", "dst"), PRODUCT_SIZES)
@pytest.mark.parametrize("channels", [1, 3])
def test_products_equal_the_term_by_term_path(
    src: tuple[int, int], dst: tuple[int, int], channels: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert _integer_plan(*src, *dst, channels) is not None
    ties = _counting_ties(monkeypatch)
    for img in _images((*src, channels), 12, seed=channels):
        flat = img.reshape(src[0], -1).astype(np.float32)
        expected = resize_area_terms(flat, *dst, channels)
        np.testing.assert_array_equal(resize_area_f32(flat, *dst, channels), expected)
    if src == (210, 160):  # D = 200 is even: exact ties exist, and the fix-up ran
        assert sum(ties) > 0


def test_ties_need_the_fix_up() -> None:
    """Rounding ``N / D`` alone is wrong on some exact ties: OpenCV's float32 order decides."""
    plan = _integer_plan(210, 160, 84, 84, 1)
    assert plan is not None
    wrong = 0
    for img in _images((210, 160), 6, seed=7):
        src = img.astype(np.float32)
        rows = np.matmul(plan.rows, src.reshape(42, 5, 160)).reshape(-1, 40)
        naive = np.rint(rows @ plan.cols).astype(np.uint8).reshape(84, 84)
        wrong += int(np.sum(naive != resize_area_terms(src, 84, 84)))
    assert wrong > 0


def test_rgb_resize_area_takes_the_products_and_matches() -> None:
    for img in _images((210, 160, 3), 4, seed=11):
        flat = img.reshape(210, -1).astype(np.float32)
        expected = resize_area_terms(flat, 84, 84, 3).reshape(84, 84, 3)
        np.testing.assert_array_equal(resize_area(img, (84, 84)), expected)


def _game_frames(game: str, n: int) -> list[np.ndarray]:
    env = palaestra.make(f"ALE/{game}-v5")
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    frames = []
    for _ in range(n):
        obs, _, terminated, truncated, _ = env.step(int(rng.integers(env.action_space.n)))
        frames.append(obs)
        if terminated or truncated:
            env.reset()
    env.close()
    return frames


# Qbert and Enduro have dozens of exact ties per frame (Enduro's are where rounding N/D alone
# goes wrong), Breakout about one.
GAMES = [
    "Breakout",
    "Qbert",
    "Enduro",
    pytest.param("Pong", marks=pytest.mark.slow),
    pytest.param("SpaceInvaders", marks=pytest.mark.slow),
    pytest.param("MsPacman", marks=pytest.mark.slow),
]


@pytest.mark.parametrize("game", GAMES)
def test_warp_frame_on_game_frames(game: str, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("ale_py")
    try:
        import cv2
    except ImportError:  # the term-by-term comparison still runs
        cv2 = None
    ties = _counting_ties(monkeypatch)
    warp = WarpFrame(palaestra.make("BreakoutNoFrameskip-v4"))
    for frame in _game_frames(game, 20):
        got = warp.observation(frame)[:, :, 0]
        np.testing.assert_array_equal(got, resize_area_terms(_gray_f32(frame), 84, 84))
        if cv2 is None:
            continue
        gray = cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)
        expected = cv2.resize(gray, (84, 84), interpolation=cv2.INTER_AREA)
        np.testing.assert_array_equal(got, expected)
    assert sum(ties) > 0
