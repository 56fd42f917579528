"""Whole-frame drawing with the pygame/SDL_gfx rules of :mod:`palaestra.rendering.gfx`, fast.

Drawing polygon by polygon into an image costs a numpy call per row of every polygon, which
made CarRacing's frame ~50 ms. A :class:`Canvas` instead collects what a frame draws, in
order, as data: the horizontal spans of every fill (computed for all polygons in one
vectorised pass) and the pixels of every anti-aliased outline with their weights. The frame
is then resolved once: the spans' ends cut each row into pieces, each piece takes the colour
of the last span covering it, and an outline pixel is kept only where no later fill covers
it, blended in draw order onto what was under it then (the last earlier fill, or an earlier
outline). ``compose`` writes those pieces out as pixels; ``shrink`` goes straight to the
smaller picture (CarRacing's observation) without the full-size frame: the area-average
filter only needs each row's running sums at ~2 points per output column, and those are
sums over the pieces plus the outline pixels' differences. The result is the same pixels as
drawing one call at a time (tests/envs/box2d/test_spans.py) and then shrinking.

Pixels are packed as ``uint64`` with one 16-bit lane per channel (R, G, B, 0), so that a sum
of up to 257 pixels of all three channels is one integer addition (pygame's area-averaging
``smoothscale``, exactly: :func:`gfx.shrink_from_running`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from typing import Any

import numpy as np

from palaestra.rendering import gfx
from palaestra.rendering.gfx import _BOTTOM, _LEFT, _RIGHT, _TOP, _clip_line, lanes, shrink_packed

Color = tuple[int, int, int]
_BIG = np.iinfo(np.int64).max
_SEQ_BITS = 22  # an outline pixel's draw position within a frame, below its pixel index


def pack(color: Sequence[int]) -> int:
    """An RGB colour as a ``uint64`` with 16-bit lanes."""
    return int(color[0]) | int(color[1]) << 16 | int(color[2]) << 32


def _round16(v: np.ndarray) -> np.ndarray:
    return (v >> 16) + ((v & 32768) >> 15)


def sdl_fill_spans(
    xs: np.ndarray, ys: np.ndarray, h: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """SDL_gfx's ``filledPolygonColor`` for ``P`` polygons of ``n`` vertices at once
    (``xs``, ``ys``: ``[P, n]`` ints): ``(polygon, row, x_a, x_b)`` of every span, rows in
    ``[0, h)``, span ends unordered and unclipped (as :func:`gfx.fill_polygon`)."""
    xs = np.asarray(xs, dtype=np.int64)
    ys = np.asarray(ys, dtype=np.int64)
    count, n = xs.shape
    empty = np.zeros(0, dtype=np.int64)
    if count == 0 or n < 3:
        return empty, empty, empty, empty
    miny, maxy = ys.min(axis=1), ys.max(axis=1)
    first, last = np.maximum(miny, 0), np.minimum(maxy, h - 1)
    nrows = np.maximum(last - first + 1, 0)
    total = int(nrows.sum())
    if total == 0:
        return empty, empty, empty, empty
    poly = np.repeat(np.arange(count), nrows)
    starts = np.cumsum(nrows) - nrows
    row = (np.arange(total) - starts[poly] + first[poly])[:, None]  # [N, 1]
    prev = np.roll(np.arange(n), 1)  # edge i runs from vertex i-1 to vertex i
    ya, yb, xa, xb = ys[:, prev], ys, xs[:, prev], xs
    down = ya < yb
    y1, y2 = np.where(down, ya, yb), np.where(down, yb, ya)
    x1, x2 = np.where(down, xa, xb), np.where(down, xb, xa)
    flat = ya == yb
    span = np.where(flat, 1, y2 - y1)
    y1, y2, x1, x2, flat, span = (a[poly] for a in (y1, y2, x1, x2, flat, span))
    top = maxy[poly][:, None]
    hit = ((row >= y1) & (row < y2)) | ((row == top) & (row > y1) & (row <= y2))
    hit &= ~flat
    ints = (65536 * (row - y1)) // span * (x2 - x1) + 65536 * x1
    ints = np.where(hit, ints, _BIG)
    ints.sort(axis=1)
    hits = hit.sum(axis=1)
    out_poly, out_row, out_a, out_b = [], [], [], []
    row = row[:, 0]
    for i in range(0, n - 1, 2):
        ok = hits >= i + 2
        if not ok.any():
            break
        out_poly.append(poly[ok])
        out_row.append(row[ok])
        out_a.append(_round16(ints[ok, i] + 1))
        out_b.append(_round16(ints[ok, i + 1] - 1))
    if not out_poly:
        return empty, empty, empty, empty
    return (np.concatenate(out_poly), np.concatenate(out_row), np.concatenate(out_a),
            np.concatenate(out_b))  # fmt: skip


def pg_fill_spans(
    xs: np.ndarray, ys: np.ndarray, h: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """pygame's ``draw.polygon`` fill for ``P`` polygons of ``n`` vertices at once (``[P, n]``
    ints): ``(polygon, row, x_a, x_b)`` of every span (rows not yet clipped), as
    :func:`gfx.pg_fill_polygon` paints them."""
    xs = np.asarray(xs, dtype=np.int64)
    ys = np.asarray(ys, dtype=np.int64)
    count, n = xs.shape
    miny, maxy = ys.min(axis=1), ys.max(axis=1)
    out = []
    line = np.flatnonzero(miny == maxy)  # a flat polygon: one span, end to end
    out.append((line, miny[line], xs[line].min(axis=1), xs[line].max(axis=1)))
    first, last = np.maximum(miny, 0), np.minimum(maxy, h - 1)
    nrows = np.where(miny == maxy, 0, np.maximum(last - first + 1, 0))
    total = int(nrows.sum())
    prev = np.roll(np.arange(n), 1)
    if total:
        poly = np.repeat(np.arange(count), nrows)
        starts = np.cumsum(nrows) - nrows
        row = (np.arange(total) - starts[poly] + first[poly])[:, None]
        ya, yb, xa, xb = ys[:, prev], ys, xs[:, prev], xs
        down = ya < yb
        y1, y2 = np.where(down, ya, yb), np.where(down, yb, ya)
        x1, x2 = np.where(down, xa, xb), np.where(down, xb, xa)
        flat = ya == yb
        span = np.where(flat, 1, y2 - y1)
        y1, y2, x1, x2, flat, span = (v[poly] for v in (y1, y2, x1, x2, flat, span))
        top = maxy[poly][:, None]
        hit = (((row >= y1) & (row < y2)) | ((row == top) & (y2 == top))) & ~flat
        ints = np.where(hit, ((row - y1) * (x2 - x1)) // span + x1, _BIG)
        ints.sort(axis=1)
        hits = hit.sum(axis=1)
        row = row[:, 0]
        for i in range(0, n - 1, 2):
            ok = hits >= i + 2
            if not ok.any():
                break
            out.append((poly[ok], row[ok], ints[ok, i], ints[ok, i + 1]))
    # Horizontal edges strictly between the top and the bottom.
    flat_edge = (ys == ys[:, prev]) & (ys > miny[:, None]) & (ys < maxy[:, None])
    p_idx, v_idx = np.nonzero(flat_edge)
    out.append((p_idx, ys[p_idx, v_idx], xs[p_idx, v_idx], xs[p_idx, prev[v_idx]]))
    return tuple(np.concatenate([o[i] for o in out]) for i in range(4))  # type: ignore[return-value]


def _codes(x: np.ndarray, y: np.ndarray, w: int, h: int) -> np.ndarray:
    c = np.where(x < 0, _LEFT, np.where(x > w - 1, _RIGHT, 0))
    return c | np.where(y < 0, _TOP, np.where(y > h - 1, _BOTTOM, 0))


def aa_outline_pixels(
    xs: np.ndarray, ys: np.ndarray, h: int, w: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """SDL_gfx's ``aapolygonColor`` for ``P`` polygons of ``n`` vertices (``[P, n]`` ints),
    as data: ``(polygon, x, y, alpha, seq)`` of every pixel it touches inside the image, where
    ``alpha`` is the blend weight (256: the pixel is set to the colour) and ``seq`` orders the
    pixels as SDL_gfx draws them (one polygon after another)."""
    xs = np.asarray(xs, dtype=np.int64)
    ys = np.asarray(ys, dtype=np.int64)
    count, n = xs.shape
    nxt = (np.arange(n) + 1) % n
    ex1, ey1 = xs.ravel(), ys.ravel()
    ex2, ey2 = xs[:, nxt].ravel(), ys[:, nxt].ravel()
    edge = np.arange(count * n)
    c1, c2 = _codes(ex1, ey1, w, h), _codes(ex2, ey2, w, h)
    keep = (c1 & c2) == 0
    inside = (c1 | c2) == 0
    # Edges crossing the image's border: SDL_gfx's clipping, one edge at a time.
    cross = np.flatnonzero(keep & ~inside)
    if len(cross):
        ex1, ey1, ex2, ey2 = ex1.copy(), ey1.copy(), ex2.copy(), ey2.copy()
        for j in cross.tolist():
            clipped = _clip_line(int(ex1[j]), int(ey1[j]), int(ex2[j]), int(ey2[j]), w, h)
            if clipped is None:
                keep[j] = False
            else:
                ex1[j], ey1[j], ex2[j], ey2[j] = clipped
    edge = edge[keep]
    x1, y1, x2, y2 = ex1[keep], ey1[keep], ex2[keep], ey2[keep]
    swap = y1 > y2
    xx0, yy0 = np.where(swap, x2, x1), np.where(swap, y2, y1)
    dx, dy = np.where(swap, x1, x2) - xx0, np.where(swap, y1, y2) - yy0
    parts_e, parts_x, parts_y, parts_a, parts_k = [], [], [], [], []

    def add(e: np.ndarray, x: np.ndarray, y: np.ndarray, a: Any, k: np.ndarray) -> None:
        parts_e.append(e)
        parts_x.append(x)
        parts_y.append(y)
        parts_a.append(np.broadcast_to(np.asarray(a, dtype=np.int64), e.shape))
        parts_k.append(k)

    # Vertical edges: solid from the upper end, dy + 1 pixels (clipped ends are inside).
    vert = dx == 0
    if vert.any():
        length = dy[vert] + 1
        e = np.repeat(np.arange(len(length)), length)
        k = np.arange(int(length.sum())) - np.repeat(np.cumsum(length) - length, length)
        add(edge[vert][e], x1[vert][e], yy0[vert][e] + k, 256, k)
    # Horizontal edges: solid from the left end to the right end.
    hor = (dy == 0) & ~vert
    if hor.any():
        lo = np.minimum(xx0[hor], xx0[hor] + dx[hor])
        length = np.abs(dx[hor]) + 1
        e = np.repeat(np.arange(len(length)), length)
        k = np.arange(int(length.sum())) - np.repeat(np.cumsum(length) - length, length)
        add(edge[hor][e], lo[e] + k, y1[hor][e], 256, k)
    slant = ~vert & ~hor
    if slant.any():
        add(edge[slant], x1[slant], y1[slant], 256, np.zeros(int(slant.sum()), np.int64))
        xdir = np.where(dx[slant] >= 0, 1, -1)
        adx, ady = np.abs(dx[slant]), dy[slant]
        steps = np.maximum(np.maximum(adx, ady) - 1, 0)  # the pixels between the ends
        if steps.any():
            sel = np.repeat(np.arange(len(steps)), steps)
            k = 1 + np.arange(int(steps.sum())) - np.repeat(np.cumsum(steps) - steps, steps)
            steep = (ady > adx)[sel]
            sx_, sy_ = adx[sel], ady[sel]
            major, minor = np.where(steep, sy_, sx_), np.where(steep, sx_, sy_)
            acc = k * (((minor << 16) // major) << 16)
            wgt = (acc >> 24) & 255
            off = acc >> 32
            sx, sy, d = xx0[slant][sel], yy0[slant][sel], xdir[sel]
            ax = np.where(steep, sx + d * off, sx + d * k)
            ay = np.where(steep, sy + k, sy + off)
            bx = np.where(steep, ax + d, ax)
            by = np.where(steep, ay, ay + 1)
            e = edge[slant][sel]
            add(e, ax, ay, (255 * (255 - wgt)) >> 8, 2 * k - 1)
            add(e, bx, by, (255 * wgt) >> 8, 2 * k)
    if not parts_e:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty, empty, empty
    e = np.concatenate(parts_e)
    x, y = np.concatenate(parts_x), np.concatenate(parts_y)
    a, k = np.concatenate(parts_a), np.concatenate(parts_k)
    ok = (x >= 0) & (x < w) & (y >= 0) & (y < h)
    e, x, y, a, k = e[ok], x[ok], y[ok], a[ok], k[ok]
    return e // n, x, y, a, (e << 12) + k


@lru_cache(maxsize=4)
def _queries(h: int, w: int, width: int) -> np.ndarray:
    """The flat positions (row * w + x) where a frame's shrink to ``width`` reads its rows'
    running sums (:func:`gfx.shrink_points` in every row)."""
    query = ((np.arange(h, dtype=np.int64) * w)[:, None] + gfx.shrink_points(w, width)).ravel()
    query.flags.writeable = False
    return query


class Canvas:
    """An ``h x w`` frame drawn as a list of fills and outlines, composed at the end."""

    def __init__(self, h: int, w: int) -> None:
        self.h, self.w = h, w
        self._order = 0  # draw order of the next fill or outline
        self._palette: list[int] = []  # packed colour of each order
        self._spans: list[tuple[np.ndarray, ...]] = []  # (order, row, x_a, x_b)
        self._lines: list[tuple[np.ndarray, ...]] = []  # (order, x, y, alpha, seq)
        self._seq = 0  # outline pixels drawn so far (orders them across calls)
        self._pending: list[tuple[np.ndarray, np.ndarray, int]] = []  # pygame fills to batch

    def _orders(self, colors: Sequence[Sequence[int]]) -> np.ndarray:
        start = self._order
        self._palette.extend(pack(c) for c in colors)
        self._order += len(colors)
        return np.arange(start, self._order)

    def gfx_polygons(self, xs: Any, ys: Any, colors: Sequence[Sequence[int]]) -> None:
        """``gfxdraw.aapolygon`` then ``gfxdraw.filled_polygon`` for each of ``P`` polygons
        (``[P, n]`` int vertices), in order."""
        xs = np.asarray(xs, dtype=np.int64)
        ys = np.asarray(ys, dtype=np.int64)
        if len(xs) == 0:
            return
        both = [c for c in colors for _ in range(2)]
        orders = self._orders(both).reshape(-1, 2)  # outline, then fill, per polygon
        poly, x, y, alpha, seq = aa_outline_pixels(xs, ys, self.h, self.w)
        self._lines.append((orders[poly, 0], x, y, alpha, seq + (self._seq << 12)))
        self._seq += xs.size
        poly, row, xa, xb = sdl_fill_spans(xs, ys, self.h)
        self._spans.append((orders[poly, 1], row, xa, xb))

    def pg_polygon(self, xs: Any, ys: Any, color: Sequence[int]) -> None:
        """``pygame.draw.polygon`` (filled) with int vertices."""
        order = int(self._orders([color])[0])
        self._pending.append((np.asarray(xs, np.int64), np.asarray(ys, np.int64), order))

    def _flush(self) -> None:
        """The pending pygame fills' spans, polygons of one vertex count at a time."""
        by_size: dict[int, list[tuple[np.ndarray, np.ndarray, int]]] = {}
        for item in self._pending:
            by_size.setdefault(len(item[0]), []).append(item)
        self._pending = []
        for items in by_size.values():
            xs = np.stack([i[0] for i in items])
            ys = np.stack([i[1] for i in items])
            orders = np.array([i[2] for i in items])
            poly, row, xa, xb = pg_fill_spans(xs, ys, self.h)
            self._spans.append((orders[poly], row, xa, xb))

    def rect(self, x0: int, y0: int, x1: int, y1: int, color: Sequence[int]) -> None:
        """Fill ``[x0, x1) x [y0, y1)`` (as ``img[y0:y1, x0:x1] = color``)."""
        self.rects([(x0, y0, x1, y1)], color)

    def rects(self, boxes: Sequence[Sequence[int]], color: Sequence[int]) -> None:
        """:meth:`rect` for each ``(x0, y0, x1, y1)`` of ``boxes``, in order, in one colour."""
        box = np.asarray(boxes, dtype=np.int64).reshape(-1, 4)
        box = box[(box[:, 2] > box[:, 0]) & (box[:, 3] > box[:, 1])]
        if not len(box):
            return
        order = self._orders([color] * len(box))
        height = box[:, 3] - box[:, 1]
        which = np.repeat(np.arange(len(box)), height)
        row = np.arange(len(which)) - np.repeat(np.cumsum(height) - height, height)
        self._spans.append((order[which], box[which, 1] + row, box[which, 0],
                            box[which, 2] - 1))  # fmt: skip

    def flip(self) -> None:
        """``pygame.transform.flip(surface, False, True)`` of what is drawn so far."""
        self._flush()
        self._spans = [(o, self.h - 1 - r, a, b) for o, r, a, b in self._spans]
        self._lines = [(o, x, self.h - 1 - y, a, s) for o, x, y, a, s in self._lines]

    def _resolve(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The frame as pieces and outline pixels: ``(starts, colors, pixels, values)``, where
        the pieces of one fill colour start at the flat positions ``starts`` (row * w + x,
        ascending from 0, each running to the next) with packed ``colors``, and the outline
        pixels at the flat positions ``pixels`` (ascending, unique) end up as ``values``."""
        self._flush()
        h, w = self.h, self.w
        palette = np.array([0, *self._palette], dtype=np.uint64)  # order -1: black
        empty = np.zeros(0, dtype=np.int64)
        order, row, xa, xb = (np.concatenate([s[i] for s in self._spans]) if self._spans
                              else empty for i in range(4))  # fmt: skip
        lo, hi = np.minimum(xa, xb), np.maximum(xa, xb)
        ok = (row >= 0) & (row < h) & (hi >= 0) & (lo < w)
        order, row = order[ok], row[ok]
        lo, hi = np.maximum(lo[ok], 0), np.minimum(hi[ok], w - 1)
        # A span over the whole row hides every earlier one there: the row starts from it.
        base = np.full(h, -1, dtype=np.int64)
        whole = (lo == 0) & (hi == w - 1)
        np.maximum.at(base, row[whole], order[whole])
        seen = order > base[row]
        order, row, lo, hi = order[seen], row[seen], lo[seen], hi[seen]
        # The spans' ends cut each row into pieces. Keys number the positions of row r as
        # r * (w + 1) + x, so that a row's end (x = w) is not the next row's start.
        stride = w + 1
        first = np.arange(h, dtype=np.int64) * stride
        keys = np.concatenate([first, row * stride + lo, row * stride + hi + 1])
        keys.sort()
        distinct = np.empty(len(keys), dtype=bool)
        distinct[0] = True
        np.not_equal(keys[1:], keys[:-1], out=distinct[1:])
        keys = keys[distinct & (keys % stride != w)]
        # Each piece takes the colour of the last span covering it (the row's base if none).
        piece_row = keys // stride
        winner = base[piece_row]
        a = np.searchsorted(keys, row * stride + lo)
        count = np.searchsorted(keys, row * stride + hi + 1) - a
        total = int(count.sum())
        covered = np.arange(total) + np.repeat(a - (np.cumsum(count) - count), count)
        np.maximum.at(winner, covered, np.repeat(order, count))
        starts = keys - piece_row  # row * w + x
        colors = palette[winner + 1]
        if not self._lines:
            return starts, colors, empty, np.zeros(0, dtype=np.uint64)
        pixels, values = self._blend_lines(starts, winner, palette)
        return starts, colors, pixels, values

    def compose(self) -> np.ndarray:
        """The frame as packed pixels, ``[h, w] uint64`` (see :func:`pack`)."""
        starts, colors, pixels, values = self._resolve()
        lengths = np.diff(starts, append=self.h * self.w)
        canvas = np.repeat(colors, lengths)
        canvas[pixels] = values
        return canvas.reshape(self.h, self.w)

    def shrink(self, width: int, height: int) -> np.ndarray:
        """``shrink_packed(self.compose(), width, height)`` without the full-size frame: the
        first pass's running sums come from the pieces (a piece adds its colour once per pixel)
        and the outline pixels (each adds its value less the fill under it)."""
        h, w = self.h, self.w
        gfx.check_shrink(w, h, width, height)
        starts, colors, pixels, values = self._resolve()
        lengths = np.diff(starts, append=h * w)
        # Sums of the pieces before each piece (uint64 wraps: only differences are used).
        piece_sums = colors * lengths.astype(np.uint64)
        before = np.cumsum(piece_sums) - piece_sums
        points = gfx.shrink_points(w, width)
        n = len(points)
        query = _queries(h, w, width)
        m = len(query)
        # Scratch arrays kept between frames (see gfx._workspace).
        count = gfx._workspace("count", (m + n,), np.int64)
        index = gfx._workspace("index", (m,), np.int64)
        running = gfx._workspace("running", (m,), np.uint64)
        tmp = gfx._workspace("tmp", (m,), np.uint64)
        # The piece under each query: the pieces starting at or before it, counted by where
        # each piece's start falls among its row's points (no binary search per query).
        count[:] = 0
        row = starts // w
        np.add.at(count, row * n + np.searchsorted(points, starts - row * w), 1)
        np.cumsum(count[:m], out=index)
        index -= 1
        # before + (query - start) * colour, as offset + query * colour per piece.
        offset = before - starts.astype(np.uint64) * colors
        np.take(colors, index, out=running, mode="clip")  # in range: no checks
        running *= query.view(np.uint64)
        running += np.take(offset, index, out=tmp, mode="clip")
        whole, tail = gfx.running_samples(running.reshape(h, n))
        if len(pixels):
            # An outline pixel changes one output's whole samples or its split sample.
            delta = values - colors[np.searchsorted(starts, pixels, side="right") - 1]
            row = pixels // w
            x = pixels - row * w
            split = points[1::2]
            col = np.searchsorted(split, x)
            reached = col < len(split)  # beyond the last split sample: read by no output
            row, x, col, delta = row[reached], x[reached], col[reached], delta[reached]
            is_split = split[col] == x
            np.add.at(tail, (row[is_split], col[is_split]), delta[is_split])
            np.add.at(whole, (row[~is_split], col[~is_split]), delta[~is_split])
        rows = gfx.shrink_samples(whole, tail, w, width)
        return gfx.shrink_columns(rows, height)

    def _blend_lines(
        self, starts: np.ndarray, winner: np.ndarray, palette: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Outline pixels onto the composed fills (pieces at ``starts`` won by the fills
        ``winner``): each kept where no later fill covers it, blended in draw order onto the
        last fill under it (SDL_gfx's ``d + ((c-d)*a >> 8)``); ``(pixels, values)``."""
        order, x, y, alpha, seq = (np.concatenate([p[i] for p in self._lines]) for i in range(5))
        pix = y * self.w + x
        owner = winner[np.searchsorted(starts, pix, side="right") - 1]
        kept = order > owner
        order, pix, alpha, seq, owner = order[kept], pix[kept], alpha[kept], seq[kept], owner[kept]
        if not len(pix):
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.uint64)
        by_pixel = np.argsort((pix << _SEQ_BITS + 12) + seq)
        order, pix, alpha, owner = order[by_pixel], pix[by_pixel], alpha[by_pixel], owner[by_pixel]
        blended = np.empty((len(pix), 3), dtype=np.int64)
        color, under = lanes(palette[order + 1]), lanes(palette[owner + 1])
        first = np.ones(len(pix), dtype=bool)
        first[1:] = pix[1:] != pix[:-1]
        # Pixels drawn over by several outlines: each blend starts from the previous one.
        rank = np.arange(len(pix)) - np.maximum.accumulate(np.where(first, np.arange(len(pix)), 0))
        a = alpha[:, None]
        for r in range(int(rank.max()) + 1):
            at = np.flatnonzero(rank == r)
            d = under[at] if r == 0 else blended[at - 1]
            blended[at] = (d + (((color[at] - d) * a[at]) >> 8)) & 255
        last = np.ones(len(pix), dtype=bool)
        last[:-1] = pix[1:] != pix[:-1]
        out = blended[last].astype(np.uint64)
        return pix[last], out[:, 0] | out[:, 1] << np.uint64(16) | out[:, 2] << np.uint64(32)


__all__ = [
    "Canvas",
    "aa_outline_pixels",
    "pack",
    "pg_fill_spans",
    "sdl_fill_spans",
    "shrink_packed",
]
