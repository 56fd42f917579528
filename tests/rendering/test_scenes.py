"""Scene functions: sizes, dtypes, fresh frames, odd inputs; the rasterizer's primitives."""

from __future__ import annotations

import math

import numpy as np
import pytest

from palaestra.rendering import raster, scenes

DRAW = {
    "cartpole": (lambda: scenes.render_cartpole((0.1, 0.0, 0.05, 0.0)), (400, 600, 3)),
    "mountain_car": (lambda: scenes.render_mountain_car(-0.5, 0.5), (400, 600, 3)),
    "mountain_car_continuous": (lambda: scenes.render_mountain_car(-0.5, 0.45), (400, 600, 3)),
    "pendulum": (lambda: scenes.render_pendulum(0.3, -1.2), (500, 500, 3)),
    "acrobot": (lambda: scenes.render_acrobot(0.3, -1.2), (500, 500, 3)),
}


@pytest.mark.parametrize("name", sorted(DRAW))
def test_size_dtype_and_fresh_frames(name):
    draw, shape = DRAW[name]
    a, b = draw(), draw()
    assert a.shape == shape and a.dtype == np.uint8 and a.flags.c_contiguous
    assert a.flags.writeable and not np.shares_memory(a, b)
    np.testing.assert_array_equal(a, b)  # deterministic
    a[:] = 0  # a user scribbling on a frame must not leak into the next one
    np.testing.assert_array_equal(draw(), b)


def test_accepts_arrays_lists_and_numpy_scalars():
    state = np.array([0.1, 0.0, 0.05, 0.0], dtype=np.float32)
    np.testing.assert_array_equal(
        scenes.render_cartpole(state), scenes.render_cartpole(list(map(float, state)))
    )
    scenes.render_mountain_car(np.float32(-0.5), 0.45)
    scenes.render_pendulum(np.float64(1.0), np.array(1.5))
    scenes.render_acrobot(np.float32(0.1), np.float32(0.2))


@pytest.mark.parametrize(
    "draw",
    [
        lambda: scenes.render_cartpole((5.0, 0, 3.0, 0)),  # cart far off screen
        lambda: scenes.render_cartpole((-2.4, 0, -math.pi / 2, 0)),
        lambda: scenes.render_mountain_car(-1.2, 0.5),
        lambda: scenes.render_mountain_car(0.6, 0.5),
        lambda: scenes.render_pendulum(100.0, 40.0),  # huge arrow, hangs off every edge
        lambda: scenes.render_pendulum(0.0, 0.001),  # arrow smaller than a pixel
        lambda: scenes.render_acrobot(-100.0, 7.0),
    ],
)
def test_extreme_states_do_not_crash(draw):
    assert draw().dtype == np.uint8


def test_torque_arrow_direction_and_size():
    base = scenes.render_pendulum(math.pi, None)  # rod pointing down, out of the arrow's way
    small, big = scenes.render_pendulum(math.pi, 0.5), scenes.render_pendulum(math.pi, 2.0)
    assert (small != base).any(axis=2).sum() < (big != base).any(axis=2).sum()
    left, right = scenes.render_pendulum(math.pi, -2.0), scenes.render_pendulum(math.pi, 2.0)
    # u > 0 is the mirror image of u < 0 about the vertical axis through the pivot
    mirrored = left[:, ::-1]
    assert np.abs(mirrored[:, :-1].astype(int) - right[:, 1:]).mean() < 0.5


def test_polygon_coverage_is_antialiased_and_winding_free():
    square = [(2.0, 2.0), (7.0, 2.0), (7.0, 7.0), (2.0, 7.0)]
    cw = raster.polygon_patch(square, (10, 10), grow=0.5)
    ccw = raster.polygon_patch(square[::-1], (10, 10), grow=0.5)
    assert cw is not None and ccw is not None
    np.testing.assert_array_equal(cw.cov, ccw.cov)
    full = np.zeros((10, 10), np.float32)
    full[cw.y0 : cw.y0 + cw.cov.shape[0], cw.x0 : cw.x0 + cw.cov.shape[1]] = cw.cov
    assert full[4, 4] == 1.0 and full[2, 4] == 0.5 and full[0, 4] == 0.0  # edge pixel: half


def test_disc_and_blend():
    img = np.zeros((20, 20, 3), np.uint8)
    raster.fill_circle(img, 10, 10, 4, (255, 0, 0))
    assert tuple(img[10, 10]) == (255, 0, 0) and tuple(img[0, 0]) == (0, 0, 0)
    assert 0 < img[13, 13, 0] < 255  # anti-aliased rim (distance 4.24)
    raster.blend(img, raster.Patch(-5, -5, np.full((8, 8), 0.5, np.float32)), (0, 0, 200))
    # a patch hanging off the top-left corner is cropped: only rows/cols 0..2 are painted
    assert tuple(img[2, 2]) == (0, 0, 100) and tuple(img[3, 3]) == (0, 0, 0)


def test_polyline_shares_ink_between_neighbours():
    mask = raster.polyline_mask([(0.0, 2.25), (9.0, 2.25)], (6, 10))
    np.testing.assert_allclose(mask[2, :9], 0.75)
    np.testing.assert_allclose(mask[3, :9], 0.25)
    assert mask[[0, 1, 4, 5]].sum() == 0
