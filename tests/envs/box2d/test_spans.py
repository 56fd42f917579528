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


def _scene(seed: int) -> spans.Canvas:
    """A frame drawn as CarRacing draws one: outlined fills in two batches, pygame fills, a
    flip and rectangles on top."""
    rng = np.random.default_rng(seed)
    canvas = spans.Canvas(H, W)
    canvas.gfx_polygons([[0, W - 1, W - 1, 0]], [[0, 0, H - 1, H - 1]], [(102, 204, 102)])
    for _ in range(2):
        quads = _quads(rng, 30)
        colors = [tuple(int(v) for v in rng.integers(0, 256, 3)) for _ in quads]
        canvas.gfx_polygons(quads[..., 0], quads[..., 1], colors)
    for q in _quads(rng, 3):
        inside = np.clip(q, 0, [W - 1, H - 1])
        canvas.pg_polygon(inside[:, 0], inside[:, 1], (255, 255, 255))
    canvas.flip()
    canvas.rect(0, H - 10, W, H, (0, 0, 0))
    canvas.rect(30, 5, 44, 17, (255, 255, 255))
    return canvas


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("size", [(12, 9), (96, 80), (W, H), (1, 1), (W, 7)])
def test_shrink_from_pieces_equals_shrinking_the_composed_frame(
    seed: int, size: tuple[int, int]
) -> None:
    canvas = _scene(seed)
    want = spans.shrink_packed(canvas.compose(), *size)
    got = canvas.shrink(*size)
    assert got.shape == (size[1], size[0], 3) and got.dtype == np.uint8
    assert np.array_equal(got, want), np.argwhere((got != want).any(axis=-1))[:10].tolist()


def test_shrink_without_outlines_or_spans() -> None:
    canvas = spans.Canvas(H, W)
    assert np.array_equal(canvas.shrink(12, 9), np.zeros((9, 12, 3), np.uint8))
    canvas.rect(0, 0, W, H, (255, 255, 255))  # pygame's fixed point: white shrinks to 253
    assert np.array_equal(canvas.shrink(12, 9), np.full((9, 12, 3), 253, np.uint8))
    canvas.rect(10, 20, 50, 30, (7, 8, 9))
    assert np.array_equal(canvas.shrink(96, 80), spans.shrink_packed(canvas.compose(), 96, 80))


@pytest.mark.parametrize("size", [(W + 1, H), (W, H + 1), (0, 9), (12, -1)])
def test_shrink_rejects_sizes_that_are_not_smaller(size: tuple[int, int]) -> None:
    canvas = _scene(0)
    match = rf"cannot shrink a {W}x{H} frame to {size[0]}x{size[1]}: expected 1 <= width"
    with pytest.raises(ValueError, match=match):
        canvas.shrink(*size)
    with pytest.raises(ValueError, match=match):
        spans.shrink_packed(canvas.compose(), *size)


def test_rects_fill_like_slices_and_skip_empty_boxes() -> None:
    boxes = [(0, 0, 5, 5), (3, 2, 10, 4), (7, 7, 7, 9), (12, 1, 10, 3), (W - 4, H - 3, W, H)]
    canvas = spans.Canvas(H, W)
    canvas.rects([], (1, 2, 3))
    canvas.rects(boxes, (200, 100, 50))
    canvas.rect(4, 3, 6, 8, (9, 9, 9))
    ref = np.zeros((H, W, 3), dtype=np.uint8)
    for x0, y0, x1, y1 in boxes:
        ref[y0:y1, x0:x1] = (200, 100, 50)
    ref[3:8, 4:6] = (9, 9, 9)
    assert np.array_equal(_unpack(canvas.compose()), ref)
