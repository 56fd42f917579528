"""palaestra.rendering.gfx against pygame itself: the same pixels for the same calls."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from palaestra.rendering import gfx

pygame = pytest.importorskip("pygame")
gfxdraw = pytest.importorskip("pygame.gfxdraw")


def _shapes(rng: np.random.Generator, count: int) -> list[np.ndarray]:
    """Quads of every size (CarRacing's tiles at every zoom), some off the image's edges,
    and random triangles."""
    shapes = []
    for t in range(count):
        if t % 3 == 2:
            shapes.append(rng.uniform(-40, 140, (3, 2)).astype(int))
            continue
        centre = rng.uniform(-10, 110, 2)
        angle, radius = rng.uniform(0, 2 * np.pi), rng.uniform(0.5, 60)
        quad = [
            (centre[0] + radius * np.cos(angle + k * np.pi / 2) + rng.uniform(-3, 3),
             centre[1] + 0.7 * radius * np.sin(angle + k * np.pi / 2))
            for k in range(4)
        ]  # fmt: skip
        shapes.append(np.trunc(np.array(quad)).astype(int))
    return shapes


def _compare(draw_ref: Callable[..., Any], draw_ours: Callable[..., Any], seed: int) -> None:
    rng = np.random.default_rng(seed)
    for i, pts in enumerate(_shapes(rng, 150)):
        base = rng.integers(0, 256, (100, 100, 3), dtype=np.uint8)
        color = tuple(int(v) for v in rng.integers(0, 256, 3))
        surface = pygame.surfarray.make_surface(base.transpose(1, 0, 2))
        draw_ref(surface, [tuple(int(v) for v in p) for p in pts], color)
        ref = pygame.surfarray.array3d(surface).transpose(1, 0, 2)
        ours = base.copy()
        draw_ours(ours, pts[:, 0], pts[:, 1], color)
        assert np.array_equal(ours, ref), f"shape {i}: {pts.tolist()}"


def test_filled_polygon_equals_gfxdraw() -> None:
    _compare(gfxdraw.filled_polygon, gfx.fill_polygon, seed=0)


def test_aapolygon_equals_gfxdraw() -> None:
    _compare(gfxdraw.aapolygon, gfx.aa_polygon, seed=1)


def test_convex_polygon_fill_equals_pygame_draw() -> None:
    def convex_only(img: np.ndarray, xs: Any, ys: Any, color: Any) -> None:
        gfx.pg_fill_polygon(img, xs, ys, color)

    rng = np.random.default_rng(2)
    # Quads inside the image: the car and the dashboard always are. (pygame's clipping at the
    # left edge and its rule for self-crossing outlines are not reproduced.)
    quads = [p for p in _shapes(rng, 1200)[::3] if p.min() >= 0 and p.max() < 100]
    assert len(quads) > 40
    for pts in quads:
        base = np.zeros((100, 100, 3), dtype=np.uint8)
        surface = pygame.surfarray.make_surface(base)
        pygame.draw.polygon(surface, (200, 10, 30), [tuple(int(v) for v in p) for p in pts])
        ours = base.copy()
        convex_only(ours, pts[:, 0], pts[:, 1], (200, 10, 30))
        assert np.array_equal(ours, pygame.surfarray.array3d(surface).transpose(1, 0, 2))


@pytest.mark.parametrize("src, dst", [((1000, 800), (96, 96)), ((1000, 800), (600, 400)),
                                      ((137, 91), (20, 13))])  # fmt: skip
def test_smoothscale_shrink_equals_pygame(src: tuple[int, int], dst: tuple[int, int]) -> None:
    img = np.random.default_rng(3).integers(0, 256, (src[1], src[0], 3), dtype=np.uint8)
    surface = pygame.surfarray.make_surface(img.transpose(1, 0, 2))
    ref = pygame.surfarray.array3d(pygame.transform.smoothscale(surface, dst))
    assert np.array_equal(gfx.smoothscale_shrink(img, *dst), ref.transpose(1, 0, 2))


@pytest.mark.parametrize("dst", [(96, 96), (600, 400), (7, 5)])
def test_smoothscale_shrink_of_extremes_equals_pygame(dst: tuple[int, int]) -> None:
    """White areas (every lane's sum at its largest: the saturating pack), black, and stripes
    of single pixels, whose sums lean on the split samples' weights."""
    img = np.zeros((800, 1000, 3), dtype=np.uint8)
    img[:300] = 255
    img[300:500, ::2] = (255, 0, 255)
    img[500:, :, 1] = np.arange(1000, dtype=np.uint8)[None, :] * 37
    surface = pygame.surfarray.make_surface(img.transpose(1, 0, 2))
    ref = pygame.surfarray.array3d(pygame.transform.smoothscale(surface, dst))
    assert np.array_equal(gfx.smoothscale_shrink(img, *dst), ref.transpose(1, 0, 2))
