"""A small numpy rasterizer: anti-aliased convex polygons, discs, lines and polylines.

Every function draws into an ``(H, W, 3) uint8`` image in place, in *pixel* coordinates
(x to the right, y down), with the centre of pixel ``(col, row)`` at the integer point
``(col, row)`` — the convention of pygame's ``gfxdraw``, so scenes can reuse Gymnasium's
geometry unchanged. Work is restricted to each shape's bounding box, and edges are
anti-aliased from the distance to the edge (one pixel wide ramp), which is cheap and looks
like ``aapolygon`` + ``filled_polygon``.

Shapes can also be turned into a :class:`Patch` (a coverage mask and its position) once and
blended many times, which is how scenes cache their static parts.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

Color = tuple[int, int, int]
Point = tuple[float, float]

# How far past the exact outline the drawn edge reaches. pygame fills every pixel centre on
# or inside the outline and draws an anti-aliased outline on top, so its shapes reach about
# one pixel past the exact geometry; 1.0 matches its frames best (measured in
# tests/rendering/test_similarity.py: 0.5 doubles the pixels that differ).
EDGE_GROW = 1.0
DISC_GROW = 1.0


_PIXEL = np.dtype((np.void, 3))  # one RGB pixel as a single element


class Patch(NamedTuple):
    """A coverage mask ``cov`` (float32 in [0, 1], shape ``[h, w]``) placed at ``(x0, y0)``."""

    x0: int
    y0: int
    cov: np.ndarray


def blend(img: np.ndarray, patch: Patch | None, color: Color) -> None:
    """Paint ``color`` over ``img`` with the patch's coverage as alpha."""
    if patch is None:
        return
    x0, y0, cov = patch
    if x0 < 0 or y0 < 0:  # crop a patch hanging off the top/left (slices can't be negative)
        cov = cov[max(-y0, 0) :, max(-x0, 0) :]
        x0, y0 = max(x0, 0), max(y0, 0)
    cov = cov[: img.shape[0] - y0, : img.shape[1] - x0]
    h, w = cov.shape
    if h <= 0 or w <= 0:
        return
    rgb = np.asarray(color, dtype=np.uint8)
    full = cov >= 1.0
    if img.flags.c_contiguous:
        # Opaque pixels (the bulk of a shape) are copied as whole 3-byte pixels through a void
        # view: one masked assignment instead of three (about 6x faster than per channel).
        pixels = img.view(_PIXEL)[:, :, 0]
        pixels[y0 : y0 + h, x0 : x0 + w][full] = rgb.view(_PIXEL)[0]
    else:
        np.copyto(img[y0 : y0 + h, x0 : x0 + w], rgb, where=full[:, :, None])
    # Only the anti-aliased rim pays for the float blend.
    rows, cols = np.nonzero((cov > 0.0) & ~full)
    if rows.size:
        region = img[y0 : y0 + h, x0 : x0 + w]
        a = cov[rows, cols][:, None]
        src = region[rows, cols].astype(np.float32)
        region[rows, cols] = (src + (rgb - src) * a + 0.5).astype(np.uint8)


def _bbox(
    xmin: float, xmax: float, ymin: float, ymax: float, shape: tuple[int, ...], pad: float
) -> tuple[int, int, int, int] | None:
    """Integer pixel box ``[x0, x1) x [y0, y1)`` around the extent, clipped to the image."""
    h, w = shape[0], shape[1]
    x0 = max(math.floor(xmin - pad), 0)
    x1 = min(math.ceil(xmax + pad) + 1, w)
    y0 = max(math.floor(ymin - pad), 0)
    y1 = min(math.ceil(ymax + pad) + 1, h)
    if x0 >= x1 or y0 >= y1:
        return None
    return x0, x1, y0, y1


def polygon_patch(
    points: Sequence[Point] | np.ndarray, shape: tuple[int, ...], grow: float = EDGE_GROW
) -> Patch | None:
    """Coverage of a convex polygon (any winding), anti-aliased over one pixel."""
    return polygons_patch([points], shape, grow)


def polygons_patch(
    polygons: Sequence[Sequence[Point] | np.ndarray],
    shape: tuple[int, ...],
    grow: float = EDGE_GROW,
) -> Patch | None:
    """Coverage of a union of convex polygons (e.g. a concave shape cut into convex pieces)."""
    polys = [np.asarray(p, dtype=np.float64) for p in polygons]
    allp = np.concatenate(polys)
    box = _bbox(allp[:, 0].min(), allp[:, 0].max(), allp[:, 1].min(), allp[:, 1].max(), shape, 2)
    if box is None:
        return None
    x0, x1, y0, y1 = box
    xs = np.arange(x0, x1, dtype=np.float32)[None, :]
    ys = np.arange(y0, y1, dtype=np.float32)[:, None]
    cov: np.ndarray | None = None
    for pts in polys:
        dist = _inner_distance(pts, xs, ys)
        if dist is not None:
            c = np.clip(dist + np.float32(grow), 0.0, 1.0)
            cov = c if cov is None else np.maximum(cov, c)
    return None if cov is None else Patch(x0, y0, cov)


def _inner_distance(pts: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray | None:
    """Signed distance of pixel centres to a convex polygon's outline (positive inside)."""
    nxt = np.roll(pts, -1, axis=0)
    # Signed area tells the winding; flip so that "inside" is positive for every edge.
    area2 = float(np.sum(pts[:, 0] * nxt[:, 1] - nxt[:, 0] * pts[:, 1]))
    sign = 1.0 if area2 >= 0 else -1.0
    dist: np.ndarray | None = None
    for (ax, ay), (bx, by) in zip(pts, nxt):
        ex, ey = bx - ax, by - ay
        length = math.hypot(ex, ey)
        if length == 0.0:
            continue
        nx, ny = -ey * sign / length, ex * sign / length
        d = (xs - np.float32(ax)) * np.float32(nx) + (ys - np.float32(ay)) * np.float32(ny)
        dist = d if dist is None else np.minimum(dist, d)
    return dist


def disc_patch(
    cx: float, cy: float, radius: float, shape: tuple[int, ...], grow: float = DISC_GROW
) -> Patch | None:
    """Coverage of a filled disc, anti-aliased over one pixel."""
    box = _bbox(cx - radius, cx + radius, cy - radius, cy + radius, shape, 2)
    if box is None:
        return None
    x0, x1, y0, y1 = box
    dx = np.arange(x0, x1, dtype=np.float32)[None, :] - np.float32(cx)
    dy = np.arange(y0, y1, dtype=np.float32)[:, None] - np.float32(cy)
    cov = np.clip(np.float32(radius + grow) - np.sqrt(dx * dx + dy * dy), 0.0, 1.0)
    return Patch(x0, y0, cov)


def fill_polygon(img: np.ndarray, points: Sequence[Point] | np.ndarray, color: Color) -> None:
    """Draw an anti-aliased filled convex polygon."""
    blend(img, polygon_patch(points, img.shape), color)


def fill_circle(img: np.ndarray, cx: float, cy: float, radius: float, color: Color) -> None:
    """Draw an anti-aliased filled disc."""
    blend(img, disc_patch(cx, cy, radius, img.shape), color)


def hline(img: np.ndarray, x0: int, x1: int, y: int, color: Color) -> None:
    """Draw the one-pixel horizontal line from ``x0`` to ``x1`` inclusive at row ``y``."""
    if 0 <= y < img.shape[0]:
        img[y, max(min(x0, x1), 0) : max(x0, x1) + 1] = color


def vline(img: np.ndarray, x: int, y0: int, y1: int, color: Color) -> None:
    """Draw the one-pixel vertical line from ``y0`` to ``y1`` inclusive at column ``x``."""
    if 0 <= x < img.shape[1]:
        img[max(min(y0, y1), 0) : max(y0, y1) + 1, x] = color


def polyline_mask(points: Sequence[Point] | np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Coverage ``[H, W]`` of an anti-aliased one-pixel polyline (Xiaolin Wu's method).

    Each segment is stepped along its major axis and splits one unit of ink between the two
    pixels straddling it, as ``pygame.draw.aalines`` does. Meant for static layers: it loops
    over segments in Python.
    """
    h, w = shape[0], shape[1]
    mask = np.zeros((h, w), dtype=np.float32)
    pts = np.asarray(points, dtype=np.float64)
    for (ax, ay), (bx, by) in itertools.pairwise(pts):
        steep = abs(by - ay) > abs(bx - ax)
        if steep:  # step along y instead; swap roles of the axes
            ax, ay, bx, by = ay, ax, by, bx
        if ax > bx:
            ax, ay, bx, by = bx, by, ax, ay
        major = np.arange(math.ceil(ax), math.floor(bx) + 1)
        if major.size == 0:
            continue
        slope = (by - ay) / (bx - ax) if bx != ax else 0.0
        minor = ay + (major - ax) * slope
        low = np.floor(minor).astype(np.intp)
        frac = (minor - low).astype(np.float32)
        for off, ink in ((0, 1.0 - frac), (1, frac)):
            cols, rows = (low + off, major) if steep else (major, low + off)
            ok = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
            r, c = rows[ok], cols[ok]
            mask[r, c] = np.maximum(mask[r, c], ink[ok])
    return mask


def blend_mask(img: np.ndarray, mask: np.ndarray, color: Color) -> None:
    """Paint ``color`` over the whole image with ``mask`` (``[H, W]`` in [0, 1]) as alpha."""
    blend(img, Patch(0, 0, mask), color)


def ring_sector_coverage(
    u: np.ndarray,
    v: np.ndarray,
    radius: float,
    half_width: float,
    start: float,
    stop: float,
    aa: float,
) -> np.ndarray:
    """Coverage of an arc of a thick ring centred on the origin, in the caller's units.

    ``u, v`` are pixel centres in shape units (broadcastable), ``start``/``stop`` bound the
    angle ``atan2(v, u)`` in radians (``start < stop``, within ``[-pi, pi]`` after wrapping is
    the caller's job) and ``aa`` is the size of one pixel in shape units.
    """
    r = np.sqrt(u * u + v * v)
    cov = np.clip(0.5 - (np.abs(r - radius) - half_width) / aa, 0.0, 1.0)
    ang = np.arctan2(v, u)
    return np.where((ang >= start) & (ang <= stop), cov, 0.0)
