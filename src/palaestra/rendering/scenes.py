"""The classic-control pictures, drawn with numpy only (no pygame).

Geometry and colours follow Gymnasium 1.x's ``render()`` of each environment, so frames look
the same: Gymnasium draws in a y-up world and flips the surface vertically at the end; here a
point ``(x, y)`` of that world lands on pixel ``(x, H - 1 - y)`` directly. Like ``gfxdraw``,
polygon and disc positions are truncated to whole pixels, which keeps the pictures
pixel-aligned with Gymnasium's.

Static parts (background, track, hill, flag) are drawn once per scene and copied.

>>> render_cartpole((0.0, 0.0, 0.1, 0.0)).shape
(400, 600, 3)
>>> render_pendulum(0.0, None).dtype
dtype('uint8')
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from palaestra.rendering import raster
from palaestra.rendering.raster import Color

WHITE: Color = (255, 255, 255)
BLACK: Color = (0, 0, 0)

# CartPole (Gymnasium: cartpole.py)
CARTPOLE_SIZE = (400, 600)  # (H, W)
_CP_SCALE = 600 / (2.4 * 2)  # pixels per metre: the track spans +-x_threshold
_CP_POLE_W, _CP_POLE_LEN = 10.0, _CP_SCALE * (2 * 0.5)  # length = 2 * half-length 0.5
_CP_CART_W, _CP_CART_H = 50.0, 30.0
_CP_CART_Y = 100  # y of the track and of the cart's centre
_CP_POLE_COLOR: Color = (202, 152, 101)
_CP_AXLE_COLOR: Color = (129, 132, 203)

# MountainCar (Gymnasium: mountain_car.py, continuous_mountain_car.py)
MOUNTAIN_CAR_SIZE = (400, 600)
_MC_MIN, _MC_MAX = -1.2, 0.6
_MC_SCALE = 600 / (_MC_MAX - _MC_MIN)
_MC_CAR_W, _MC_CAR_H, _MC_CLEARANCE = 40.0, 20.0, 10.0
_MC_WHEEL_COLOR: Color = (128, 128, 128)
_MC_FLAG_COLOR: Color = (204, 204, 0)

# Pendulum (Gymnasium: pendulum.py)
PENDULUM_SIZE = (500, 500)
_PD_SCALE = 500 / (2.2 * 2)
_PD_OFFSET = 500 // 2
_PD_ROD_COLOR: Color = (204, 77, 77)

# Acrobot (Gymnasium: acrobot.py)
ACROBOT_SIZE = (500, 500)
_AC_SCALE = 500 / (2.2 * 2)  # bound = both link lengths (1 m each) + 0.2
_AC_OFFSET = 500 / 2
_AC_LINK_COLOR: Color = (0, 204, 204)
_AC_JOINT_COLOR: Color = (204, 204, 0)


def _to_pixels(points: Sequence[tuple[float, float]] | np.ndarray, height: int) -> np.ndarray:
    """World points (y up) to pixel coordinates (y down), truncated like ``gfxdraw``."""
    pts = np.trunc(np.asarray(points, dtype=np.float64))
    return np.stack([pts[:, 0], height - 1 - pts[:, 1]], axis=1)


def _rotate(points: np.ndarray, angle: float) -> np.ndarray:
    """Rotate ``[N, 2]`` points counter-clockwise by ``angle`` radians (y up)."""
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


def _rect(left: float, right: float, top: float, bottom: float) -> np.ndarray:
    """Corners of an axis-aligned rectangle, in Gymnasium's order."""
    return np.array([(left, bottom), (left, top), (right, top), (right, bottom)], dtype=np.float64)


def _disc(img: np.ndarray, x: float, y: float, radius: float, color: Color) -> None:
    """A disc at a world point, centre and radius truncated to ints as ``gfxdraw`` does."""
    raster.fill_circle(img, int(x), img.shape[0] - 1 - int(y), int(radius), color)


def _frozen(img: np.ndarray) -> np.ndarray:
    img.setflags(write=False)  # cached layers are shared: copy before drawing
    return img


@lru_cache(maxsize=1)
def _cartpole_background() -> np.ndarray:
    h, w = CARTPOLE_SIZE
    img = np.full((h, w, 3), 255, dtype=np.uint8)
    raster.hline(img, 0, w, h - 1 - _CP_CART_Y, BLACK)
    return _frozen(img)


def render_cartpole(state: Sequence[float] | np.ndarray) -> np.ndarray:
    """CartPole frame ``[400, 600, 3] uint8`` for ``state = (x, x_dot, theta, theta_dot)``."""
    h, w = CARTPOLE_SIZE
    img = _cartpole_background().copy()
    x, theta = float(state[0]), float(state[2])
    cart_x = x * _CP_SCALE + w / 2.0
    axle_y = _CP_CART_Y + _CP_CART_H / 4.0

    cart = _rect(-_CP_CART_W / 2, _CP_CART_W / 2, _CP_CART_H / 2, -_CP_CART_H / 2)
    raster.fill_polygon(img, _to_pixels(cart + np.array([cart_x, _CP_CART_Y]), h), BLACK)

    half = _CP_POLE_W / 2
    pole = _rotate(_rect(-half, half, _CP_POLE_LEN - half, -half), -theta) + np.array(
        [cart_x, axle_y]
    )
    raster.fill_polygon(img, _to_pixels(pole, h), _CP_POLE_COLOR)
    _disc(img, cart_x, axle_y, half, _CP_AXLE_COLOR)
    # Gymnasium draws the track last, over the cart and the foot of the pole.
    raster.hline(img, 0, w, h - 1 - _CP_CART_Y, BLACK)
    return img


def _mountain_height(xs: np.ndarray | float) -> np.ndarray | float:
    return np.sin(3 * xs) * 0.45 + 0.55


@lru_cache(maxsize=4)
def _mountain_background() -> np.ndarray:
    h, w = MOUNTAIN_CAR_SIZE
    img = np.full((h, w, 3), 255, dtype=np.uint8)
    xs = np.linspace(_MC_MIN, _MC_MAX, 100)
    hill = np.stack([(xs - _MC_MIN) * _MC_SCALE, h - 1 - _mountain_height(xs) * _MC_SCALE], 1)
    raster.blend_mask(img, raster.polyline_mask(hill, img.shape), BLACK)
    return _frozen(img)


@lru_cache(maxsize=4)
def _mountain_flag(goal_position: float) -> tuple[int, int, int, raster.Patch | None]:
    """Flag pole ``(x, y_top, y_bottom)`` in pixels and the pennant's coverage."""
    h, w = MOUNTAIN_CAR_SIZE
    flag_x = int((goal_position - _MC_MIN) * _MC_SCALE)
    flag_y1 = int(_mountain_height(goal_position) * _MC_SCALE)
    flag_y2 = flag_y1 + 50
    pennant = [(flag_x, flag_y2), (flag_x, flag_y2 - 10), (flag_x + 25, flag_y2 - 5)]
    patch = raster.polygon_patch(_to_pixels(pennant, h), (h, w))
    return flag_x, h - 1 - flag_y2, h - 1 - flag_y1, patch


def render_mountain_car(position: float, goal_position: float) -> np.ndarray:
    """MountainCar frame ``[400, 600, 3] uint8`` (goal 0.5 for v0, 0.45 for the continuous one)."""
    h, _ = MOUNTAIN_CAR_SIZE
    img = _mountain_background().copy()
    pos = float(position)
    tilt = math.cos(3 * pos)
    base = np.array(
        [(pos - _MC_MIN) * _MC_SCALE, _MC_CLEARANCE + _mountain_height(pos) * _MC_SCALE]
    )

    car = _rotate(_rect(-_MC_CAR_W / 2, _MC_CAR_W / 2, _MC_CAR_H, 0), tilt) + base
    raster.fill_polygon(img, _to_pixels(car, h), BLACK)
    wheels = _rotate(np.array([(_MC_CAR_W / 4, 0.0), (-_MC_CAR_W / 4, 0.0)]), tilt) + base
    for wx, wy in wheels:
        _disc(img, wx, wy, _MC_CAR_H / 2.5, _MC_WHEEL_COLOR)

    # The flag is drawn after the car, as in Gymnasium (they overlap at the goal).
    flag_x, top, bottom, pennant = _mountain_flag(float(goal_position))
    raster.vline(img, flag_x, top, bottom, BLACK)
    raster.blend(img, pennant, _MC_FLAG_COLOR)
    return img


@lru_cache(maxsize=1)
def _white_square() -> np.ndarray:
    return _frozen(np.full((*PENDULUM_SIZE, 3), 255, dtype=np.uint8))


# The torque arrow: a ring arc with a notched head, laid out in a 329 x 312 box (the size of
# Gymnasium's clockwise.png, which is stretched to a square of side scale * |u| / 2).
_ARROW_BOX = (329.0, 312.0)
_ARROW_CENTRE, _ARROW_RADIUS, _ARROW_HALF_WIDTH = (174.5, 155.5), 150.5, 5.0
_ARROW_ARC = (math.radians(-91.0), math.radians(180.0))  # clockwise, 12 to 9 o'clock
_ARROW_HEAD = (
    ((21.0, 112.0), (44.0, 168.0), (22.0, 157.0)),
    ((21.0, 112.0), (22.0, 157.0), (0.0, 168.0)),
)


@lru_cache(maxsize=256)
def _torque_arrow(side: int, mirror: bool) -> tuple[raster.Patch, raster.Patch | None]:
    """Coverage of the arrow's ring and head for a square of ``side`` pixels (cached: the
    arrow only changes with the integer ``side``, as Gymnasium's scaled image does)."""
    col0, row0 = _PD_OFFSET - side // 2, _PD_OFFSET - (side - side // 2)
    bw, bh = _ARROW_BOX

    def to_pixels(u: float, v: float) -> tuple[float, float]:
        x = u / bw * side
        return col0 + (side - x if mirror else x) - 0.5, row0 + v / bh * side - 0.5

    cols = np.arange(side, dtype=np.float32)[None, :] + 0.5
    rows = np.arange(side, dtype=np.float32)[:, None] + 0.5
    u = (side - cols if mirror else cols) * (bw / side) - _ARROW_CENTRE[0]
    v = rows * (bh / side) - _ARROW_CENTRE[1]
    ring = raster.ring_sector_coverage(
        u, v, _ARROW_RADIUS, _ARROW_HALF_WIDTH, *_ARROW_ARC, aa=(bw + bh) / 2 / side
    )
    head = [[to_pixels(u_, v_) for u_, v_ in tri] for tri in _ARROW_HEAD]
    return (
        raster.Patch(col0, row0, ring.astype(np.float32)),
        raster.polygons_patch(head, PENDULUM_SIZE, grow=0.5),
    )


def _draw_torque_arrow(img: np.ndarray, last_u: float) -> None:
    """Circular arrow of side ``scale * |u| / 2``; clockwise for u <= 0, mirrored for u > 0."""
    side = int(_PD_SCALE * abs(last_u) / 2)
    if side < 1:
        return
    ring, head = _torque_arrow(side, last_u > 0)
    raster.blend(img, ring, BLACK)
    raster.blend(img, head, BLACK)


def render_pendulum(theta: float, last_u: float | None) -> np.ndarray:
    """Pendulum frame ``[500, 500, 3] uint8``; ``last_u`` (the torque) sizes the arrow."""
    h, _ = PENDULUM_SIZE
    img = _white_square().copy()
    angle = float(theta) + math.pi / 2
    rod_len, rod_w = 1.0 * _PD_SCALE, 0.2 * _PD_SCALE
    rod = _rotate(_rect(0, rod_len, rod_w / 2, -rod_w / 2), angle) + _PD_OFFSET
    raster.fill_polygon(img, _to_pixels(rod, h), _PD_ROD_COLOR)
    _disc(img, _PD_OFFSET, _PD_OFFSET, rod_w / 2, _PD_ROD_COLOR)
    end_x, end_y = _rotate(np.array([[rod_len, 0.0]]), angle)[0] + _PD_OFFSET
    _disc(img, end_x, end_y, rod_w / 2, _PD_ROD_COLOR)
    if last_u is not None:
        _draw_torque_arrow(img, float(last_u))
    _disc(img, _PD_OFFSET, _PD_OFFSET, 0.05 * _PD_SCALE, BLACK)  # the axle, on top
    return img


@lru_cache(maxsize=1)
def _acrobot_background() -> np.ndarray:
    h, w = ACROBOT_SIZE
    img = np.full((h, w, 3), 255, dtype=np.uint8)
    # The "height to reach" line, one link length above the pivot.
    raster.hline(img, 0, w - 1, h - 1 - int(1 * _AC_SCALE + _AC_OFFSET), BLACK)
    return _frozen(img)


def render_acrobot(theta1: float, theta2: float) -> np.ndarray:
    """Acrobot frame ``[500, 500, 3] uint8`` for joint angles ``theta1``, ``theta2``."""
    h, _ = ACROBOT_SIZE
    img = _acrobot_background().copy()
    t1, t2 = float(theta1), float(theta2)
    joints = [(0.0, 0.0), (math.sin(t1) * _AC_SCALE, -math.cos(t1) * _AC_SCALE)]
    angles = [t1 - math.pi / 2, t1 + t2 - math.pi / 2]
    half = 0.1 * _AC_SCALE
    for (jx, jy), angle in zip(joints, angles):
        x, y = jx + _AC_OFFSET, jy + _AC_OFFSET
        link = _rotate(_rect(0, 1.0 * _AC_SCALE, half, -half), angle) + np.array([x, y])
        raster.fill_polygon(img, _to_pixels(link, h), _AC_LINK_COLOR)
        _disc(img, x, y, half, _AC_JOINT_COLOR)
    return img
