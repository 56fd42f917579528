"""palaestra's numpy frames against Gymnasium's pygame frames for the same states.

Measures per frame: ``mad`` = mean absolute difference over all pixels and channels (0-255
scale) and ``frac`` = fraction of pixels whose largest channel difference exceeds 32.
Measured: mad <= 0.062 and frac <= 0.088 % for CartPole, MountainCar and Acrobot; Pendulum
with a torque arrow mad <= 0.20, frac <= 0.23 % (Gymnasium smooth-scales a PNG, we draw the
arrow).

Thresholds: mad < 0.1 and frac < 0.1 %, Pendulum mad < 0.25 and frac < 0.3 %. A wrong colour
for a main part, a mirrored frame, geometry shifted by one pixel, the wrong flag position or a
reversed torque arrow each cost more than that (checked below, so the thresholds bite).
"""

from __future__ import annotations

import numpy as np
import pytest

from palaestra.rendering import scenes

pytest.importorskip("gymnasium")
pytest.importorskip("pygame")

from .gym_reference import (
    ACROBOT_STATES,
    CARTPOLE_STATES,
    MOUNTAIN_POSITIONS,
    PENDULUM_STATES,
    gym_frame,
    similarity,
)

# env id -> (max mean absolute difference, max fraction of pixels off by > 32)
THRESHOLDS = {
    "CartPole-v1": (0.1, 0.001),
    "MountainCar-v0": (0.1, 0.001),
    "MountainCarContinuous-v0": (0.1, 0.001),
    "Acrobot-v1": (0.1, 0.001),
    "Pendulum-v1": (0.25, 0.003),
}


def close_enough(env_id: str, ref: np.ndarray, ours: np.ndarray) -> bool:
    max_mad, max_frac = THRESHOLDS[env_id]
    mad, frac = similarity(ref, ours)
    return mad < max_mad and frac < max_frac


CASES = (
    [("CartPole-v1", s, lambda s=s: scenes.render_cartpole(s)) for s in CARTPOLE_STATES]
    + [
        ("MountainCar-v0", p, lambda p=p: scenes.render_mountain_car(p, 0.5))
        for p in MOUNTAIN_POSITIONS
    ]
    + [("Pendulum-v1", s, lambda s=s: scenes.render_pendulum(*s)) for s in PENDULUM_STATES]
    + [("Acrobot-v1", s, lambda s=s: scenes.render_acrobot(*s)) for s in ACROBOT_STATES]
)


@pytest.mark.parametrize(("env_id", "state", "draw"), CASES, ids=lambda v: str(v)[:24])
def test_frame_matches_gymnasium(env_id, state, draw):
    ref, ours = gym_frame(env_id, state), draw()
    assert ours.shape == ref.shape and ours.dtype == ref.dtype == np.uint8
    mad, frac = similarity(ref, ours)
    assert close_enough(env_id, ref, ours), f"{env_id} {state}: mad={mad:.4f} frac={frac:.4%}"


def test_continuous_mountain_car_flag():
    ref = gym_frame("MountainCarContinuous-v0", -0.3)
    assert close_enough("MountainCarContinuous-v0", ref, scenes.render_mountain_car(-0.3, 0.45))
    # the discrete env's flag (0.5) in the continuous env's picture must be caught
    assert not close_enough("MountainCarContinuous-v0", ref, scenes.render_mountain_car(-0.3, 0.5))


def _recolour(img: np.ndarray, old: tuple[int, int, int], new: tuple[int, int, int]) -> np.ndarray:
    out = img.copy()
    out[(img == old).all(axis=2)] = new
    return out


CORRUPTIONS = {
    "flip-v": lambda f: f[::-1],  # forgot Gymnasium's vertical flip
    "flip-h": lambda f: f[:, ::-1],
    "shift-x": lambda f: np.roll(f, 1, axis=1),  # geometry one pixel off
    "shift-y": lambda f: np.roll(f, 1, axis=0),
}
SAMPLES = {
    "CartPole-v1": ((0.37, 0, 1.2, 0), lambda s: scenes.render_cartpole(s)),
    "MountainCar-v0": (-0.52, lambda p: scenes.render_mountain_car(p, 0.5)),
    "Pendulum-v1": ((0.3, -1.5), lambda s: scenes.render_pendulum(*s)),
    "Acrobot-v1": ((0.6, -1.1), lambda s: scenes.render_acrobot(*s)),
}


@pytest.mark.parametrize("env_id", sorted(SAMPLES))
@pytest.mark.parametrize("corruption", sorted(CORRUPTIONS))
def test_thresholds_catch_geometry_mistakes(env_id, corruption):
    state, draw = SAMPLES[env_id]
    ref = gym_frame(env_id, state)
    assert not close_enough(env_id, ref, CORRUPTIONS[corruption](draw(state)))


@pytest.mark.parametrize(
    ("env_id", "old", "new"),
    [
        ("CartPole-v1", (202, 152, 101), (204, 77, 77)),  # pole
        ("CartPole-v1", (0, 0, 0), (60, 60, 60)),  # cart
        ("Pendulum-v1", (204, 77, 77), (202, 152, 101)),  # rod
        ("Acrobot-v1", (0, 204, 204), (0, 204, 0)),  # links
    ],
    ids=["cart-pole", "cart", "pendulum-rod", "acrobot-links"],
)
def test_thresholds_catch_a_wrong_colour(env_id, old, new):
    # Small parts (CartPole's axle, MountainCar's pennant) are below what the thresholds see.
    state, draw = SAMPLES[env_id]
    ours = draw(state)
    ours[(ours == old).all(axis=2)] = new
    assert not close_enough(env_id, gym_frame(env_id, state), ours)


def test_thresholds_catch_a_reversed_torque_arrow():
    ref = gym_frame("Pendulum-v1", (0.3, -1.5))
    assert not close_enough("Pendulum-v1", ref, scenes.render_pendulum(0.3, 1.5))
