"""The Box2D environments' pictures, drawn with palaestra's rasterizer (no pygame).

Geometry and colours follow Gymnasium 1.4's ``render()``: the world is drawn y-up at
``SCALE`` pixels per metre and flipped, so a world point ``(x, y)`` lands on pixel
``(x * SCALE, H - 1 - y * SCALE)``. Frames are not pixel copies of Gymnasium's (its outlines
are pygame's), but every shape is where Gymnasium puts it, in its colour.
"""

from __future__ import annotations

import itertools
import math
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


# BipedalWalker (Gymnasium: bipedal_walker.py)
WALKER_SIZE = (400, 600)
_BW_SCALE = 30.0
_BW_SKY: Color = (215, 215, 255)
_BW_GROUND: Color = (102, 153, 76)
_BW_GRASS: tuple[Color, Color] = ((76, 255, 76), (76, 204, 76))  # even, odd segments
_BW_OBSTACLE: tuple[Color, Color] = ((255, 255, 255), (153, 153, 153))
_BW_FLAG: Color = (230, 51, 0)
_BW_LIDAR: Color = (255, 0, 0)
_BW_STRIP_MARGIN = 600  # pixels of sky past the terrain's end, for the last frames


def _segment(img: np.ndarray, a: tuple[float, float], b: tuple[float, float], color: Color) -> None:
    """An anti-aliased line about one pixel wide, drawn as a thin quad (pixel coordinates)."""
    (ax, ay), (bx, by) = a, b
    length = float(np.hypot(bx - ax, by - ay))
    if length == 0.0:
        return
    nx, ny = -(by - ay) / length * 0.5, (bx - ax) / length * 0.5
    quad = [(ax + nx, ay + ny), (bx + nx, by + ny), (bx - nx, by - ny), (ax - nx, ay - ny)]
    raster.blend(img, raster.polygon_patch(quad, img.shape, grow=0.5), color)


def _outlined(img: np.ndarray, pts: np.ndarray, fill: Color, outline: Color) -> None:
    """A convex polygon with a one-pixel outline in a second colour."""
    raster.blend(img, raster.polygon_patch(pts, img.shape, grow=1.0), outline)
    raster.blend(img, raster.polygon_patch(pts, img.shape, grow=0.0), fill)


def walker_terrain_strip(
    grass: Sequence[tuple[float, float]], obstacles: Sequence[Points]
) -> np.ndarray:
    """The whole course of one episode, drawn once: sky, ground, grass line, obstacles, flag.

    ``grass`` is the terrain's surface points and ``obstacles`` the stumps, stairs and pit
    walls, in world metres. Frames are 600-pixel windows of this strip.
    """
    h = WALKER_SIZE[0]
    width = math.ceil(grass[-1][0] * _BW_SCALE) + _BW_STRIP_MARGIN
    img = np.empty((h, width, 3), dtype=np.uint8)
    img[:] = _BW_SKY
    pts = _to_pixels(grass, _BW_SCALE, h)  # [200, 2]
    bottom = float(h - 1)
    for (x0, y0), (x1, y1) in itertools.pairwise(pts):
        raster.fill_polygon(img, [(x0, y0), (x1, y1), (x1, bottom), (x0, bottom)], _BW_GROUND)
    for i, (a, b) in enumerate(itertools.pairwise(pts)):
        _segment(img, tuple(a), tuple(b), _BW_GRASS[i % 2])
    for poly in obstacles:  # over the grass line, which runs through the pits
        _outlined(img, _to_pixels(poly, _BW_SCALE, h), *_BW_OBSTACLE)
    # The start flag, 3 terrain steps in: a black pole and a red pennant.
    x, y1 = 14 / _BW_SCALE * 3 * _BW_SCALE, 400 / _BW_SCALE / 4 * _BW_SCALE
    y2 = y1 + 50
    raster.vline(img, round(x), h - 1 - round(y1), h - 1 - round(y2), BLACK)
    pennant = np.array([(x, h - 1 - y2), (x, h - 1 - (y2 - 10)), (x + 25, h - 1 - (y2 - 5))])
    _outlined(img, pennant, _BW_FLAG, BLACK)
    img.setflags(write=False)
    return img


def render_bipedal_walker(
    strip: np.ndarray,
    scroll: float,
    clouds: Sequence[Points],
    ray: tuple[tuple[float, float], tuple[float, float]] | None,
    bodies: Sequence[tuple[Points, tuple[Color, Color]]],
) -> np.ndarray:
    """BipedalWalker frame ``[400, 600, 3] uint8``: the strip's window at ``scroll`` metres,
    clouds (half the ground's speed, behind it), one lidar ray and the walker's parts."""
    h, w = WALKER_SIZE
    off = round(max(0.0, scroll) * _BW_SCALE)
    img = np.empty((h, w, 3), dtype=np.uint8)
    img[:] = _BW_SKY
    window = strip[:, off : off + w]
    img[:, : window.shape[1]] = window
    # Clouds (half the ground's speed) go behind the ground: one coverage for all of them, so
    # overlapping clouds leave no seams, painted where the strip shows sky only.
    shift = np.array([scroll * _BW_SCALE / 2 - off, 0.0])
    cover = np.zeros((h, w), dtype=np.float32)
    for poly in clouds:
        pts = _to_pixels(poly, _BW_SCALE, h) + shift
        # A cloud is star-shaped, not convex: a fan of triangles around its centre.
        centre = pts.mean(axis=0)
        fan = [(centre, a, b) for a, b in zip(pts, np.roll(pts, -1, axis=0))]
        patch = raster.polygons_patch(fan, img.shape)
        if patch is not None:
            x0, y0, cov = patch
            cov = cov[: h - y0, : w - x0]
            view = cover[y0 : y0 + cov.shape[0], x0 : x0 + cov.shape[1]]
            np.maximum(view, cov, out=view)
    cover *= (img == _BW_SKY).all(axis=-1)
    raster.blend_mask(img, cover, WHITE)
    move = np.array([-off, 0.0])
    if ray is not None:
        a, b = _to_pixels(ray, _BW_SCALE, h) + move
        _segment(img, tuple(a), tuple(b), _BW_LIDAR)
    for poly, (fill, outline) in bodies:
        _outlined(img, _to_pixels(poly, _BW_SCALE, h) + move, fill, outline)
    return img
