"""BipedalWalker-v3: walk a two-legged robot to the end of a rough (or ``hardcore``) terrain.

Gymnasium 1.4.0's dynamics (Oleg Klimov's walker) on the same ``box2d`` package. Unlike
LunarLander, Gymnasium keeps one Box2D world for the env's whole life and destroys the bodies
of the last episode at reset; the order of those destructions decides which broad-phase proxy
ids the next episode's bodies get, and so the order in which contacts are created and solved.
This env keeps one world too and destroys and creates the same bodies in the same order, and
draws from ``np_random`` in Gymnasium's order (terrain, clouds, the hull's push), so the same
seed and actions give bit-identical observations and rewards.

The reward is Gymnasium's: 130/SCALE per metre of forward progress, minus 5 per radian of hull
tilt (as a shaping difference), minus 0.028 per unit of motor torque; -100 if the hull touches
the ground or the walker leaves on the left. As in Gymnasium, the torque cost is computed in the
action's own float type, so a float32 action gives a float32-rounded reward (returned as float).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.box2d._common import ReplayCopies, box_action, check_bool, import_box2d
from palaestra.envs.classic_control._common import RENDER_MODES, ClassicControlEnv
from palaestra.rendering import box2d_scenes as scenes
from palaestra.spaces import Box

# Gymnasium's constants (bipedal_walker.py): pixels unless divided by SCALE.
FPS = 50
SCALE = 30.0
MOTORS_TORQUE = 80
SPEED_HIP = 4
SPEED_KNEE = 6
LIDAR_RANGE = 160 / SCALE
INITIAL_RANDOM = 5
HULL_POLY = [(-30, +9), (+6, +9), (+34, +1), (+34, -8), (-30, -8)]
LEG_DOWN = -8 / SCALE
LEG_W, LEG_H = 8 / SCALE, 34 / SCALE
VIEWPORT_W = 600
VIEWPORT_H = 400
TERRAIN_STEP = 14 / SCALE
TERRAIN_LENGTH = 200  # in steps
TERRAIN_HEIGHT = VIEWPORT_H / SCALE / 4
TERRAIN_GRASS = 10  # longest stretch of grass between obstacles, in steps
TERRAIN_STARTPAD = 20  # flat steps at the start
FRICTION = 2.5
GRASS, STUMP, STAIRS, PIT, _STATES = range(5)

_FINISH_X = (TERRAIN_LENGTH - TERRAIN_GRASS) * TERRAIN_STEP
_TORQUE_COST = 0.00035 * MOTORS_TORQUE  # Gymnasium's product, folded in the same order
# Lidar: 10 rays fanning from straight down to 1.5 rad forward.
_LIDAR_DX = [math.sin(1.5 * i / 10.0) * LIDAR_RANGE for i in range(10)]
_LIDAR_DY = [math.cos(1.5 * i / 10.0) * LIDAR_RANGE for i in range(10)]
_HULL, _CONTACT_LEGS = "hull", (0, 1)  # userData tags (the lower legs report ground contact)
_WALKER = "walker"  # the userData of the walker's fixtures (the terrain's have none)

# Colours (fill, outline), as Gymnasium draws them.
HULL_COLOR = ((127, 51, 229), (76, 76, 127))
LEG_COLORS = {
    i: ((153 - i * 25, 76 - i * 25, 127 - i * 25), (102 - i * 25, 51 - i * 25, 76 - i * 25))
    for i in (-1, 1)
}


@lru_cache(maxsize=1)
def _box2d_helpers() -> tuple[Any, type, type]:
    """``(fixture defs, ContactDetector, LidarCallback)``, built on first use (needs Box2D)."""
    b2 = import_box2d().b2
    fixtures = {
        "hull": b2.fixtureDef(
            shape=b2.polygonShape(vertices=[(x / SCALE, y / SCALE) for x, y in HULL_POLY]),
            density=5.0,
            friction=0.1,
            categoryBits=0x0020,
            maskBits=0x001,  # bodies collide with the ground only
            restitution=0.0,
            userData=_WALKER,
        ),
        "leg": b2.fixtureDef(
            shape=b2.polygonShape(box=(LEG_W / 2, LEG_H / 2)),
            density=1.0,
            restitution=0.0,
            userData=_WALKER,
            categoryBits=0x0020,
            maskBits=0x001,
        ),
        "lower": b2.fixtureDef(
            shape=b2.polygonShape(box=(0.8 * LEG_W / 2, LEG_H / 2)),
            density=1.0,
            restitution=0.0,
            userData=_WALKER,
            categoryBits=0x0020,
            maskBits=0x001,
        ),
    }

    class ContactDetector(b2.contactListener):  # type: ignore[name-defined]
        def __init__(self, env: BipedalWalker) -> None:
            super().__init__()
            self.env = env

        def BeginContact(self, contact: Any) -> None:
            for tag in (contact.fixtureA.body.userData, contact.fixtureB.body.userData):
                if tag == _HULL:
                    self.env.game_over = True
                elif tag in _CONTACT_LEGS:
                    self.env.leg_contact[tag] = True

        def EndContact(self, contact: Any) -> None:
            for tag in (contact.fixtureA.body.userData, contact.fixtureB.body.userData):
                if tag in _CONTACT_LEGS:
                    self.env.leg_contact[tag] = False

    class LidarCallback(b2.rayCastCallback):  # type: ignore[name-defined]
        """Keeps the nearest ground hit (``fraction`` of the ray, 1.0 when nothing)."""

        fraction = 1.0
        p1: Any = None
        p2: Any = None

        def ReportFixture(self, fixture: Any, point: Any, normal: Any, fraction: float) -> float:
            # Gymnasium ignores fixtures without the ground's category bit: in this world
            # those are the walker's own, the only ones with userData (a read 6x cheaper than
            # filterData's, and this runs ~20 times a step).
            if fixture.userData is not None:
                return -1  # not ground: ignore and go on
            self.p2 = point
            self.fraction = fraction
            return fraction  # clip the ray here: later hits are nearer

    return fixtures, ContactDetector, LidarCallback


def _sign(x: float) -> float:
    """``np.sign`` of a float, for Gymnasium's terrain drift."""
    return 1.0 if x > 0 else (-1.0 if x < 0 else 0.0)


class BipedalWalker(ReplayCopies, ClassicControlEnv):
    """The walker; actions are 4 motor torques in [-1, 1] (hip, knee, hip, knee)."""

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": FPS}

    def __init__(self, render_mode: str | None = None, hardcore: bool = False) -> None:
        self._record_init(render_mode=render_mode, hardcore=hardcore)
        self.hardcore = check_bool("hardcore", hardcore)
        self._init_render(render_mode)
        b2 = import_box2d().b2
        self._b2 = b2
        self._fixtures, self._listener_cls, self._lidar_cls = _box2d_helpers()
        self.world = b2.world()  # one world for the env's life, as Gymnasium
        self.terrain: list[Any] = []
        self.hull: Any = None
        self.legs: list[Any] = []
        self.joints: list[Any] = []
        self.lidar: list[Any] = []
        self.leg_contact = [False, False]
        self.game_over = False
        self.prev_shaping: float | None = None
        self.scroll = 0.0
        self.lidar_render = 0
        self._strip: np.ndarray | None = None
        # Reused shape holders: terrain pieces are made by setting their vertices.
        self._fd_polygon = b2.fixtureDef(
            shape=b2.polygonShape(vertices=[(0, 0), (1, 0), (1, -1), (0, -1)]),
            friction=FRICTION,
        )
        self._static_body = b2.bodyDef(type=b2.staticBody)
        self._fd_edge = b2.fixtureDef(
            shape=b2.edgeShape(vertices=[(0, 0), (1, 1)]), friction=FRICTION, categoryBits=0x0001
        )
        pi = math.pi
        joint_low = [-pi, -5.0, -pi, -5.0, -0.0]  # angle, speed, angle, speed, contact
        joint_high = [pi, 5.0, pi, 5.0, 5.0]
        low = np.array([-pi, -5.0, -5.0, -5.0, *joint_low, *joint_low, *[-1.0] * 10], np.float32)
        high = np.array([pi, 5.0, 5.0, 5.0, *joint_high, *joint_high, *[1.0] * 10], np.float32)
        self.observation_space = Box(low, high)
        self.action_space = Box(
            np.array([-1, -1, -1, -1], np.float32), np.array([1, 1, 1, 1], np.float32)
        )

    # -- episode -----------------------------------------------------------------------------

    def _destroy(self) -> None:
        """Destroy last episode's bodies in Gymnasium's order (it decides the next proxy ids)."""
        if not self.terrain:
            return
        self.world.contactListener = None
        for body in self.terrain:
            self.world.DestroyBody(body)
        self.terrain = []
        self.world.DestroyBody(self.hull)
        self.hull = None
        for leg in self.legs:
            self.world.DestroyBody(leg)
        self.legs = []
        self.joints = []

    def _static(self, fixture_def: Any) -> None:
        """A static body with one fixture: what Gymnasium's ``CreateStaticBody(fixtures=...)``
        makes, without building its body definition in Python each time (~7 us, 200 times
        a reset)."""
        body = self.world.CreateBody(self._static_body)
        body.CreateFixture(fixture_def)
        self.terrain.append(body)

    def _generate_terrain(self) -> None:
        """Gymnasium's terrain walk: grass drifting around TERRAIN_HEIGHT, and in hardcore mode
        stumps, stairs and pits after each stretch of grass."""
        rng, ts = self._own_random(), TERRAIN_STEP
        state, velocity, y = GRASS, 0.0, TERRAIN_HEIGHT
        counter: Any = TERRAIN_STARTPAD
        oneshot = False
        self.terrain, self.terrain_x, self.terrain_y = [], [], []
        self.obstacles: list[list[tuple[float, float]]] = []
        stair_steps: Any = 0
        stair_width: Any = 0
        stair_height = 0
        original_y = 0.0
        for i in range(TERRAIN_LENGTH):
            x = i * ts
            self.terrain_x.append(x)
            if state == GRASS and not oneshot:
                velocity = 0.8 * velocity + 0.01 * _sign(TERRAIN_HEIGHT - y)
                if i > TERRAIN_STARTPAD:
                    velocity += rng.uniform(-1, 1) / SCALE
                y += velocity
            elif state == PIT and oneshot:
                counter = rng.integers(3, 5)
                poly = [(x, y), (x + ts, y), (x + ts, y - 4 * ts), (x, y - 4 * ts)]
                self._obstacle(poly)
                self._obstacle([(p[0] + ts * counter, p[1]) for p in poly])
                counter += 2
                original_y = y
            elif state == PIT and not oneshot:
                y = original_y
                if counter > 1:
                    y -= 4 * ts
            elif state == STUMP and oneshot:
                counter = rng.integers(1, 3)
                side = counter * ts
                self._obstacle([(x, y), (x + side, y), (x + side, y + side), (x, y + side)])
            elif state == STAIRS and oneshot:
                stair_height = +1 if rng.random() > 0.5 else -1
                stair_width = rng.integers(4, 5)
                stair_steps = rng.integers(3, 5)
                original_y = y
                for s in range(stair_steps):
                    x0, x1 = x + (s * stair_width) * ts, x + ((1 + s) * stair_width) * ts
                    top, bottom = y + (s * stair_height) * ts, y + (-1 + s * stair_height) * ts
                    self._obstacle([(x0, top), (x1, top), (x1, bottom), (x0, bottom)])
                counter = stair_steps * stair_width
            elif state == STAIRS and not oneshot:
                s = stair_steps * stair_width - counter - stair_height
                n = s / stair_width
                y = original_y + (n * stair_height) * ts
            oneshot = False
            self.terrain_y.append(y)
            counter -= 1
            if counter == 0:
                counter = rng.integers(TERRAIN_GRASS // 2, TERRAIN_GRASS)
                if state == GRASS and self.hardcore:
                    state = int(rng.integers(1, _STATES))
                else:
                    state = GRASS
                oneshot = True

        # An edge's two vertices set directly: its vertices setter (Python, ~2 us) would also
        # clear hasVertex0/hasVertex3, which stay False on this shape.
        edge = self._fd_edge.shape
        xs, ys = self.terrain_x, self.terrain_y
        for i in range(TERRAIN_LENGTH - 1):
            edge.vertex1 = (xs[i], ys[i])
            edge.vertex2 = (xs[i + 1], ys[i + 1])
            self._static(self._fd_edge)
        self.terrain.reverse()  # Gymnasium's order, which _destroy follows

    def _obstacle(self, poly: list[tuple[float, float]]) -> None:
        self._fd_polygon.shape.vertices = poly
        self._static(self._fd_polygon)
        self.obstacles.append(poly)

    def _generate_clouds(self) -> None:
        """Ten five-sided clouds (decoration, but they draw from np_random: kept for parity)."""
        rng, ts = self._own_random(), TERRAIN_STEP
        self.cloud_poly = []
        for _ in range(TERRAIN_LENGTH // 20):
            x = rng.uniform(0, TERRAIN_LENGTH) * ts
            y = VIEWPORT_H / SCALE * 3 / 4
            poly = []
            for a in range(5):
                px = x + 15 * ts * math.sin(3.14 * 2 * a / 5) + rng.uniform(0, 5 * ts)
                py = y + 5 * ts * math.cos(3.14 * 2 * a / 5) + rng.uniform(0, 5 * ts)
                poly.append((px, py))
            xs = [p[0] for p in poly]
            self.cloud_poly.append((poly, min(xs), max(xs)))

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """New terrain and walker; the first observation is that of a zero-torque step."""
        super().reset(seed=seed)
        fresh_world = self._start_reset(seed)
        b2, fixtures = self._b2, self._fixtures
        self._destroy()
        if fresh_world:  # the history a copy replays restarts here (ReplayCopies)
            self.world = b2.world()
        world = self.world
        self._listener = self._listener_cls(self)
        world.contactListener = self._listener
        self.game_over = False
        self.prev_shaping = None
        self.scroll = 0.0
        self.lidar_render = 0
        self.leg_contact = [False, False]
        self._strip = None

        self._generate_terrain()
        self._generate_clouds()

        init_x = TERRAIN_STEP * TERRAIN_STARTPAD / 2
        init_y = TERRAIN_HEIGHT + 2 * LEG_H
        self.hull = hull = world.CreateDynamicBody(
            position=(init_x, init_y), fixtures=fixtures["hull"]
        )
        hull.userData = _HULL
        push = self._own_random().uniform(-INITIAL_RANDOM, INITIAL_RANDOM)
        hull.ApplyForceToCenter((push, 0), True)

        self.legs, self.joints = [], []
        for i in (-1, +1):
            leg = world.CreateDynamicBody(
                position=(init_x, init_y - LEG_H / 2 - LEG_DOWN),
                angle=(i * 0.05),
                fixtures=fixtures["leg"],
            )
            hip = b2.revoluteJointDef(
                bodyA=hull,
                bodyB=leg,
                localAnchorA=(0, LEG_DOWN),
                localAnchorB=(0, LEG_H / 2),
                enableMotor=True,
                enableLimit=True,
                maxMotorTorque=MOTORS_TORQUE,
                motorSpeed=i,
                lowerAngle=-0.8,
                upperAngle=1.1,
            )
            self.legs.append(leg)
            self.joints.append(world.CreateJoint(hip))
            lower = world.CreateDynamicBody(
                position=(init_x, init_y - LEG_H * 3 / 2 - LEG_DOWN),
                angle=(i * 0.05),
                fixtures=fixtures["lower"],
            )
            lower.userData = _CONTACT_LEGS[(i + 1) // 2]
            knee = b2.revoluteJointDef(
                bodyA=leg,
                bodyB=lower,
                localAnchorA=(0, -LEG_H / 2),
                localAnchorB=(0, LEG_H / 2),
                enableMotor=True,
                enableLimit=True,
                maxMotorTorque=MOTORS_TORQUE,
                motorSpeed=1,
                lowerAngle=-1.6,
                upperAngle=-0.1,
            )
            self.legs.append(lower)
            self.joints.append(world.CreateJoint(knee))
        self.drawlist = self.terrain + self.legs + [hull]
        self.lidar = [self._lidar_cls() for _ in range(10)]

        if self.render_mode == "human":
            self.render()
        obs = self.step(np.array([0, 0, 0, 0]))[0]
        self._record_reset(options)
        return obs, {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Set the four motors, advance 1/50 s, cast the lidar, observe and score."""
        hull = self.hull
        if hull is None:
            raise error.ResetNeeded("Call reset before using step method.")
        self._start_step()
        a = box_action(action, self.action_space, keep_float_dtype=True)
        # Each motor turns at full speed towards the action's sign with torque |a| (clipped).
        # np.minimum(|a|, 1) is np.clip(|a|, 0, 1) for finite |a|, at a fifth of its cost.
        effort = np.minimum(np.abs(a), 1.0)  # [4], in the action's float type
        speeds = (SPEED_HIP, SPEED_KNEE, SPEED_HIP, SPEED_KNEE)
        for joint, speed, ai, ei in zip(self.joints, speeds, a.tolist(), effort.tolist()):
            joint.motorSpeed = float(speed * _sign(ai))
            joint.maxMotorTorque = float(MOTORS_TORQUE * ei)

        self.world.Step(1.0 / FPS, 6 * 30, 2 * 30)

        pos, vel = hull.position, hull.linearVelocity
        px, py = pos.x, pos.y
        # The start as a tuple of the same floats: a b2Vec2 argument costs a Python __len__.
        p1, ray_cast = (px, py), self.world.RayCast
        for ray, dx, dy in zip(self.lidar, _LIDAR_DX, _LIDAR_DY):
            ray.fraction = 1.0
            ray.p1 = p1
            ray.p2 = p2 = (px + dx, py - dy)
            ray_cast(ray, p1, p2)

        j0, j1, j2, j3 = self.joints
        contact = self.leg_contact
        angle = hull.angle
        state = [
            angle,
            2.0 * hull.angularVelocity / FPS,
            0.3 * vel.x * (VIEWPORT_W / SCALE) / FPS,
            0.3 * vel.y * (VIEWPORT_H / SCALE) / FPS,
            j0.angle,
            j0.speed / SPEED_HIP,
            j1.angle + 1.0,
            j1.speed / SPEED_KNEE,
            1.0 if contact[0] else 0.0,
            j2.angle,
            j2.speed / SPEED_HIP,
            j3.angle + 1.0,
            j3.speed / SPEED_KNEE,
            1.0 if contact[1] else 0.0,
            *[ray.fraction for ray in self.lidar],
        ]
        self.scroll = px - VIEWPORT_W / SCALE / 5

        shaping = 130 * px / SCALE  # forward progress: ~300 for reaching the end
        shaping -= 5.0 * abs(angle)  # keep the hull level
        reward: Any = 0.0 if self.prev_shaping is None else shaping - self.prev_shaping
        self.prev_shaping = shaping
        for cost in _TORQUE_COST * effort:  # numpy scalars: float32 actions give float32
            reward -= cost

        terminated = False
        if self.game_over or px < 0:
            reward, terminated = -100.0, True
        if px > _FINISH_X:
            terminated = True
        if self.render_mode == "human":
            self.render()
        self._record_step(action)
        return np.array(state, dtype=np.float32), float(reward), terminated, False, {}

    # -- rendering ----------------------------------------------------------------------------

    def _frame(self) -> np.ndarray:
        if self.hull is None:
            raise error.ResetNeeded("Call reset before render.")
        if self._strip is None:
            grass = list(zip(self.terrain_x, self.terrain_y))
            self._strip = scenes.walker_terrain_strip(grass, self.obstacles)
        self.lidar_render = (self.lidar_render + 1) % 100
        i = self.lidar_render
        ray = None
        if i < 2 * len(self.lidar):  # one ray per frame sweeps forward, then back
            r = self.lidar[i] if i < len(self.lidar) else self.lidar[len(self.lidar) - i - 1]
            if r.p1 is not None:
                ray = ((r.p1[0], r.p1[1]), (r.p2[0], r.p2[1]))
        bodies = []
        for body, colors in zip(
            [*self.legs, self.hull],
            [LEG_COLORS[-1], LEG_COLORS[-1], LEG_COLORS[1], LEG_COLORS[1], HULL_COLOR],
        ):
            for f in body.fixtures:
                bodies.append(([tuple(f.body.transform * v) for v in f.shape.vertices], colors))
        clouds = [poly for poly, _, _ in self.cloud_poly]
        return scenes.render_bipedal_walker(self._strip, self.scroll, clouds, ray, bodies)


class BipedalWalkerHardcore(BipedalWalker):
    """``BipedalWalker(hardcore=True)`` under Gymnasium's name.

    Gymnasium's class of this name only raises, telling the user to pass ``hardcore=True``;
    here it builds that env (``hardcore=False`` is refused: use :class:`BipedalWalker`).
    """

    def __init__(self, render_mode: str | None = None, hardcore: bool = True) -> None:
        if hardcore is not True:
            raise ValueError(
                f"BipedalWalkerHardcore is BipedalWalker(hardcore=True), got hardcore="
                f"{hardcore!r}; use BipedalWalker for the plain course"
            )
        super().__init__(render_mode, hardcore=True)
