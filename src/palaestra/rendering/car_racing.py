"""CarRacing's pictures without pygame: the observation (96x96) and the video frame (600x400).

Gymnasium draws the scene on a 1000x800 pygame surface (y down), rotated and zoomed around the
car, flips it vertically, adds the dashboard and shrinks it with ``smoothscale``. This module
does the same steps on a :class:`palaestra.rendering.spans.Canvas`, which reproduces the
pygame/SDL_gfx primitives of :mod:`palaestra.rendering.gfx` for a whole frame at once, so most
pixels equal Gymnasium's. What differs: the score text (Gymnasium renders
it with pygame's bundled font; here digits are drawn as simple strokes) and the skid marks in
video frames (pygame's 2-pixel lines; here thin quads).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from palaestra.rendering import spans


@dataclass(frozen=True)
class Dims:
    """The env's constants the picture needs. The env module owns them and passes them in, so
    this module never imports the env (which imports this module to draw)."""

    playfield: float
    grass_dim: float
    max_shape_dim: float
    scale: float
    zoom: float
    state_size: tuple[int, int]  # (W, H) of the observation
    video_size: tuple[int, int]  # (W, H) of a video frame
    hull_color: tuple[float, float, float]  # 0..1
    wheel_w: float
    wheel_r: float
    car_size: float
    wheel_white: tuple[int, int, int]


W, H = 1000, 800
_TWO_PI = 2 * math.pi
_HALF_PI = math.pi / 2
_EPS = 1e-6  # pygame.math.Vector2's epsilon: rotations this close to a right angle are exact


def _rotator(angle: float) -> tuple[int, float, float]:
    """pygame's ``Vector2.rotate_rad``: ``(quarter turns, cos, sin)``; quarter turns is -1
    unless the angle is within epsilon of a multiple of 90 degrees (then exact)."""
    a = math.fmod(angle, _TWO_PI)
    if a < 0:
        a += _TWO_PI
    if math.fmod(a + _EPS, _HALF_PI) < 2 * _EPS:
        return int((a + _EPS) / _HALF_PI) % 4, 0.0, 0.0
    return -1, math.cos(a), math.sin(a)


def _rotate(pts: np.ndarray, rot: tuple[int, float, float]) -> np.ndarray:
    """Rotate ``[..., 2]`` points as pygame does (same products, same order)."""
    quarter, c, s = rot
    x, y = pts[..., 0], pts[..., 1]
    if quarter == 0:
        return pts.copy()
    if quarter == 1:
        return np.stack([-y, x], axis=-1)
    if quarter == 2:
        return np.stack([-x, -y], axis=-1)
    if quarter == 3:
        return np.stack([y, -x], axis=-1)
    return np.stack([c * x - s * y, s * x + c * y], axis=-1)


def _rgb(color: Any) -> tuple[int, int, int]:
    return (int(color[0]), int(color[1]), int(color[2]))


@lru_cache(maxsize=1)
def _grass_patches(grass_dim: float) -> np.ndarray:
    """Gymnasium's checkerboard of grass squares, ``[400, 4, 2]`` world points."""
    polys = []
    for x in range(-20, 20, 2):
        for y in range(-20, 20, 2):
            polys.append([
                (grass_dim * x + grass_dim, grass_dim * y + 0),
                (grass_dim * x + 0, grass_dim * y + 0),
                (grass_dim * x + 0, grass_dim * y + grass_dim),
                (grass_dim * x + grass_dim, grass_dim * y + grass_dim),
            ])  # fmt: skip
    return np.array(polys, dtype=np.float64)


def _to_screen(
    polys: np.ndarray, rot: tuple[int, float, float], zoom: float, trans: tuple[float, float]
) -> np.ndarray:
    pts = _rotate(polys, rot)
    return np.stack([pts[..., 0] * zoom + trans[0], pts[..., 1] * zoom + trans[1]], axis=-1)


def _visible(screen: np.ndarray, margin: float) -> np.ndarray:
    """Gymnasium's cull: a polygon is drawn if any vertex is within the window + margin."""
    x, y = screen[..., 0], screen[..., 1]
    inside = (x >= -margin) & (x <= W + margin) & (y >= -margin) & (y <= H + margin)
    return np.asarray(inside.any(axis=-1))


def _gfx_polygons(canvas: spans.Canvas, screen: np.ndarray, colors: list[Any]) -> None:
    """``gfxdraw.aapolygon`` then ``gfxdraw.filled_polygon`` for each of ``[M, k, 2]``
    polygons, coordinates truncated (as pygame hands floats to SDL_gfx)."""
    pixels = np.trunc(screen).astype(np.int64)
    canvas.gfx_polygons(pixels[..., 0], pixels[..., 1], colors)


def _pg_polygon(canvas: spans.Canvas, pts: Any, color: tuple[int, int, int]) -> None:
    """``pygame.draw.polygon`` (filled; coordinates truncated)."""
    arr = np.trunc(np.asarray(pts, dtype=np.float64)).astype(np.int64)
    canvas.pg_polygon(arr[:, 0], arr[:, 1], color)


def _draw_road(
    canvas: spans.Canvas, env: Any, zoom: float, trans: Any, rot: Any, dims: Dims
) -> None:
    b = dims.playfield
    field = np.array([[(b, b), (b, -b), (-b, -b), (-b, b)]])
    quads = [_to_screen(field, rot, zoom, trans)]
    colors = [_rgb(env.bg_color)]
    grass = _to_screen(_grass_patches(dims.grass_dim), rot, zoom, trans)
    quads.append(grass[_visible(grass, dims.max_shape_dim)])
    colors += [_rgb(env.grass_color)] * len(quads[-1])
    if env.road_poly:
        screen = _to_screen(_road_points(env), rot, zoom, trans)
        shown = np.flatnonzero(_visible(screen, dims.max_shape_dim)).tolist()
        quads.append(screen[shown])
        colors += [_rgb(env.road_poly[i][1]) for i in shown]
    # One call for the field, the grass and the road (drawn in that order): a batch's cost
    # is mostly per call.
    _gfx_polygons(canvas, np.concatenate(quads), colors)


def _road_points(env: Any) -> np.ndarray:
    """The road's polygons as one ``[M, 4, 2]`` array, built once per track."""
    cached = getattr(env, "_road_points_cache", None)
    if cached is None or cached[0] is not env.road_poly or cached[1] != len(env.road_poly):
        points = np.array([p for p, _ in env.road_poly], dtype=np.float64)
        cached = (env.road_poly, len(env.road_poly), points)
        env._road_points_cache = cached
    return cached[2]


def _draw_car(
    canvas: spans.Canvas,
    car: Any,
    zoom: float,
    trans: Any,
    rot: Any,
    marks: bool,
    dims: Dims,
) -> None:
    def screen(points: list[tuple[float, float]]) -> np.ndarray:
        return _to_screen(np.asarray(points, dtype=np.float64), rot, zoom, trans)

    if marks:
        for mark in car.skid_marks:
            pts = screen(mark.poly)
            for a, b in itertools.pairwise(pts):
                d = b - a
                length = float(np.hypot(*d))
                if length == 0.0:
                    continue
                n = np.array([-d[1], d[0]]) / length  # 2 pixels wide
                _pg_polygon(canvas, [a, b, b + n, a + n], mark.color)
    bodies: list[tuple[Any, tuple[int, int, int], Any]] = [
        (w.body, (0, 0, 0), w) for w in car.wheels
    ]
    bodies.append((car.hull, _rgb([c * 255 for c in dims.hull_color]), None))
    for body, color, wheel in bodies:
        for f in body.fixtures:
            trans_b = f.body.transform
            # Box2D's own float32 transform, as Gymnasium's ``trans * v``.
            path = [tuple(trans_b * v) for v in f.shape.vertices]
            _pg_polygon(canvas, screen(path), color)
            if wheel is None:
                continue
            a1, a2 = wheel.phase, wheel.phase + 1.2  # the white band turns with the wheel
            s1, s2, c1, c2 = math.sin(a1), math.sin(a2), math.cos(a1), math.cos(a2)
            if s1 > 0 and s2 > 0:
                continue
            if s1 > 0:
                c1 = float(np.sign(c1))
            if s2 > 0:
                c2 = float(np.sign(c2))
            ww, wr, size = dims.wheel_w, dims.wheel_r, dims.car_size
            band = [(-ww * size, +wr * c1 * size), (+ww * size, +wr * c1 * size),
                    (+ww * size, +wr * c2 * size), (-ww * size, +wr * c2 * size)]  # fmt: skip
            path = [tuple(trans_b * v) for v in band]
            _pg_polygon(canvas, screen(path), dims.wheel_white)


def _draw_indicators(canvas: spans.Canvas, car: Any) -> None:
    """The dashboard along the bottom (drawn after the flip, in screen coordinates)."""
    s, h = W / 40.0, H / 40.0
    _pg_polygon(canvas, [(W, H), (W, H - 5 * h), (0, H - 5 * h), (0, H)], (0, 0, 0))

    def vertical(place: float, val: float) -> list[tuple[float, float]]:
        return [(place * s, H - (h + h * val)), ((place + 1) * s, H - (h + h * val)),
                ((place + 1) * s, H - h), ((place + 0) * s, H - h)]  # fmt: skip

    def horizontal(place: float, val: float) -> list[tuple[float, float]]:
        return [((place + 0) * s, H - 4 * h), ((place + val) * s, H - 4 * h),
                ((place + val) * s, H - 2 * h), ((place + 0) * s, H - 2 * h)]  # fmt: skip

    v = car.hull.linearVelocity
    speed = math.sqrt(v[0] * v[0] + v[1] * v[1])
    bars = [
        (speed, vertical(5, 0.02 * speed), (255, 255, 255)),
        (car.wheels[0].omega, vertical(7, 0.01 * car.wheels[0].omega), (0, 0, 255)),  # ABS
        (car.wheels[1].omega, vertical(8, 0.01 * car.wheels[1].omega), (0, 0, 255)),
        (car.wheels[2].omega, vertical(9, 0.01 * car.wheels[2].omega), (51, 0, 255)),
        (car.wheels[3].omega, vertical(10, 0.01 * car.wheels[3].omega), (51, 0, 255)),
    ]
    steer = car.wheels[0].joint.angle
    bars.append((steer, horizontal(20, -10.0 * steer), (0, 255, 0)))
    spin = car.hull.angularVelocity
    bars.append((spin, horizontal(30, -0.8 * spin), (255, 0, 0)))
    for value, points, color in bars:
        if abs(value) > 1e-4:
            _pg_polygon(canvas, points, color)


def render(env: Any, mode: str, dims: Dims) -> np.ndarray:
    """The frame of ``env`` (a CarRacing) for ``mode``: ``state_pixels`` (96x96) or
    ``rgb_array`` / ``human`` (600x400); ``dims`` are the env's constants."""
    car = env.car
    angle = -car.hull.angle
    # The first second zooms in from far away.
    zoom = 0.1 * dims.scale * max(1 - env.t, 0) + dims.zoom * dims.scale * min(env.t, 1)
    pos = car.hull.position
    rot = _rotator(angle)
    scroll = _rotate(np.array([-(pos[0]) * zoom, -(pos[1]) * zoom]), rot)
    trans = (W / 2 + float(scroll[0]), H / 4 + float(scroll[1]))

    canvas = spans.Canvas(H, W)
    _draw_road(canvas, env, zoom, trans, rot, dims)
    _draw_car(canvas, car, zoom, trans, rot, marks=mode != "state_pixels", dims=dims)
    canvas.flip()  # pygame.transform.flip(surf, False, True)
    _draw_indicators(canvas, car)
    _draw_score(canvas, env.reward)
    size = dims.state_size if mode == "state_pixels" else dims.video_size
    return canvas.shrink(*size)


# Seven-segment digits for the score: segments a-g as (x0, y0, x1, y1) boxes in a 20x30 cell.
_SEGMENTS = {
    "a": (3, 0, 17, 4), "b": (16, 2, 20, 15), "c": (16, 15, 20, 28), "d": (3, 26, 17, 30),
    "e": (0, 15, 4, 28), "f": (0, 2, 4, 15), "g": (3, 13, 17, 17),
}  # fmt: skip
_DIGITS = {
    "0": "abcdef", "1": "bc", "2": "abdeg", "3": "abcdg", "4": "bcfg", "5": "acdfg",
    "6": "acdefg", "7": "abc", "8": "abcdefg", "9": "abcdfg", "-": "g",
}  # fmt: skip


def _draw_score(canvas: spans.Canvas, reward: float) -> None:
    """The score as in Gymnasium (``f"{reward:04.0f}"`` centred at (60, 750), white on black),
    in simple seven-segment digits instead of pygame's font."""
    text = f"{reward:04.0f}"
    cell, gap = 20, 4
    width = len(text) * (cell + gap) - gap
    x0, y0 = 60 - width // 2, 750 - 15
    boxes = []
    for k, ch in enumerate(text):
        left = x0 + k * (cell + gap)
        for seg in _DIGITS.get(ch, ""):
            a, b, c, d = _SEGMENTS[seg]
            boxes.append((left + a, y0 + b, left + c, y0 + d))
    canvas.rects(boxes, (255, 255, 255))
