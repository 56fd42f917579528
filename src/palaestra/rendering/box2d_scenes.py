"""The Box2D environments' pictures, drawn with palaestra's rasterizer (no pygame).

Geometry and colours follow Gymnasium 1.4's ``render()``: the world is drawn y-up at
``SCALE`` pixels per metre and flipped, so a world point ``(x, y)`` lands on pixel
``(x * SCALE, H - 1 - y * SCALE)``. Frames are not pixel copies of Gymnasium's (its outlines
are pygame's), but every shape is where Gymnasium puts it, in its colour.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from palaestra.rendering import raster
from palaestra.rendering.raster import Color

WHITE: Color = (255, 255, 255)
BLACK: Color = (0, 0, 0)

# LunarLander (Gymnasium: lunar_lander.py)
LUNAR_LANDER_SIZE = (400, 600)  # (H, W)
_LL_SCALE = 30.0
_LL_FILL: Color = (128, 102, 230)
_LL_OUTLINE: Color = (77, 77, 128)
_LL_FLAG: Color = (204, 204, 0)

Points = Sequence[tuple[float, float]]


def _to_pixels(points: Points | np.ndarray, scale: float, height: int) -> np.ndarray:
    """World points (metres, y up) to pixel coordinates (y down)."""
    pts = np.asarray(points, dtype=np.float64) * scale
    pts[:, 1] = height - 1 - pts[:, 1]
    return pts


def _flags(img: np.ndarray, pad_xs: tuple[float, float], pad_y: float) -> None:
    """The two helipad flags: a white pole and a yellow pennant, 50 px tall."""
    h = img.shape[0]
    for x in pad_xs:
        px, y1 = x * _LL_SCALE, pad_y * _LL_SCALE
        y2 = y1 + 50
        raster.vline(img, round(px), h - 1 - round(y1), h - 1 - round(y2), WHITE)
        pennant = np.array([(px, y2), (px, y2 - 10), (px + 25, y2 - 5)])
        pennant[:, 1] = h - 1 - pennant[:, 1]
        raster.fill_polygon(img, pennant, _LL_FLAG)


def lunar_lander_background(
    sky_polys: Sequence[Points], pad_xs: tuple[float, float], pad_y: float
) -> np.ndarray:
    """The static layer of one episode: white ground under a black sky, and the flags."""
    h, w = LUNAR_LANDER_SIZE
    img = np.full((h, w, 3), 255, dtype=np.uint8)
    sky = [_to_pixels(poly, _LL_SCALE, h) for poly in sky_polys]
    raster.blend(img, raster.polygons_patch(sky, img.shape), BLACK)
    _flags(img, pad_xs, pad_y)
    img.setflags(write=False)  # shared by every frame of the episode: copy before drawing
    return img


def _spark_color(ttl: float) -> Color:
    """Gymnasium's exhaust colour: red-white when fresh, fading to dark grey."""
    red = int(max(0.2, 0.15 + ttl) * 255)
    rest = int(max(0.2, 0.5 * ttl) * 255)
    return (red, rest, rest)


def render_lunar_lander(
    background: np.ndarray,
    sparks: Sequence[tuple[float, float, float]],
    hull: Sequence[Points],
    pad_xs: tuple[float, float],
    pad_y: float,
) -> np.ndarray:
    """LunarLander frame ``[400, 600, 3] uint8``.

    ``sparks`` are exhaust particles ``(x, y, ttl)`` and ``hull`` the lander's and legs'
    polygons, all in world metres; each hull polygon gets a darker one-pixel outline.
    """
    h, _ = LUNAR_LANDER_SIZE
    img = background.copy()
    for x, y, ttl in sparks:
        raster.fill_circle(img, x * _LL_SCALE, h - 1 - y * _LL_SCALE, 1.0, _spark_color(ttl))
    for poly in hull:
        pts = _to_pixels(poly, _LL_SCALE, h)
        raster.blend(img, raster.polygon_patch(pts, img.shape, grow=1.0), _LL_OUTLINE)
        raster.blend(img, raster.polygon_patch(pts, img.shape, grow=0.0), _LL_FILL)
    _flags(img, pad_xs, pad_y)  # Gymnasium draws the flags over everything
    return img
