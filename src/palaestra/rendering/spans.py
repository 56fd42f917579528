"""Whole-frame drawing with the pygame/SDL_gfx rules of :mod:`palaestra.rendering.gfx`, fast.

Drawing polygon by polygon into an image costs a numpy call per row of every polygon, which
made CarRacing's frame ~50 ms. A :class:`Canvas` instead collects what a frame draws, in
order, as data: the horizontal spans of every fill (computed for all polygons in one
vectorised pass) and the pixels of every anti-aliased outline with their weights. ``compose``
then decides each pixel once: per row, the spans' ends cut the row into pieces, each piece
takes the colour of the last span covering it, and the row is written with one ``np.repeat``
for the whole image. An outline pixel is kept only where no later fill covers it, and blended
in draw order onto what was under it then (the last earlier fill, or an earlier outline).
The result is the same pixels as drawing one call at a time (tests/envs/box2d/test_gfx.py).

Pixels are packed as ``uint64`` with one 16-bit lane per channel (R, G, B, 0), so that
:func:`shrink_packed` can sum up to 257 pixels of all three channels in one integer addition
(pygame's area-averaging ``smoothscale``, exactly: :func:`gfx.shrink_packed`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

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
        if x1 <= x0 or y1 <= y0:
            return
        row = np.arange(y0, y1, dtype=np.int64)
        order = self._orders([color])
        self._spans.append((np.repeat(order, len(row)), row, np.full_like(row, x0),
                            np.full_like(row, x1 - 1)))  # fmt: skip

    def flip(self) -> None:
        """``pygame.transform.flip(surface, False, True)`` of what is drawn so far."""
        self._flush()
        self._spans = [(o, self.h - 1 - r, a, b) for o, r, a, b in self._spans]
        self._lines = [(o, x, self.h - 1 - y, a, s) for o, x, y, a, s in self._lines]

    def compose(self) -> np.ndarray:
        """The frame as packed pixels, ``[h, w] uint64`` (see :func:`pack`)."""
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
        # Per row, a table of its spans; their ends cut the row into pieces.
        by_row = np.argsort(row, kind="stable")
        order, row, lo, hi = order[by_row], row[by_row], lo[by_row], hi[by_row]
        counts = np.bincount(row, minlength=h)
        width = max(int(counts.max(initial=0)), 1)
        slot = np.arange(len(row)) - (np.cumsum(counts) - counts)[row]
        t_lo = np.full((h, width), w, dtype=np.int64)
        t_hi = np.full((h, width), w - 1, dtype=np.int64)
        t_order = np.full((h, width), -1, dtype=np.int64)
        t_lo[row, slot], t_hi[row, slot], t_order[row, slot] = lo, hi, order
        cuts = np.concatenate(
            [np.zeros((h, 1), np.int64), t_lo, t_hi + 1, np.full((h, 1), w, np.int64)], axis=1
        )
        cuts.sort(axis=1)
        start = cuts[:, :-1, None]  # [h, pieces, 1]
        cover = (t_lo[:, None, :] <= start) & (t_hi[:, None, :] >= start)
        winner = np.where(cover, t_order[:, None, :], base[:, None, None]).max(axis=2)
        lengths = np.diff(cuts, axis=1).ravel()
        canvas = np.repeat(palette[winner.ravel() + 1], lengths)
        if self._lines:
            self._blend_lines(canvas, np.repeat(winner.ravel(), lengths), palette)
        return canvas.reshape(h, w)

    def _blend_lines(self, canvas: np.ndarray, owner: np.ndarray, palette: np.ndarray) -> None:
        """Outline pixels onto the composed fills: each kept where no later fill covers it,
        blended in draw order onto the last fill under it (SDL_gfx's ``d + ((c-d)*a >> 8)``)."""
        order, x, y, alpha, seq = (np.concatenate([p[i] for p in self._lines]) for i in range(5))
        pix = y * self.w + x
        kept = order > owner[pix]
        order, pix, alpha, seq = order[kept], pix[kept], alpha[kept], seq[kept]
        if not len(pix):
            return
        by_pixel = np.argsort((pix << _SEQ_BITS + 12) + seq)
        order, pix, alpha = order[by_pixel], pix[by_pixel], alpha[by_pixel]
        blended = np.empty((len(pix), 3), dtype=np.int64)
        color, under = lanes(palette[order + 1]), lanes(canvas[pix])
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
        canvas[pix[last]] = out[:, 0] | out[:, 1] << np.uint64(16) | out[:, 2] << np.uint64(32)


__all__ = [
    "Canvas",
    "aa_outline_pixels",
    "pack",
    "pg_fill_spans",
    "sdl_fill_spans",
    "shrink_packed",
]
