"""OpenCV's ``INTER_AREA`` downscale as two small matrix products.

When ``src / dst`` reduces to ``P / Q`` on an axis, every area weight of that axis is a multiple
of ``1 / P`` (a cell is ``P / Q`` source pixels and overlaps them in multiples of ``1 / Q``).
So an output pixel is ``N / D``, with ``D = Py * Px`` and ``N`` a sum of integer weights times
pixel values. The vertical product (integer weights, a ``Qy x Py`` block per period) is exact
in float32 in any summation order while ``255 * D < 2**24``, so BLAS may block, thread or fuse
as it likes; the horizontal one (weights ``k / D``, a ``Px x Qx`` block) lands within a few
float32 roundings of ``N / D``. Atari's 210x160 -> 84x84 is ``(2/5) x (21/40)``: ``D = 200``.

OpenCV sums float32 weights in a fixed order, so its result too is ``N / D`` give or take a few
roundings: each is within ``error_bound`` of ``N / D``, and a plan is only made where that bound
is below ``1 / (4D)``. A pixel of ours farther than ``1 / (2D)`` from a rounding boundary
``k + 1/2`` then has OpenCV's on the same side, and rounds to OpenCV's byte. The others are the
exact ties ``N / D = k + 1/2`` (a few per frame in most Atari games, dozens in some), where
OpenCV's rounding errors decide the side: they are recomputed in OpenCV's own order
(``ResizeArea_Invoker``: each source row's horizontal sum, then the vertical sum, term by term
in float32).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["IntegerAreaPlan", "integer_area_plan", "resize_with_plan"]

WeightTable = tuple[np.ndarray, np.ndarray]  # (index, alpha), each [dst, terms], OpenCV order


@dataclass(frozen=True)
class IntegerAreaPlan:
    """The two block matrices of one ``(h, w, C) -> (oh, ow, C)`` resize, and its tables."""

    rows: np.ndarray  # [Qy, Py] float32 integers: one vertical period
    cols: np.ndarray  # [Px*C, Qx*C] float32, integers / D: one horizontal period, per channel
    tie_margin: float  # 1/2 - 1/(2D): |value - round(value)| above this is recomputed
    # OpenCV's terms per output value (flat [oh*ow*C]), for recomputing ties in its order:
    tie_pixels: np.ndarray  # [oh*ow*C, Ty, Tx] intp: flat source positions
    tie_weights: np.ndarray  # [oh*ow*C, Ty, Tx+1] float32: horizontal weights, vertical last


def _period(src: int, dst: int) -> tuple[int, int]:
    g = math.gcd(src, dst)
    return src // g, dst // g


def _block(table: WeightTable, src: int, dst: int) -> np.ndarray | None:
    """``[Q, P]`` integer weights of one period, or None if a weight is not ``k / P`` or the
    periods differ (float noise in the tables: the caller then keeps the general path)."""
    p, q = _period(src, dst)
    index, alpha = table
    numerators = np.rint(alpha.astype(np.float64) * p)
    # A float32 weight is k/P rounded: a few ulp off at most (error_bound counts 4).
    if np.max(np.abs(alpha * np.float64(p) - numerators)) > 2.0**-22 * p:
        return None
    dense = np.zeros((dst, src), np.float64)
    np.add.at(dense, (np.arange(dst)[:, None], index), numerators)
    block = dense[:q, :p]
    if not np.array_equal(dense, np.kron(np.eye(src // p), block)):
        return None
    if not np.all(block.sum(axis=1) == p):
        return None
    return block.astype(np.float32)


def error_bound(y_terms: int, x_terms: int) -> float:
    """A generous bound on ``|OpenCV's float32 sum - N / D|`` (and on ours) for pixel values up
    to 255: per pass, each product and each addition is off by at most 2**-24 of a value
    <= 255, and the float32 weights by at most 4 ulp in all."""
    return 4 * (y_terms + x_terms + 2) * 255 * 2.0**-24


def integer_area_plan(
    y_table: WeightTable, x_table: WeightTable, h: int, w: int, channels: int
) -> IntegerAreaPlan | None:
    """The plan for area tables ``y_table`` (``h`` -> its rows) and ``x_table``, or None where
    the products would not be exact or ``1 / D`` is not well clear of OpenCV's rounding."""
    oh, ow = len(y_table[0]), len(x_table[0])
    (py, _), (px, _) = _period(h, oh), _period(w, ow)
    d = py * px
    bound = error_bound(y_table[0].shape[1], x_table[0].shape[1])
    # Ours and OpenCV's each within `bound` < 1/(4D) of N/D: they differ by less than 1/(2D).
    if 255 * d >= 2**24 or 4 * bound * d >= 1:
        return None
    rows, cols = _block(y_table, h, oh), _block(x_table, w, ow)
    if rows is None or cols is None:
        return None
    # Interleaved channels: each pixel weight applies to its C lanes alone.
    cols = np.kron(cols.T / d, np.eye(channels)).astype(np.float32)
    (yi, ya), (xi, xa) = y_table, x_table
    lanes = np.arange(channels)
    # [oh, ow, C, Ty, Tx]: row yi[y, i], column xi[x, j], lane c of the [H, W*C] source.
    pixels = (yi[:, None, None, :, None] * w + xi[None, :, None, None, :]) * channels
    pixels = pixels + lanes[None, None, :, None, None]
    ty, tx = ya.shape[1], xa.shape[1]
    weights = np.empty((oh, ow, channels, ty, tx + 1), np.float32)
    weights[..., :tx] = xa[None, :, None, None, :]
    weights[..., tx] = ya[:, None, None, :]
    return IntegerAreaPlan(
        rows=rows,
        cols=cols,
        tie_margin=0.5 - 0.5 / d,
        tie_pixels=pixels.reshape(oh * ow * channels, ty, tx).astype(np.intp),
        tie_weights=weights.reshape(oh * ow * channels, ty, tx + 1),
    )


def resize_with_plan(src: np.ndarray, plan: IntegerAreaPlan) -> np.ndarray:
    """``[H, W*C]`` float32 image of integers in [0, 255] -> ``[oh, ow*C]`` uint8, the bytes of
    OpenCV's ``INTER_AREA``."""
    qy, py = plan.rows.shape
    pxc = plan.cols.shape[0]
    h, wc = src.shape
    vertical = np.matmul(plan.rows, src.reshape(h // py, py, wc))  # [H/Py, Qy, W*C]: exact
    oh = vertical.shape[0] * qy
    value = vertical.reshape(oh * wc // pxc, pxc) @ plan.cols  # [oh * W/Px, Qx*C]: ~N/D
    out = np.rint(value)
    value -= out
    np.abs(value, out=value)
    ties = np.flatnonzero(value > plan.tie_margin)
    if ties.size:
        out.ravel()[ties] = _opencv_order(src, plan, ties)
    return out.astype(np.uint8).reshape(oh, -1)


def _opencv_order(src: np.ndarray, plan: IntegerAreaPlan, flat: np.ndarray) -> np.ndarray:
    """OpenCV's rounded float32 result at the flat output positions ``flat``: each source
    row's horizontal sum, then the vertical sum, term by term (padding terms weigh 0)."""
    terms = src.take(plan.tie_pixels[flat])  # [M, Ty, Tx]
    weights = plan.tie_weights[flat]  # [M, Ty, Tx+1]
    terms *= weights[:, :, :-1]
    row_sums = _sum_in_order(terms)  # [M, Ty]
    row_sums *= weights[:, :, -1]
    return np.rint(_sum_in_order(row_sums))


def _sum_in_order(terms: np.ndarray) -> np.ndarray:
    """``terms[..., 0] + terms[..., 1] + ...``, left to right in float32 (OpenCV's order)."""
    if terms.shape[-1] == 1:
        return terms[..., 0].copy()
    total = terms[..., 0] + terms[..., 1]
    for j in range(2, terms.shape[-1]):
        total += terms[..., j]
    return total
