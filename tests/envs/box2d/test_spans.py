"""palaestra.rendering.spans (whole frames composed at once) against palaestra.rendering.gfx
(one call at a time, itself checked against pygame in test_gfx.py): the same pixels."""

from __future__ import annotations

import numpy as np
import pytest

from palaestra.rendering import gfx, spans

H, W = 90, 120


def _quads(rng: np.random.Generator, count: int) -> np.ndarray:
    """Overlapping rotated quads of every size, many crossing the image's edges, some
    degenerate (flat or a point): ``[count, 4, 2]`` ints."""
    centre = rng.uniform(-20, [W + 20, H + 20], (count, 1, 2))
    angle = rng.uniform(0, 2 * np.pi, (count, 1))
    radius = rng.choice([0.0, 0.7, 3.0, 15.0, 60.0], (count, 1)) * rng.uniform(0.5, 1.5, (count, 1))
    k = np.arange(4)[None, :] * np.pi / 2
    pts = np.stack([np.cos(angle + k), 0.6 * np.sin(angle + k)], axis=-1) * radius[..., None]
    quads = np.trunc(centre + pts + rng.uniform(-2, 2, (count, 4, 2))).astype(np.int64)
    quads[::7, :, 1] = quads[::7, :1, 1]  # flat ones
    quads[3::11, :, 0] = quads[3::11, :1, 0]  # vertical ones
    return quads


def _unpack(packed: np.ndarray) -> np.ndarray:
    return gfx.lanes(packed).astype(np.uint8)


@pytest.mark.parametrize("seed", range(6))
def test_canvas_equals_drawing_one_call_at_a_time(seed: int) -> None:
    rng = np.random.default_rng(seed)
    quads = _quads(rng, 40)
    colors = [tuple(int(v) for v in rng.integers(0, 256, 3)) for _ in quads]
    car = [_quads(rng, 1)[0] for _ in range(3)]
    ref = np.zeros((H, W, 3), dtype=np.uint8)
    canvas = spans.Canvas(H, W)
    half = len(quads) // 2
    for part in (slice(0, half), slice(half, None)):  # two batches: order across calls
        for q, c in zip(quads[part], colors[part]):
            gfx.aa_polygon(ref, q[:, 0], q[:, 1], c)
            gfx.fill_polygon(ref, q[:, 0], q[:, 1], c)
        canvas.gfx_polygons(quads[part, :, 0], quads[part, :, 1], colors[part])
    for q in car:
        inside = np.clip(q, 0, [W - 1, H - 1])  # pygame's fill is checked inside the image
        gfx.pg_fill_polygon(ref, inside[:, 0], inside[:, 1], (9, 99, 199))
        canvas.pg_polygon(inside[:, 0], inside[:, 1], (9, 99, 199))
    ref = ref[::-1].copy()
    canvas.flip()
    ref[5:17, 30:44] = (255, 255, 255)
    canvas.rect(30, 5, 44, 17, (255, 255, 255))
    got = _unpack(canvas.compose())
    assert np.array_equal(got, ref), np.argwhere((got != ref).any(axis=-1))[:10].tolist()


def test_empty_canvas_is_black_and_shrinks() -> None:
    canvas = spans.Canvas(H, W)
    canvas.gfx_polygons(np.zeros((0, 4)), np.zeros((0, 4)), [])
    frame = canvas.compose()
    assert frame.shape == (H, W) and frame.dtype == np.uint64 and not frame.any()
    assert np.array_equal(spans.shrink_packed(frame, 12, 9), np.zeros((9, 12, 3), np.uint8))


def test_packed_pixels_round_trip() -> None:
    img = np.random.default_rng(7).integers(0, 256, (8, 10, 3), dtype=np.uint8)
    packed = gfx.pack_lanes(img)
    assert packed.dtype == np.uint64 and packed.shape == (8, 10)
    assert np.array_equal(_unpack(packed), img)
    assert int(packed[0, 0]) == spans.pack(img[0, 0])
