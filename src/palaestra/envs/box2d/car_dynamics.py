"""The CarRacing car: a Box2D hull on four wheels with a hand-written tyre model.

Gymnasium 1.4.0's model (``car_dynamics.py``, by Oleg Klimov), rebuilt on the same Box2D calls:
each wheel is a body on a revolute joint, steered by a joint motor; the tyre force is the
difference between the wheel's rolling speed and its ground speed, capped by the friction
limit of what the wheel touches (road tiles, else grass). The arithmetic follows Gymnasium's
order and types so that runs match bit for bit.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

from palaestra.envs.box2d._common import import_box2d

SIZE = 0.02
ENGINE_POWER = 100000000 * SIZE * SIZE
WHEEL_MOMENT_OF_INERTIA = 4000 * SIZE * SIZE
FRICTION_LIMIT = 1000000 * SIZE * SIZE  # friction ~ mass ~ size^2
WHEEL_R = 27
WHEEL_W = 14
WHEELPOS = [(-55, +80), (+55, +80), (-55, -82), (+55, -82)]
HULL_POLY1 = [(-60, +130), (+60, +130), (+60, +110), (-60, +110)]
HULL_POLY2 = [(-15, +120), (+15, +120), (+20, +20), (-20, 20)]
HULL_POLY3 = [(+25, +20), (+50, -10), (+50, -40), (+20, -90), (-20, -90), (-50, -40), (-50, -10),
              (-25, +20)]  # fmt: skip
HULL_POLY4 = [(-50, -120), (+50, -120), (+50, -90), (-50, -90)]
WHEEL_COLOR = (0, 0, 0)
WHEEL_WHITE = (77, 77, 77)
MUD_COLOR = (102, 102, 0)
HULL_COLOR = (0.8, 0.0, 0.0)
_TYRE_GAIN = 205000 * SIZE * SIZE  # cuts force oscillations (Gymnasium's "random coefficient")
_BRAKE_FORCE = 15  # radians per second


def _sign(x: float) -> float:
    """``np.sign`` for a float (NaN aside), without numpy's scalar overhead."""
    return 1.0 if x > 0 else (-1.0 if x < 0 else 0.0)


@dataclass
class SkidMark:
    """A skid trace: world points, black on road, mud on grass (decoration only)."""

    color: tuple[int, int, int]
    poly: list[tuple[float, float]]
    grass: bool
    ttl: int = 1


@dataclass
class Wheel:
    """A wheel body and its controls and state (Gymnasium keeps these as body attributes)."""

    body: Any
    joint: Any = None
    gas: float = 0.0
    brake: float = 0.0
    steer: float = 0.0
    phase: float = 0.0  # rotation angle, for the drawing
    omega: float = 0.0  # angular velocity
    skid_start: Any = None
    skid_mark: SkidMark | None = None
    tiles: set[Any] = field(default_factory=set)
    wheel_rad: float = WHEEL_R * SIZE


class Car:
    """The car in ``world`` at ``(init_x, init_y)`` heading ``init_angle``."""

    def __init__(self, world: Any, init_angle: float, init_x: float, init_y: float) -> None:
        b2 = import_box2d().b2
        self.world = world
        self.hull = world.CreateDynamicBody(
            position=(init_x, init_y),
            angle=init_angle,
            fixtures=[
                b2.fixtureDef(
                    shape=b2.polygonShape(vertices=[(x * SIZE, y * SIZE) for x, y in poly]),
                    density=1.0,
                )
                for poly in (HULL_POLY1, HULL_POLY2, HULL_POLY3, HULL_POLY4)
            ],
        )
        self.wheels: list[Wheel] = []
        self.fuel_spent = 0.0
        corners = [(-WHEEL_W, +WHEEL_R), (+WHEEL_W, +WHEEL_R), (+WHEEL_W, -WHEEL_R),
                   (-WHEEL_W, -WHEEL_R)]  # fmt: skip
        for wx, wy in WHEELPOS:
            front_k = 1.0  # Gymnasium's front and rear wheels are the same size
            body = world.CreateDynamicBody(
                # Placed without the hull's rotation, as in Gymnasium (the joint pulls them in).
                position=(init_x + wx * SIZE, init_y + wy * SIZE),
                angle=init_angle,
                fixtures=b2.fixtureDef(
                    shape=b2.polygonShape(
                        vertices=[(x * front_k * SIZE, y * front_k * SIZE) for x, y in corners]
                    ),
                    density=0.1,
                    categoryBits=0x0020,
                    maskBits=0x001,
                    restitution=0.0,
                ),
            )
            wheel = Wheel(body=body, wheel_rad=front_k * WHEEL_R * SIZE)
            joint = b2.revoluteJointDef(
                bodyA=self.hull,
                bodyB=body,
                localAnchorA=(wx * SIZE, wy * SIZE),
                localAnchorB=(0, 0),
                enableMotor=True,
                enableLimit=True,
                maxMotorTorque=180 * 900 * SIZE * SIZE,
                motorSpeed=0,
                lowerAngle=-0.4,
                upperAngle=+0.4,
            )
            wheel.joint = world.CreateJoint(joint)
            body.userData = wheel  # the contact listener finds the wheel from its body
            self.wheels.append(wheel)
        self.skid_marks: deque[SkidMark] = deque(maxlen=30)

    def gas(self, gas: float) -> None:
        """Rear-wheel drive: throttle clipped to [0, 1], raised by at most 0.1 per step."""
        gas = min(max(gas, 0), 1)
        for w in self.wheels[2:4]:
            diff = gas - w.gas
            if diff > 0.1:
                diff = 0.1  # gradually increase, but stop immediately
            w.gas += diff

    def brake(self, b: float) -> None:
        """Brake on all wheels (0.9 or more locks them)."""
        for w in self.wheels:
            w.brake = b

    def steer(self, s: float) -> None:
        """Target steering angle of the front wheels (reached by the joint motors)."""
        self.wheels[0].steer = s
        self.wheels[1].steer = s

    def step(self, dt: float) -> None:
        """Steer, spin and push each wheel for ``dt`` seconds (before the world steps)."""
        for w in self.wheels:
            body, joint = w.body, w.joint
            angle = joint.angle
            joint.motorSpeed = _sign(w.steer - angle) * min(50.0 * abs(w.steer - angle), 3.0)

            grass = not w.tiles
            friction_limit = FRICTION_LIMIT * 0.6  # grass, unless a road tile is touched
            for tile in w.tiles:
                friction_limit = max(friction_limit, FRICTION_LIMIT * tile.road_friction)

            forw = body.GetWorldVector((0, 1))
            side = body.GetWorldVector((1, 0))
            v = body.linearVelocity
            fx, fy, sx, sy, vx, vy = forw.x, forw.y, side.x, side.y, v.x, v.y
            vf = fx * vx + fy * vy  # forward speed
            vs = sx * vx + sy * vy  # side speed

            # Engine power into wheel energy: d(omega) = dt * P / I / omega (+5 avoids /0).
            w.omega += dt * ENGINE_POWER * w.gas / WHEEL_MOMENT_OF_INERTIA / (abs(w.omega) + 5.0)
            self.fuel_spent += dt * ENGINE_POWER * w.gas

            if w.brake >= 0.9:
                w.omega = 0
            elif w.brake > 0:
                direction = -_sign(w.omega)
                val = _BRAKE_FORCE * w.brake
                if abs(val) > abs(w.omega):
                    val = abs(w.omega)  # low speed: stop
                w.omega += direction * val
            w.phase += w.omega * dt

            vr = w.omega * w.wheel_rad  # rolling speed
            f_force = -vf + vr  # towards equal speeds
            p_force = -vs
            f_force *= _TYRE_GAIN
            p_force *= _TYRE_GAIN
            force = math.sqrt(f_force * f_force + p_force * p_force)

            if abs(force) > 2.0 * friction_limit:  # skidding: leave a trace
                mark = w.skid_mark
                if mark and mark.grass == grass and len(mark.poly) < 30:
                    pos = body.position
                    mark.poly.append((pos[0], pos[1]))
                elif w.skid_start is None:
                    w.skid_start = body.position
                else:
                    w.skid_mark = self._skid(w.skid_start, body.position, grass)
                    w.skid_start = None
            else:
                w.skid_start = None
                w.skid_mark = None

            if abs(force) > friction_limit:
                f_force /= force
                p_force /= force
                force = friction_limit
                f_force *= force
                p_force *= force

            w.omega -= dt * f_force * w.wheel_rad / WHEEL_MOMENT_OF_INERTIA
            body.ApplyForceToCenter(
                (p_force * sx + f_force * fx, p_force * sy + f_force * fy), True
            )

    def _skid(self, p1: Any, p2: Any, grass: bool) -> SkidMark:
        mark = SkidMark(
            color=MUD_COLOR if grass else WHEEL_COLOR,
            poly=[(p1[0], p1[1]), (p2[0], p2[1])],
            grass=grass,
        )
        self.skid_marks.append(mark)
        return mark

    def destroy(self) -> None:
        """Remove the hull and wheels from the world (hull first, as Gymnasium)."""
        self.world.DestroyBody(self.hull)
        self.hull = None
        for w in self.wheels:
            self.world.DestroyBody(w.body)
        self.wheels = []
