"""``ResizeObservation`` and :func:`resize_area`: OpenCV's ``INTER_AREA`` in numpy.

Gymnasium resizes with ``cv2.resize(..., interpolation=cv2.INTER_AREA)``. This module computes
the same bytes without OpenCV, for downscaling (the case of frame preprocessing, e.g. Atari's
210x160 -> 84x84): the same per-axis area weights in float32, summed in the same order, then
rounded half to even. Exact integer factors take OpenCV's block-average path, including its
``(sum + 2) >> 2`` rounding for 2x2 blocks.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from palaestra.core import ActType, Env, ObsType, WrapperObsType
from palaestra.spaces import Box
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.resize_products import IntegerAreaPlan, integer_area_plan, resize_with_plan
from palaestra.wrappers.transform_observation import TransformObservation

__all__ = ["ResizeObservation", "resize_area", "resize_area_f32", "resize_area_terms"]


@lru_cache(maxsize=64)
def _area_weights(src: int, dst: int) -> tuple[np.ndarray, np.ndarray]:
    """``(index, alpha)``, each ``[dst, terms]``: source cells and float32 weights per output
    cell, in OpenCV's order (``computeResizeAreaTab``); padding terms have weight 0."""
    scale = src / dst
    cells: list[list[tuple[int, np.float32]]] = []
    for d in range(dst):
        start = d * scale
        stop = start + scale
        width = min(scale, src - start)
        first, last = math.ceil(start), math.floor(stop)
        last = min(last, src - 1)
        first = min(first, last)
        terms = []
        if first - start > 1e-3:  # partial cell on the left
            terms.append((first - 1, np.float32((first - start) / width)))
        terms += [(s, np.float32(1.0 / width)) for s in range(first, last)]
        if stop - last > 1e-3:  # partial cell on the right
            terms.append((last, np.float32(min(stop - last, 1.0, width) / width)))
        cells.append(terms)
    n_terms = max(len(t) for t in cells)
    index = np.zeros((dst, n_terms), dtype=np.intp)
    alpha = np.zeros((dst, n_terms), dtype=np.float32)
    for d, terms in enumerate(cells):
        for j, (s, a) in enumerate(terms):
            index[d, j], alpha[d, j] = s, a
    return index, alpha


def resize_area(image: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Downscale a ``(H, W, ...)`` uint8 image to ``shape = (h, w)`` like ``cv2.INTER_AREA``.

    >>> img = np.arange(16, dtype=np.uint8).reshape(4, 4)
    >>> resize_area(img, (2, 2))
    array([[ 3,  5],
           [11, 13]], dtype=uint8)
    """
    h, w = image.shape[:2]
    oh, ow = shape
    if not (0 < oh <= h and 0 < ow <= w):
        raise ValueError(f"resize_area only downscales: cannot resize {(h, w)} to {(oh, ow)}")
    trailing = image.shape[2:]
    if h % oh == 0 and w % ow == 0:
        sy, sx = h // oh, w // ow
        blocks = image.astype(np.int32).reshape((oh, sy, ow, sx, *trailing))
        total = blocks.sum(axis=(1, 3))
        if sy == 2 and sx == 2:
            return ((total + 2) >> 2).astype(np.uint8)  # OpenCV's SIMD 2x2 path rounds half up
        mean = total.astype(np.float32) * np.float32(1.0 / (sy * sx))
        return np.clip(np.rint(mean), 0, 255).astype(np.uint8)

    channels = math.prod(trailing)
    # Pixels as rows of interleaved channels, [H, W*C]: gathering columns of a 2-D array is the
    # fast case in numpy, and no transpose is needed.
    src = image.reshape(h, w * channels).astype(np.float32)
    return resize_area_f32(src, oh, ow, channels).reshape(oh, ow, *trailing)


def resize_area_f32(src: np.ndarray, oh: int, ow: int, channels: int = 1) -> np.ndarray:
    """The general (non-integer factor) path of :func:`resize_area` on a ``[H, W*C]`` float32
    image of integer values in [0, 255]: ``[oh, ow*C]`` uint8. Taking float32 lets a caller
    that computes the image in float32 anyway (``WarpFrame``'s grayscale) skip a uint8 round
    trip.

    Where the scale factors are small fractions (Atari's 210x160 -> 84x84 is 2/5 by 21/40),
    two exact integer matrix products and a fix-up of exact ties
    (:mod:`palaestra.wrappers.resize_products`); otherwise :func:`resize_area_terms`.
    """
    plan = _integer_plan(src.shape[0], src.shape[1] // channels, oh, ow, channels)
    if plan is not None:
        return resize_with_plan(src, plan)
    return resize_area_terms(src, oh, ow, channels)


@lru_cache(maxsize=64)
def _integer_plan(h: int, w: int, oh: int, ow: int, channels: int) -> IntegerAreaPlan | None:
    return integer_area_plan(_area_weights(h, oh), _area_weights(w, ow), h, w, channels)


def resize_area_terms(src: np.ndarray, oh: int, ow: int, channels: int = 1) -> np.ndarray:
    """:func:`resize_area_f32` term by term, for any factors: horizontal pass for every source
    row, then the vertical one, each term multiplied and summed in float32 in OpenCV's order
    (``ResizeArea_Invoker``), so every byte matches. All terms of a pass are gathered with one
    fancy index and weighted with one multiply; only the sums are per term, on strided views.
    """
    h = src.shape[0]
    w = src.shape[1] // channels
    (cols, col_weights), (rows, row_weights) = _area_plan(h, w, oh, ow, channels)
    terms = src[:, cols]  # [H, ow*C*T]: every term of every output column
    terms *= col_weights
    terms = terms.reshape(h, ow * channels, -1)
    pass1 = terms[:, :, 0] + terms[:, :, 1] if terms.shape[2] > 1 else terms[:, :, 0].copy()
    for j in range(2, terms.shape[2]):
        pass1 += terms[:, :, j]
    stacked = pass1[rows]  # [oh*T, ow*C]
    stacked *= row_weights
    stacked = stacked.reshape(oh, -1, ow * channels)
    out = stacked[:, 0] + stacked[:, 1] if stacked.shape[1] > 1 else stacked[:, 0].copy()
    for j in range(2, stacked.shape[1]):
        out += stacked[:, j]
    # Area averages of values in [0, 255] stay in range: rounding is the only step left.
    np.rint(out, out=out)
    return out.astype(np.uint8)


@lru_cache(maxsize=64)
def _area_plan(
    h: int, w: int, oh: int, ow: int, channels: int
) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """``(columns, weights)`` of the ``[H, W*C]`` image to gather for every horizontal term,
    laid out ``[output column, term]``, and ``(rows, weights)`` of the horizontal result for the
    vertical terms, laid out ``[output row, term]`` (``_area_weights`` in OpenCV's order)."""
    yi, ya = _area_weights(h, oh)  # [oh, Ty]
    xi, xa = _area_weights(w, ow)  # [ow, Tx]
    lanes = np.arange(channels)
    # [ow, C, Tx]: output column x, channel c, term j reads source column xi[x, j]*C + c.
    cols = xi[:, None, :] * channels + lanes[None, :, None]
    col_weights = np.broadcast_to(xa[:, None, :], cols.shape)
    return (
        (cols.ravel().copy(), col_weights.ravel().copy()),
        (yi.ravel().copy(), ya.reshape(-1, 1).copy()),
    )


class ResizeObservation(
    TransformObservation[WrapperObsType, ActType, ObsType], RecordConstructorArgs
):
    """Downscale ``(H, W[, C])`` uint8 image observations to ``shape = (h, w)`` with area
    averaging; the same bytes as Gymnasium's OpenCV-based wrapper, without OpenCV.

    Upscaling is not supported (Gymnasium's OpenCV path interpolates bilinearly there).
    """

    def __init__(self, env: Env[ObsType, ActType], shape: tuple[int, int]) -> None:
        space = env.observation_space
        if not isinstance(space, Box):
            raise TypeError(
                f"ResizeObservation requires a Box observation space, got {type(space)}"
            )
        if not (np.all(space.low == 0) and np.all(space.high == 255)):
            raise ValueError("ResizeObservation requires observation bounds 0 to 255")
        if space.dtype != np.uint8:
            raise ValueError(
                f"ResizeObservation requires observation dtype uint8, got {space.dtype}"
            )
        if not isinstance(shape, tuple):
            raise TypeError(f"ResizeObservation requires shape to be a tuple, got {type(shape)}")
        if len(shape) != 2:
            raise ValueError(f"ResizeObservation requires shape tuple of length 2, got {shape}")
        if not all(np.issubdtype(type(d), np.integer) for d in shape):
            raise TypeError(
                f"ResizeObservation requires shape elements to be integers, got {shape}"
            )
        if not all(d > 0 for d in shape):
            raise ValueError(
                f"ResizeObservation requires shape elements to be greater than 0, got {shape}"
            )
        if len(space.shape) < 2 or shape[0] > space.shape[0] or shape[1] > space.shape[1]:
            raise ValueError(
                f"ResizeObservation only downscales: cannot resize images of shape {space.shape} "
                f"to {shape}"
            )
        RecordConstructorArgs.__init__(self, shape=shape)
        self.shape = (int(shape[0]), int(shape[1]))
        new_space = Box(0, 255, shape=self.shape + space.shape[2:], dtype=np.uint8)
        target = self.shape

        def func(obs: Any) -> np.ndarray:
            return resize_area(np.asarray(obs), target)

        TransformObservation.__init__(self, env=env, func=func, observation_space=new_space)  # type: ignore[misc]
