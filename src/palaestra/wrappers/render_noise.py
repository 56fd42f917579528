"""Wrappers that spoil rendered frames: ``AddWhiteNoise`` and ``ObstructView`` (Gymnasium's).

With :class:`~palaestra.wrappers.AddRenderObservation` they turn a pixel MDP into a POMDP:
noisy pixels, or square patches of noise hiding part of the scene. The noise is drawn from the
env's ``np_random`` in Gymnasium's order (patch centres, then noise, then the pixel mask), so a
seeded env spoils its frames exactly as Gymnasium's wrappers do. Both live in
``palaestra.wrappers.rendering`` too, Gymnasium's module for them.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np

from palaestra import error
from palaestra.core import ActType, Env, ObsType, Wrapper
from palaestra.utils.record_constructor import RecordConstructorArgs

__all__ = ["AddWhiteNoise", "ObstructView"]

# ITU-R 601 luma weights: grey noise is three channels drawn below 255 * weight and summed
# (at most 76 + 149 + 29 = 254, so the sum fits in uint8).
_GREY_WEIGHTS = np.array([0.2989, 0.5870, 0.1140])


def _frame_of(env: Env[Any, Any], who: str) -> np.ndarray:
    """The inner env's frame, or a ``TypeError`` saying what came back instead."""
    frame = env.render()
    if not isinstance(frame, np.ndarray) or frame.ndim != 3:
        raise TypeError(
            f"{who} needs env.render() to return an (H, W, C) image (render_mode='rgb_array'), "
            f"got {type(frame).__name__} with render_mode={env.render_mode!r}"
        )
    return frame


def _noise(rng: np.random.Generator, shape: tuple[int, ...], grayscale: bool) -> np.ndarray:
    """Uniform uint8 noise of ``shape`` (``[H, W, C]``), grey (equal channels) if asked."""
    if grayscale:
        channels = rng.integers((0, 0, 0), 255 * _GREY_WEIGHTS, size=shape, dtype=np.uint8)
        # Summed in uint8 (Gymnasium's sum widens to uint64 and so does its frame).
        grey = channels.sum(axis=-1, keepdims=True, dtype=np.uint8)
        return np.repeat(grey, 3, axis=-1)
    return rng.integers(0, 255, size=shape, dtype=np.uint8)


def _check_grayscale(value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"is_noise_grayscale must be a bool, got {value!r}")
    return bool(value)


def _check_fraction(name: str, value: Any, exc: type[Exception]) -> float:
    """A real number in [0, 1), else ``exc`` (Gymnasium's type) naming the value."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number in [0, 1), got {value!r}")
    number = float(value)
    if not 0 <= number < 1:  # NaN fails here too
        raise exc(f"{name} should be in the interval [0,1). Received {value!r}")
    return number


class AddWhiteNoise(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Each pixel of ``render()``'s frame becomes noise with ``probability_of_noise_per_pixel``.

    A probability outside ``[0, 1)`` raises :class:`palaestra.error.InvalidProbability` (as
    Gymnasium). ``is_noise_grayscale`` draws grey noise.
    """

    def __init__(
        self,
        env: Env[ObsType, ActType],
        probability_of_noise_per_pixel: float,
        is_noise_grayscale: bool = False,
    ) -> None:
        probability = _check_fraction(
            "probability_of_noise_per_pixel",
            probability_of_noise_per_pixel,
            error.InvalidProbability,
        )
        grayscale = _check_grayscale(is_noise_grayscale)
        RecordConstructorArgs.__init__(
            self,
            probability_of_noise_per_pixel=probability_of_noise_per_pixel,
            is_noise_grayscale=is_noise_grayscale,
        )
        Wrapper.__init__(self, env)
        self.probability_of_noise_per_pixel = probability
        self.is_noise_grayscale = grayscale

    def render(self) -> np.ndarray:
        """The inner frame with noisy pixels (drawn from the env's ``np_random``)."""
        frame = _frame_of(self.env, "AddWhiteNoise")
        rng = self.np_random
        noise = _noise(rng, frame.shape, self.is_noise_grayscale)
        mask = rng.random(frame.shape[:2]) < self.probability_of_noise_per_pixel  # [H, W]
        return np.where(mask[..., None], noise, frame)


class ObstructView(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Square patches of noise, ``obstruction_width`` pixels wide, over the rendered frame.

    Patch centres are drawn uniformly, as many as cover ``obstructed_pixels_ratio`` of the
    frame if they did not overlap (Gymnasium's count); patches are cut at the frame's edges.
    """

    def __init__(
        self,
        env: Env[ObsType, ActType],
        obstructed_pixels_ratio: float,
        obstruction_width: int,
        is_noise_grayscale: bool = False,
    ) -> None:
        ratio = _check_fraction("obstructed_pixels_ratio", obstructed_pixels_ratio, ValueError)
        if isinstance(obstruction_width, bool) or not isinstance(
            obstruction_width, (int, np.integer)
        ):
            raise TypeError(
                f"obstruction_width must be an integer number of pixels, got {obstruction_width!r}"
            )
        if obstruction_width < 1:
            raise ValueError(
                "obstruction_width should be larger or equal than 1. "
                f"Received {obstruction_width!r}"
            )
        grayscale = _check_grayscale(is_noise_grayscale)
        RecordConstructorArgs.__init__(
            self,
            obstructed_pixels_ratio=obstructed_pixels_ratio,
            obstruction_width=obstruction_width,
            is_noise_grayscale=is_noise_grayscale,
        )
        Wrapper.__init__(self, env)
        self.obstruction_centers_ratio = ratio / int(obstruction_width) ** 2
        self.obstruction_width = int(obstruction_width)
        self.is_noise_grayscale = grayscale

    def render(self) -> np.ndarray:
        """The inner frame with noise patches (drawn from the env's ``np_random``)."""
        frame = _frame_of(self.env, "ObstructView")
        height, width = frame.shape[:2]
        rng = self.np_random
        count = math.floor(height * width * self.obstruction_centers_ratio)
        rows, cols = np.unravel_index(rng.integers(0, height * width, count), (height, width))
        mask = _patch_mask(rows, cols, self.obstruction_width, height, width)
        noise = _noise(rng, frame.shape, self.is_noise_grayscale)
        return np.where(mask[..., None], noise, frame)


def _patch_mask(
    rows: np.ndarray, cols: np.ndarray, size: int, height: int, width: int
) -> np.ndarray:
    """``[height, width]`` bools: True under any ``size``-wide square centred on a point.

    A square spans ``[r - size // 2, r + size - size // 2)`` (Gymnasium's extent), clipped to
    the frame. Painted at once with a 2-D difference array (+1/-1 at the corners, summed along
    both axes) instead of a Python loop over patches: a small ``size`` gives many thousands.
    """
    low, high = size // 2, size - size // 2
    r0, r1 = np.maximum(rows - low, 0), np.minimum(rows + high, height)
    c0, c1 = np.maximum(cols - low, 0), np.minimum(cols + high, width)
    corners = np.zeros((height + 1, width + 1), dtype=np.int64)
    np.add.at(corners, (r0, c0), 1)
    np.add.at(corners, (r0, c1), -1)
    np.add.at(corners, (r1, c0), -1)
    np.add.at(corners, (r1, c1), 1)
    covered = corners.cumsum(axis=0).cumsum(axis=1)
    return covered[:height, :width] > 0
