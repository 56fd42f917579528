"""Integer rasterization with the conventions of SDL_gfx and pygame, written in numpy.

CarRacing's observation is a picture: Gymnasium draws it with pygame (``gfxdraw`` polygons
with anti-aliased outlines, ``draw.polygon`` for the car and the dashboard) on a 1000x800
surface and shrinks it with ``transform.smoothscale``. To give the same pixels without pygame,
this module reproduces those algorithms as published (SDL_gfx's scanline fill with 16.16
fixed-point edges, its Wu-style anti-aliased lines with 8-bit weights and Cohen-Sutherland
clipping, pygame's polygon fill, and pygame's area-averaging shrink with 16-bit fixed-point
weights) and is tested against pygame pixel for pixel (tests/envs/box2d/test_gfx.py).

Images are ``[H, W, 3] uint8`` arrays indexed ``img[y, x]``; coordinates are ints (callers
truncate floats toward zero, as pygame does when it hands them to SDL_gfx).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence
from functools import lru_cache
from typing import Any

import numpy as np

Color = tuple[int, int, int]
Ints = Sequence[int] | np.ndarray

_LEFT, _RIGHT, _BOTTOM, _TOP = 1, 2, 4, 8


_PIXEL = np.dtype((np.void, 3))  # one RGB pixel as a single element


def _hspans(img: np.ndarray, y: np.ndarray, xa: np.ndarray, xb: np.ndarray, color: Color) -> None:
    """Fill the horizontal spans ``[min(xa, xb), max(xa, xb)]`` on distinct rows ``y``, clipped.

    Pixels are written as whole 3-byte values through a void view; a few spans go one slice
    each, many as one coverage mask (Python's per-row cost would dominate).
    """
    h, w = img.shape[:2]
    lo, hi = np.minimum(xa, xb), np.maximum(xa, xb)
    keep = (y >= 0) & (y < h) & (hi >= 0) & (lo < w)
    if not keep.any():
        return
    y, lo, hi = y[keep], np.maximum(lo[keep], 0), np.minimum(hi[keep], w - 1)
    pixels = img.view(_PIXEL)[:, :, 0]
    value = np.array(color, dtype=np.uint8).view(_PIXEL)[0]
    # One slice per row costs ~1 us, a mask ~5 ns per pixel: slices win for wide spans.
    if len(y) <= 8 or int((hi - lo).sum()) > 150 * len(y):
        for r, a, b in zip(y.tolist(), lo.tolist(), (hi + 1).tolist()):
            pixels[r, a:b] = value
        return
    y0, y1 = int(y.min()), int(y.max()) + 1
    x0, x1 = int(lo.min()), int(hi.max()) + 1
    cols = np.arange(x0, x1)
    covered = np.zeros((y1 - y0, x1 - x0), dtype=bool)
    covered[y - y0] = (cols >= lo[:, None]) & (cols <= hi[:, None])
    pixels[y0:y1, x0:x1][covered] = value


def fill_polygon(img: np.ndarray, xs: Ints, ys: Ints, color: Color) -> None:
    """SDL_gfx's ``filledPolygonColor`` (opaque colour): scanline fill, 16.16 fixed point.

    On each row from the top vertex to the bottom one, every edge crossing the row (lower
    end excluded, except on the last row) gives an intersection
    ``(65536 * (y - y1)) // (y2 - y1) * (x2 - x1) + 65536 * x1``; the sorted intersections
    pair into spans rounded inwards.
    """
    n = len(xs)
    if n < 3:
        return
    lx, ly = [int(v) for v in xs], [int(v) for v in ys]
    miny, maxy = min(ly), max(ly)
    h = img.shape[0]
    first, last = max(miny, 0), min(maxy, h - 1)  # rows outside the image draw nothing
    if first > last:
        return
    if last - first < 48:  # a small polygon: plain Python beats numpy's per-call cost
        _fill_small(img, lx, ly, first, last, maxy, color)
        return
    vx = np.asarray(lx, dtype=np.int64)
    vy = np.asarray(ly, dtype=np.int64)
    rows = np.arange(first, last + 1, dtype=np.int64)[:, None]  # [R, 1]
    a, b = np.roll(np.arange(n), 1), np.arange(n)  # edge i runs from vertex i-1 to vertex i
    ya, yb, xa, xb = vy[a], vy[b], vx[a], vx[b]
    down = ya < yb
    y1 = np.where(down, ya, yb)
    y2 = np.where(down, yb, ya)
    x1 = np.where(down, xa, xb)
    x2 = np.where(down, xb, xa)
    flat = ya == yb
    hit = ((rows >= y1) & (rows < y2)) | ((rows == maxy) & (rows > y1) & (rows <= y2))
    hit &= ~flat
    span = np.where(flat, 1, y2 - y1)
    ints = (65536 * (rows - y1)) // span * (x2 - x1) + 65536 * x1  # [R, n] (division >= 0)
    ints = np.where(hit, ints, np.iinfo(np.int64).max)
    ints.sort(axis=1)
    count = hit.sum(axis=1)
    for i in range(0, n - 1, 2):
        ok = count >= i + 2
        if not ok.any():
            break
        lo = ints[ok, i] + 1
        lo = (lo >> 16) + ((lo & 32768) >> 15)
        hi = ints[ok, i + 1] - 1
        hi = (hi >> 16) + ((hi & 32768) >> 15)
        _hspans(img, rows[ok, 0], lo, hi, color)


def _clip_line(
    x1: int, y1: int, x2: int, y2: int, w: int, h: int
) -> tuple[int, int, int, int] | None:
    """SDL_gfx's Cohen-Sutherland clipping (float32 slope, truncating), or None if outside."""
    left, right, top, bottom = 0, w - 1, 0, h - 1

    def code(x: int, y: int) -> int:
        c = 0
        if x < left:
            c |= _LEFT
        elif x > right:
            c |= _RIGHT
        if y < top:
            c |= _TOP
        elif y > bottom:
            c |= _BOTTOM
        return c

    while True:
        c1, c2 = code(x1, y1), code(x2, y2)
        if not (c1 | c2):
            return x1, y1, x2, y2
        if c1 & c2:
            return None
        if not c1:  # move the outside point into slot 1
            x1, y1, x2, y2, c1, c2 = x2, y2, x1, y1, c2, c1
        m = np.float32(y2 - y1) / np.float32(x2 - x1) if x2 != x1 else np.float32(1.0)
        if c1 & _LEFT:
            y1 += int(np.float32(left - x1) * m)
            x1 = left
        elif c1 & _RIGHT:
            y1 += int(np.float32(right - x1) * m)
            x1 = right
        elif c1 & _BOTTOM:
            if x2 != x1:
                x1 += int(np.float32(bottom - y1) / m)
            y1 = bottom
        elif c1 & _TOP:
            if x2 != x1:
                x1 += int(np.float32(top - y1) / m)
            y1 = top
        x1, y1 = _int16(x1), _int16(y1)


def _fill_small(
    img: np.ndarray, vx: list[int], vy: list[int], first: int, last: int, maxy: int, color: Color
) -> None:
    """:func:`fill_polygon` row by row in Python (same arithmetic) for a few rows."""
    n = len(vx)
    w = img.shape[1]
    edges = []
    for i in range(n):
        ya, yb = vy[i - 1], vy[i]
        if ya < yb:
            edges.append((ya, yb, vx[i - 1], vx[i]))
        elif ya > yb:
            edges.append((yb, ya, vx[i], vx[i - 1]))
    pixels = img.view(_PIXEL)[:, :, 0]
    value = np.array(color, dtype=np.uint8).view(_PIXEL)[0]
    for y in range(first, last + 1):
        ints = sorted(
            (65536 * (y - y1)) // (y2 - y1) * (x2 - x1) + 65536 * x1
            for y1, y2, x1, x2 in edges
            if (y1 <= y < y2) or (y == maxy and y1 < y <= y2)
        )
        for i in range(0, len(ints) - 1, 2):
            lo, hi = ints[i] + 1, ints[i + 1] - 1
            lo = (lo >> 16) + ((lo & 32768) >> 15)
            hi = (hi >> 16) + ((hi & 32768) >> 15)
            if lo > hi:
                lo, hi = hi, lo
            if hi >= 0 and lo < w:
                pixels[y, max(lo, 0) : min(hi, w - 1) + 1] = value


def _int16(v: int) -> int:
    return (v + 32768) % 65536 - 32768  # Sint16 wrap-around, as the C code stores


def _blend(
    img: np.ndarray, xs: np.ndarray, ys: np.ndarray, color: Color, alpha: np.ndarray
) -> None:
    """SDL_gfx's 32-bit alpha blend: ``d + ((c - d) * a >> 8)`` per channel, clipped."""
    h, w = img.shape[:2]
    ok = (xs >= 0) & (xs < w) & (ys >= 0) & (ys < h)
    xs, ys, alpha = xs[ok], ys[ok], alpha[ok]
    d = img[ys, xs].astype(np.int64)  # [K, 3]
    c = np.asarray(color, dtype=np.int64)
    a = alpha[:, None]
    out = np.where(a == 255, c, d + (((c - d) * a) >> 8))
    img[ys, xs] = (out & 255).astype(np.uint8)


def _put(img: np.ndarray, x: int, y: int, color: Color) -> None:
    if 0 <= x < img.shape[1] and 0 <= y < img.shape[0]:
        img[y, x] = color


def aa_line(img: np.ndarray, x1: int, y1: int, x2: int, y2: int, color: Color) -> None:
    """SDL_gfx's ``_aalineColor`` without its end point (what ``aapolygon`` draws per edge).

    Horizontal and vertical lines are drawn solid; others pair pixels along the major axis
    with weights from a 32-bit error accumulator (top 8 bits), the first pixel solid.
    """
    h, w = img.shape[:2]
    clipped = _clip_line(x1, y1, x2, y2, w, h)
    if clipped is None:
        return
    x1, y1, x2, y2 = clipped
    xx0, yy0, xx1, yy1 = x1, y1, x2, y2
    if yy0 > yy1:
        xx0, yy0, xx1, yy1 = xx1, yy1, xx0, yy0
    dx, dy = xx1 - xx0, yy1 - yy0
    if dx == 0:
        if dy > 0:
            img[max(yy0, 0) : min(yy0 + dy, h - 1) + 1, x1] = color
        else:
            _put(img, x1, y1, color)
        return
    if dy == 0:
        lo, hi = min(xx0, xx0 + dx), max(xx0, xx0 + dx)
        img[y1, max(lo, 0) : min(hi, w - 1) + 1] = color
        return
    xdir = 1 if dx >= 0 else -1
    dx = abs(dx)
    _put(img, x1, y1, color)  # SDL_gfx starts with the (clipped) first point, unweighted
    if max(dx, dy) <= 1:
        return  # no pixels between the ends
    if max(dx, dy) <= 96:  # a short line: the C loop in Python beats numpy's per-call cost
        _aa_small(img, xx0, yy0, dx, dy, xdir, color)
        return
    k = np.arange(1, max(dx, dy), dtype=np.int64)  # the pixels between the ends
    if dy > dx:
        erradj = ((dx << 16) // dy) << 16
        acc = k * erradj
        wgt = (acc >> 24) & 255
        major = yy0 + k
        minor = xx0 + xdir * (acc >> 32)
        xs_a, ys_a, xs_b, ys_b = minor, major, minor + xdir, major
    else:
        erradj = ((dy << 16) // dx) << 16
        acc = k * erradj
        wgt = (acc >> 24) & 255
        major = xx0 + xdir * k
        minor = yy0 + (acc >> 32)
        xs_a, ys_a, xs_b, ys_b = major, minor, major, minor + 1
    _blend(img, xs_a, ys_a, color, (255 * (255 - wgt)) >> 8)
    _blend(img, xs_b, ys_b, color, (255 * wgt) >> 8)


def _aa_small(
    img: np.ndarray, xx0: int, yy0: int, dx: int, dy: int, xdir: int, color: Color
) -> None:
    """The weighted pixels of :func:`aa_line`, one at a time (same arithmetic)."""
    h, w = img.shape[:2]
    r, g, b = color
    buf = img.data.cast("B")  # byte access: ~20x cheaper than numpy item access

    def blend(x: int, y: int, a: int) -> None:
        if 0 <= x < w and 0 <= y < h:
            i = (y * w + x) * 3
            d0, d1, d2 = buf[i], buf[i + 1], buf[i + 2]
            buf[i] = (d0 + (((r - d0) * a) >> 8)) & 255
            buf[i + 1] = (d1 + (((g - d1) * a) >> 8)) & 255
            buf[i + 2] = (d2 + (((b - d2) * a) >> 8)) & 255

    if dy > dx:
        erradj = ((dx << 16) // dy) << 16
        for k in range(1, dy):
            acc = k * erradj
            wgt = (acc >> 24) & 255
            x = xx0 + xdir * (acc >> 32)
            blend(x, yy0 + k, (255 * (255 - wgt)) >> 8)
            blend(x + xdir, yy0 + k, (255 * wgt) >> 8)
    else:
        erradj = ((dy << 16) // dx) << 16
        for k in range(1, dx):
            acc = k * erradj
            wgt = (acc >> 24) & 255
            y = yy0 + (acc >> 32)
            blend(xx0 + xdir * k, y, (255 * (255 - wgt)) >> 8)
            blend(xx0 + xdir * k, y + 1, (255 * wgt) >> 8)


def aa_polygon(img: np.ndarray, xs: Ints, ys: Ints, color: Color) -> None:
    """SDL_gfx's ``aapolygonColor``: :func:`aa_line` along each edge, closing the loop."""
    n = len(xs)
    if n < 3:
        return
    for i in range(n):
        j = (i + 1) % n
        aa_line(img, int(xs[i]), int(ys[i]), int(xs[j]), int(ys[j]), color)


def pg_fill_polygon(img: np.ndarray, xs: Ints, ys: Ints, color: Color) -> None:
    """pygame's ``draw.polygon`` fill (inside the image): per row, floor-divided edge crossings,
    spans between sorted pairs, then the horizontal edges strictly between top and bottom."""
    vx = np.asarray(xs, dtype=np.int64)
    vy = np.asarray(ys, dtype=np.int64)
    n = len(vx)
    miny, maxy = int(vy.min()), int(vy.max())
    if miny == maxy:
        _hspans(img, np.array([miny]), np.array([vx.min()]), np.array([vx.max()]), color)
        return
    h = img.shape[0]
    first, last = max(miny, 0), min(maxy, h - 1)
    if first <= last:
        rows = np.arange(first, last + 1, dtype=np.int64)[:, None]  # [R, 1]
        a, b = np.roll(np.arange(n), 1), np.arange(n)
        ya, yb, xa, xb = vy[a], vy[b], vx[a], vx[b]
        down = ya < yb
        y1, y2 = np.where(down, ya, yb), np.where(down, yb, ya)
        x1, x2 = np.where(down, xa, xb), np.where(down, xb, xa)
        flat = ya == yb
        hit = (((rows >= y1) & (rows < y2)) | ((rows == maxy) & (y2 == maxy))) & ~flat
        ints = ((rows - y1) * (x2 - x1)) // np.where(flat, 1, y2 - y1) + x1
        ints = np.where(hit, ints, np.iinfo(np.int64).max)
        ints.sort(axis=1)
        count = hit.sum(axis=1)
        for i in range(0, n - 1, 2):
            ok = count >= i + 2
            if not ok.any():
                break
            _hspans(img, rows[ok, 0], ints[ok, i], ints[ok, i + 1], color)
    for i in range(n):
        p = i - 1 if i else n - 1
        y = int(vy[i])
        if miny < y < maxy and int(vy[p]) == y:
            _hspans(img, np.array([y]), np.array([vx[i]]), np.array([vx[p]]), color)


_ONE = 0x4000  # pygame's SSE2 smoothscale works in 2.14 fixed point


@lru_cache(maxsize=8)
def _shrink_plan(src: int, dst: int) -> tuple[np.ndarray, ...]:
    """For pygame's area-average shrink of ``src`` samples to ``dst``: per output sample, the
    previous sample's carried-over part (index, weight), the whole samples (as a cumulative
    sum range) and the split sample (index, weight), from its fixed-point walk."""
    space = _ONE * src // dst
    head_idx, head_w, full_lo, full_hi, tail_idx, tail_w = [], [], [], [], [], []
    counter, carry_idx, carry_w, start = space, -1, 0, 0
    for x in range(src):
        if counter > _ONE:
            counter -= _ONE
        else:
            head_idx.append(max(carry_idx, 0))
            head_w.append(carry_w)
            full_lo.append(start)
            full_hi.append(x)
            tail_idx.append(x)
            tail_w.append(counter)
            carry_idx, carry_w = x, _ONE - counter
            start = x + 1
            counter = space - carry_w
    arrays = (head_idx, head_w, full_lo, full_hi, tail_idx, tail_w)
    return tuple(np.asarray(a, dtype=np.int64)[:dst] for a in arrays)


def lanes(packed: np.ndarray) -> np.ndarray:
    """The ``[..., 3] int64`` channels of packed pixels (``uint64``, 16-bit lanes R, G, B, 0:
    sums of up to 257 pixels stay within their lanes)."""
    packed = np.ascontiguousarray(packed)
    return packed.view(np.uint16).reshape(*packed.shape, 4)[..., :3].astype(np.int64)


_BUFFERS = threading.local()  # a running-sum buffer per thread: a fresh 6 MB costs ~1 ms


def _running_buffer(size: int) -> np.ndarray:
    buf = getattr(_BUFFERS, "running", None)
    if buf is None or len(buf) < size:
        buf = np.empty(size, dtype=np.uint64)
        _BUFFERS.running = buf
    return buf[:size]


@lru_cache(maxsize=8)
def shrink_points(src: int, dst: int) -> np.ndarray:
    """Where pygame's area-average shrink of ``src`` samples to ``dst`` reads a row's running
    sum (the sum of the samples before a position): ``[0, hi_0, hi_0 + 1, hi_1, hi_1 + 1,
    ...]``, ``hi_j`` the sample output ``j`` splits with the next one (2 * reached + 1 points,
    see :func:`shrink_from_running`)."""
    _, _, lo, hi, tail_idx, _ = _shrink_plan(src, dst)
    # The plan's walk: output j's whole samples are [hi_{j-1} + 1, hi_j), its split sample is
    # hi_j and its carried-over one hi_{j-1} (weight 0 for j = 0).
    assert np.array_equal(tail_idx, hi) and np.array_equal(lo[1:], hi[:-1] + 1)
    points = np.empty(2 * len(hi) + 1, dtype=np.int64)
    points[0] = 0
    points[1::2], points[2::2] = hi, hi + 1
    return points


_LANES_02 = np.uint64(0x0000FFFF0000FFFF)  # 16-bit lanes 0 and 2 of a packed pixel
_LOW_BYTES = np.uint64(0x000000FF000000FF)
_HIGH_BYTES = np.uint64(0x0000FF000000FF00)
_LOW_BITS = np.uint64(0x0000000100000001)


def _workspace(name: str, shape: tuple[int, ...], dtype: Any) -> np.ndarray:
    """A per-thread scratch array kept between frames: fresh arrays of a few MB each frame
    cost more in page faults (the allocator hands them back to the system) than the
    arithmetic on them."""
    buffers = getattr(_BUFFERS, "scratch", None)
    if buffers is None:
        buffers = _BUFFERS.scratch = {}
    size = math.prod(shape)
    buf = buffers.get((name, np.dtype(dtype)))
    if buf is None or len(buf) < size:
        buf = buffers[name, np.dtype(dtype)] = np.empty(size, dtype=dtype)
    return buf[:size].reshape(shape)


def running_samples(running: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """From rows' running sums at :func:`shrink_points` (``[R, 2 * reached + 1] uint64``,
    wrapping: only differences are used), each output's whole samples' sum and split sample's
    pixel, ``([R, reached], [R, reached])`` packed (scratch arrays: use before the next call)."""
    shape = (running.shape[0], running.shape[1] // 2)
    whole, tail = _workspace("whole", shape, np.uint64), _workspace("tail", shape, np.uint64)
    np.subtract(running[:, 1::2], running[:, 0:-1:2], out=whole)
    np.subtract(running[:, 2::2], running[:, 1::2], out=tail)
    return whole, tail


def shrink_from_running(running: np.ndarray, src: int, dst: int) -> np.ndarray:
    """pygame's SSE2 area-average shrink of rows of ``src`` packed pixels to ``dst``, from each
    row's running sums at :func:`shrink_points` (see :func:`running_samples`)."""
    return shrink_samples(*running_samples(running), src, dst)


def shrink_samples(whole: np.ndarray, tail: np.ndarray, src: int, dst: int) -> np.ndarray:
    """pygame's SSE2 area-average shrink of rows of ``src`` packed pixels to ``dst``, from each
    output's whole samples' sum and split sample's pixel (``[R, reached]`` packed, each sum of
    at most 257 pixels per lane): ``[R, dst]`` packed pixels, lanes 0..255.

    The arithmetic runs on two ``uint64`` words per pixel, (R, B) and (G, 0) in 32-bit lanes,
    where pygame's 16-bit products (a lane times a weight or reciprocal < 2**16) fit."""
    rows = whole.shape[0]
    space = _ONE * src // dst
    recip = np.uint64((0x40000000 // space) & 0xFFFF)
    _, head_w, _, _, _, tail_w = _shrink_plan(src, dst)
    reached = len(head_w)
    tail_w4 = (4 * tail_w).astype(np.uint64)  # <= 2**16: a lane's product < 2**24
    head_w4 = (4 * head_w[1:]).astype(np.uint64)
    shape = (rows, reached)
    out = np.zeros((rows, dst), dtype=np.uint64)  # unreached samples stay zero, as pygame's
    acc, part = _workspace("acc", shape, np.uint64), _workspace("part", shape, np.uint64)
    for shift in (0, 16):  # the (R, B) word, then the (G, 0) one
        np.right_shift(whole, np.uint64(shift), out=acc)
        acc &= _LANES_02
        lanes_t = np.right_shift(tail, np.uint64(shift), out=part)
        lanes_t &= _LANES_02
        # Output j's carried-over sample is output j - 1's split one (none for j = 0).
        carried = _workspace("carried", (rows, reached - 1), np.uint64)
        np.multiply(lanes_t[:, :-1], head_w4, out=carried)
        carried >>= np.uint64(16)
        carried &= _LANES_02
        acc[:, 1:] += carried
        lanes_t *= tail_w4
        lanes_t >>= np.uint64(16)
        lanes_t &= _LANES_02
        acc += lanes_t
        acc &= _LANES_02
        acc *= recip  # < 2**32 per lane: both factors < 2**16
        acc >>= np.uint64(16)
        acc &= _LANES_02
        # Saturate each lane at 255 (pygame packs with unsigned saturation); averages of
        # pixels seldom reach 256, so first check whether any lane does.
        np.bitwise_and(acc, _HIGH_BYTES, out=part)
        if part.any():
            np.right_shift(acc, np.uint64(8), out=part)
            part &= _LOW_BYTES
            part += _LOW_BYTES
            part >>= np.uint64(8)
            part &= _LOW_BITS
            part *= np.uint64(255)
            acc |= part
            acc &= _LOW_BYTES
        if shift:
            acc <<= np.uint64(16)
        out[:, :reached] |= acc
    return out


def _shrink_rows(packed: np.ndarray, dst: int) -> np.ndarray:
    """pygame's SSE2 area-average shrink along axis 1 of ``[R, src]`` packed pixels:
    ``[R, dst]`` packed pixels."""
    rows, src = packed.shape
    # Running sums over the flat image (uint64 arithmetic wraps, but every difference used
    # is a sum of at most 257 pixels per lane: exact).
    running = _running_buffer(rows * src + 1)
    running[0] = 0
    np.cumsum(packed.reshape(-1), out=running[1:])
    base = (np.arange(rows, dtype=np.int64) * src)[:, None]
    return shrink_from_running(running[base + shrink_points(src, dst)], src, dst)


def shrink_columns(rows: np.ndarray, height: int) -> np.ndarray:
    """The second (y) pass of :func:`shrink_packed`, on the first pass's ``[H, width]``
    packed output: ``[height, width, 3] uint8``."""
    out = _shrink_rows(np.ascontiguousarray(rows.T), height)  # [width, height]
    return np.ascontiguousarray(lanes(out.T).astype(np.uint8))


def shrink_packed(packed: np.ndarray, width: int, height: int) -> np.ndarray:
    """pygame's ``transform.smoothscale`` (SSE2) of a packed ``[H, W]`` frame to a smaller
    ``(width, height)``: area averages along x, then along y; ``[height, width, 3] uint8``."""
    check_shrink(packed.shape[1], packed.shape[0], width, height)
    return shrink_columns(_shrink_rows(packed, width), height)


def check_shrink(src_w: int, src_h: int, width: int, height: int) -> None:
    """Raise ``ValueError`` unless ``(width, height)`` is a shrink of ``(src_w, src_h)``: the
    area-average filter here is pygame's for shrinking only."""
    if not (0 < width <= src_w and 0 < height <= src_h):
        raise ValueError(
            f"cannot shrink a {src_w}x{src_h} frame to {width!r}x{height!r}: expected "
            f"1 <= width <= {src_w} and 1 <= height <= {src_h}"
        )


def pack_lanes(img: np.ndarray) -> np.ndarray:
    """``[..., 3] uint8`` pixels packed as ``uint64`` (see :func:`lanes`)."""
    wide = np.zeros((*img.shape[:-1], 4), dtype=np.uint16)
    wide[..., :3] = img
    return wide.view(np.uint64)[..., 0]


def smoothscale_shrink(img: np.ndarray, width: int, height: int) -> np.ndarray:
    """pygame's ``transform.smoothscale`` (its SSE2 filters) to a smaller ``(width, height)``:
    area averages, first along x then along y."""
    return shrink_packed(pack_lanes(img), width, height)
