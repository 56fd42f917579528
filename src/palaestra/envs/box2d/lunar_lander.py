"""LunarLander-v3: land a two-legged craft on the pad between the flags.

Gymnasium 1.4.0's dynamics (Oleg Klimov's lander), rebuilt on the same ``box2d`` package: the
world, bodies, fixtures and joint are created with the same Box2D calls in the same order, the
impulses are computed with the same float operations in the same association, and
``np_random`` is drawn in the same order (12 terrain heights, 2 initial forces, the two wind
indices when wind is on, then 2 dispersions per step, including the step that ``reset`` takes).
The same seed and actions therefore give bit-identical observations, rewards and flags
(tests/envs/box2d/test_parity.py).

Reward (Gymnasium's): the change in a shaping potential (distance to the pad, speed, tilt,
+10 per leg on the ground), minus 0.3 per full-power main-engine frame and 0.03 per side-engine
frame; -100 for a crash or flying off-screen, +100 when the lander comes to rest (Box2D puts
its body to sleep).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from palaestra import error, logger
from palaestra.envs.box2d._common import (
    ReplayCopies,
    box_action_values,
    check_bool,
    check_real,
    discrete_action,
    import_box2d,
)
from palaestra.envs.classic_control._common import RENDER_MODES, ClassicControlEnv
from palaestra.rendering import box2d_scenes as scenes
from palaestra.spaces import Box, Discrete

# Gymnasium's constants (lunar_lander.py), in its units: pixels unless divided by SCALE.
FPS = 50
SCALE = 30.0  # pixels per metre
MAIN_ENGINE_POWER = 13.0
SIDE_ENGINE_POWER = 0.6
INITIAL_RANDOM = 1000.0  # bound of the random force applied at reset
LANDER_POLY = [(-14, +17), (-17, 0), (-17, -10), (+17, -10), (+17, 0), (+14, +17)]
LEG_AWAY = 20
LEG_DOWN = 18
LEG_W, LEG_H = 2, 8
LEG_SPRING_TORQUE = 40
SIDE_ENGINE_HEIGHT = 14
SIDE_ENGINE_AWAY = 12
MAIN_ENGINE_Y_LOCATION = 4
VIEWPORT_W = 600
VIEWPORT_H = 400
CHUNKS = 11  # terrain segments

W = VIEWPORT_W / SCALE  # world width, metres
H = VIEWPORT_H / SCALE
HELIPAD_Y = H / 4
# Observation scales, each written as Gymnasium's expression so the floats are the same.
_HALF_W = VIEWPORT_W / SCALE / 2
_HALF_H = VIEWPORT_H / SCALE / 2
_PAD_Y = HELIPAD_Y + LEG_DOWN / SCALE
_MAIN_OFFSET = MAIN_ENGINE_Y_LOCATION / SCALE

# Collision categories: every moving part collides with the ground (category 1) only.
_LANDER_BITS, _LEG_BITS, _PARTICLE_BITS, _GROUND_MASK = 0x0010, 0x0020, 0x0100, 0x001
# userData tags, read by the contact listener
_LANDER, _LEG0, _LEG1 = "lander", 0, 1

LANDER_COLOR = ((128, 102, 230), (77, 77, 128))  # fill, outline


def _check_kwargs(gravity: Any, wind_power: Any, turbulence_power: Any) -> tuple[float, ...]:
    """Gymnasium's ranges: gravity in (-12, 0) is required, the wind ranges are advice."""
    g = check_real("gravity", gravity)
    if not -12.0 < g < 0.0:
        raise ValueError(f"gravity (current value: {gravity!r}) must be between -12 and 0")
    wind = check_real("wind_power", wind_power)
    if not 0.0 <= wind <= 20.0:
        logger.warn(
            "wind_power value is recommended to be between 0.0 and 20.0, "
            f"(current value: {wind_power})"
        )
    turbulence = check_real("turbulence_power", turbulence_power)
    if not 0.0 <= turbulence <= 2.0:
        logger.warn(
            "turbulence_power value is recommended to be between 0.0 and 2.0, "
            f"(current value: {turbulence_power})"
        )
    return g, wind, turbulence


@lru_cache(maxsize=1)
def _contact_listener_class() -> type:
    """A ``b2ContactListener`` that flags crashes and leg contacts on its env.

    Built on first use so that importing this module does not import Box2D.
    """
    box2d = import_box2d()

    class ContactDetector(box2d.b2ContactListener):  # type: ignore[name-defined]
        def __init__(self, env: LunarLander) -> None:
            super().__init__()
            self.env = env

        def BeginContact(self, contact: Any) -> None:
            for tag in (contact.fixtureA.body.userData, contact.fixtureB.body.userData):
                if tag == _LANDER:
                    self.env.game_over = True
                elif tag is not None:
                    self.env.leg_contact[tag] = True

        def EndContact(self, contact: Any) -> None:
            for tag in (contact.fixtureA.body.userData, contact.fixtureB.body.userData):
                if tag is not None and tag != _LANDER:
                    self.env.leg_contact[tag] = False

    return ContactDetector


@lru_cache(maxsize=1)
def _definitions() -> dict[str, Any]:
    """The Box2D definitions every episode builds from, made once (needs Box2D).

    ``reset`` makes the same ``CreateBody``/``CreateFixture`` calls with them as Gymnasium's
    keyword forms (``CreateStaticBody(shapes=...)``, ``CreateEdgeFixture(...)``,
    ``CreateDynamicBody(...)``), which build these definitions field by field in Python at
    every reset (a third of a LunarLander reset). They are never changed after this: the
    definitions ``reset`` changes (the terrain's edge, the leg joints) are each env's own.
    """
    b2 = import_box2d().b2
    initial_x, initial_y = VIEWPORT_W / SCALE / 2, VIEWPORT_H / SCALE
    legs = [
        b2.bodyDef(
            type=b2.dynamicBody,
            position=(initial_x - i * LEG_AWAY / SCALE, initial_y),
            angle=(i * 0.05),
            fixtures=b2.fixtureDef(
                shape=b2.polygonShape(box=(LEG_W / SCALE, LEG_H / SCALE)),
                density=1.0,
                restitution=0.0,
                categoryBits=_LEG_BITS,
                maskBits=_GROUND_MASK,
            ),
        )
        for i in (-1, +1)
    ]
    return {
        "moon": b2.bodyDef(type=b2.staticBody),
        # CreateStaticBody(shapes=...) puts the shape on a default fixture definition.
        "floor": b2.fixtureDef(shape=b2.edgeShape(vertices=[(0, 0), (W, 0)])),
        "lander": b2.bodyDef(
            type=b2.dynamicBody,
            position=(initial_x, initial_y),
            angle=0.0,
            fixtures=b2.fixtureDef(
                shape=b2.polygonShape(vertices=[(x / SCALE, y / SCALE) for x, y in LANDER_POLY]),
                density=5.0,
                friction=0.1,
                categoryBits=_LANDER_BITS,
                maskBits=_GROUND_MASK,
                restitution=0.0,
            ),
        ),
        "legs": legs,
    }


def _leg_joint(box2d: Any, i: int) -> Any:
    """The revolute joint definition of leg ``i`` (-1, +1), without its two bodies (nor the
    reference angle, which ``reset`` computes from them)."""
    joint = box2d.b2.revoluteJointDef(
        localAnchorA=(0, 0),
        localAnchorB=(i * LEG_AWAY / SCALE, LEG_DOWN / SCALE),
        enableMotor=True,
        enableLimit=True,
        maxMotorTorque=LEG_SPRING_TORQUE,
        motorSpeed=+0.3 * i,  # slow: the spring never throws the lander back up
    )
    # The legs swing within 0.5 rad of their splayed rest angle (Gymnasium's numbers).
    if i == -1:
        joint.lowerAngle, joint.upperAngle = +0.9 - 0.5, +0.9
    else:
        joint.lowerAngle, joint.upperAngle = -0.9, -0.9 + 0.5
    return joint


def _wind(index: int, power: float) -> float:
    """Gymnasium's non-periodic wind profile ``tanh(sin(2kx) + sin(pi kx)) * power``, k=0.01."""
    return math.tanh(math.sin(0.02 * index) + math.sin(math.pi * 0.01 * index)) * power


class LunarLander(ReplayCopies, ClassicControlEnv):
    """The lander; ``continuous=True`` takes ``[main, lateral]`` throttles in [-1, 1].

    Discrete actions: 0 nothing, 1 left engine, 2 main engine, 3 right engine.
    """

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": FPS}
    _FRESH_WORLD_EACH_RESET = True  # a copy replays the current episode only

    def __init__(
        self,
        render_mode: str | None = None,
        continuous: bool = False,
        gravity: float = -10.0,
        enable_wind: bool = False,
        wind_power: float = 15.0,
        turbulence_power: float = 1.5,
    ) -> None:
        self._record_init(
            render_mode=render_mode,
            continuous=continuous,
            gravity=gravity,
            enable_wind=enable_wind,
            wind_power=wind_power,
            turbulence_power=turbulence_power,
        )
        self.continuous = check_bool("continuous", continuous)
        self.enable_wind = check_bool("enable_wind", enable_wind)
        self.gravity, self.wind_power, self.turbulence_power = _check_kwargs(
            gravity, wind_power, turbulence_power
        )
        self._init_render(render_mode)
        self._box2d = import_box2d()  # after the argument checks: they need no Box2D
        # Per env, since reset sets the bodies (of this env's world) on them.
        self._joints = [_leg_joint(self._box2d, i) for i in (-1, +1)]
        # The terrain's edge: its vertices are set before each CreateFixture in reset.
        self._terrain_edge = self._box2d.b2.fixtureDef(
            shape=self._box2d.b2.edgeShape(vertices=[(0, 0), (1, 1)]), density=0, friction=0.1
        )
        low = np.array([-2.5, -2.5, -10.0, -10.0, -2 * math.pi, -10.0, -0.0, -0.0], np.float32)
        high = np.array([2.5, 2.5, 10.0, 10.0, 2 * math.pi, 10.0, 1.0, 1.0], np.float32)
        self.observation_space = Box(low, high)
        self.action_space: Box | Discrete = (
            Box(-1, +1, (2,), dtype=np.float32) if self.continuous else Discrete(4)
        )
        self.world: Any = None
        self.lander: Any = None
        self.legs: list[Any] = []
        self.leg_contact = [False, False]
        self.particles: list[Any] = []
        self.game_over = False
        self.prev_shaping: float | None = None
        self.wind_idx = self.torque_idx = 0
        self._background: np.ndarray | None = None

    # -- episode -----------------------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """New terrain and lander; the first observation is that of a no-op step."""
        super().reset(seed=seed)
        self._start_reset(seed)
        rng = self._own_random()
        b2 = self._box2d.b2
        if self.world is not None:
            self.world.contactListener = None  # break the env <-> listener cycle
        self.particles = []
        # A fresh world each episode, as Gymnasium does (its issue #728: reusing one leaks
        # contacts between episodes).
        self.world = world = b2.world(gravity=(0, self.gravity))
        self._listener = _contact_listener_class()(self)
        world.contactListener = self._listener
        self.game_over = False
        self.prev_shaping = None
        self.leg_contact = [False, False]

        height = rng.uniform(0, H / 2, size=(CHUNKS + 1,))  # [12]
        chunk_x = [W / (CHUNKS - 1) * i for i in range(CHUNKS)]
        self.helipad_x1 = chunk_x[CHUNKS // 2 - 1]
        self.helipad_x2 = chunk_x[CHUNKS // 2 + 1]
        self.helipad_y = HELIPAD_Y
        height[CHUNKS // 2 - 2 : CHUNKS // 2 + 3] = HELIPAD_Y  # the flat pad, 5 heights
        h = height.tolist()
        # Each height averaged with its neighbours; the first wraps to h[-1], as Gymnasium.
        smooth_y = [0.33 * (h[i - 1] + h[i] + h[i + 1]) for i in range(CHUNKS)]

        defs = _definitions()
        self.moon = moon = world.CreateBody(defs["moon"])
        moon.CreateFixture(defs["floor"])
        terrain = self._terrain_edge
        self.sky_polys = []
        for i in range(CHUNKS - 1):
            p1, p2 = (chunk_x[i], smooth_y[i]), (chunk_x[i + 1], smooth_y[i + 1])
            terrain.shape.vertices = [p1, p2]
            moon.CreateFixture(terrain)
            self.sky_polys.append([p1, p2, (p2[0], H), (p1[0], H)])

        self.lander = lander = world.CreateBody(defs["lander"])
        lander.userData = _LANDER
        push = rng.uniform(-INITIAL_RANDOM, INITIAL_RANDOM, size=2).tolist()
        lander.ApplyForceToCenter(tuple(push), True)
        if self.enable_wind:
            # Two scalar draws: integers(size=2) would consume the stream differently.
            self.wind_idx = int(rng.integers(-9999, 9999))
            self.torque_idx = int(rng.integers(-9999, 9999))

        self.legs = []
        for leg_def, joint in zip(defs["legs"], self._joints):
            leg = world.CreateBody(leg_def)
            leg.userData = len(self.legs)
            joint.bodyA, joint.bodyB = lander, leg
            # What the box2d package's revoluteJointDef(bodyA=..., bodyB=...) computes.
            joint.referenceAngle = leg.angle - lander.angle
            leg.joint = world.CreateJoint(joint)
            self.legs.append(leg)
        self.drawlist = [lander, *self.legs]
        self._background = None

        if self.render_mode == "human":
            self.render()
        # Gymnasium's first observation comes from a no-op step (which draws 2 dispersions).
        noop = np.zeros(2) if self.continuous else 0
        obs = self.step(noop)[0]
        self._record_reset(options)
        return obs, {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Fire the engines, advance the world 1/50 s, observe and score."""
        lander = self.lander
        if lander is None:
            raise error.ResetNeeded("Call reset before using step method.")
        self._start_step()
        continuous = self.continuous
        if continuous:
            throttle, lateral = box_action_values(action, self.action_space)
            throttle = min(max(throttle, -1.0), 1.0)
            lateral = min(max(lateral, -1.0), 1.0)
            fire_main, fire_side = throttle > 0.0, abs(lateral) > 0.5
        else:
            if (type(action) is int or type(action) is np.int64) and 0 <= action < 4:
                act = int(action)  # the common case, without discrete_action's call
            else:
                act = discrete_action(action, self.action_space)
            fire_main, fire_side = act == 2, act == 1 or act == 3
        contact = self.leg_contact

        if self.enable_wind and not (contact[0] or contact[1]):
            lander.ApplyForceToCenter((_wind(self.wind_idx, self.wind_power), 0.0), True)
            self.wind_idx += 1
            lander.ApplyTorque(_wind(self.torque_idx, self.turbulence_power), True)
            self.torque_idx += 1

        # Gymnasium's dispersion, uniform(-1, 1, size=2) / SCALE: numpy computes each uniform
        # draw as -1.0 + 2.0 * random() (the same two doubles), and random(2) costs a third.
        r0, r1 = self._rng.random(2).tolist()  # type: ignore[union-attr]
        d0, d1 = (-1.0 + 2.0 * r0) / SCALE, (-1.0 + 2.0 * r1) / SCALE
        m_power = s_power = 0.0
        if fire_main or fire_side:
            angle = lander.angle
            tip0, tip1 = math.sin(angle), math.cos(angle)  # the lander's up axis
            side0, side1 = -tip1, tip0
            pos = lander.position
            px, py = pos.x, pos.y  # not tuple(pos): b2Vec2.__iter__ is a Python lambda

        if fire_main:
            m_power = (throttle + 1.0) * 0.5 if continuous else 1.0  # 0.5..1.0
            k = _MAIN_OFFSET + 2 * d0  # engine 4 px below the centre, +-2 px of jitter
            ox = tip0 * k + side0 * d1
            oy = -tip1 * k - side1 * d1
            at = (px + ox, py + oy)
            if self.render_mode is not None:  # exhaust: decoration, never touches the lander
                flame = self._particle(3.5, at[0], at[1], m_power)
                flame.ApplyLinearImpulse(
                    (ox * MAIN_ENGINE_POWER * m_power, oy * MAIN_ENGINE_POWER * m_power), at, True
                )
            lander.ApplyLinearImpulse(
                (-ox * MAIN_ENGINE_POWER * m_power, -oy * MAIN_ENGINE_POWER * m_power), at, True
            )

        if fire_side:
            if continuous:
                direction, s_power = (1.0 if lateral > 0 else -1.0), abs(lateral)
            else:
                direction, s_power = act - 2, 1.0  # 1 fires the left engine, 3 the right
            lever = 3 * d1 + direction * SIDE_ENGINE_AWAY / SCALE
            ox = tip0 * d0 + side0 * lever
            oy = -tip1 * d0 - side1 * lever
            # Gymnasium offsets the thrust point by 17 px along x but SIDE_ENGINE_HEIGHT (14)
            # along y, which makes the torque depend on the tilt; kept for parity.
            at = (px + ox - tip0 * 17 / SCALE, py + oy + tip1 * SIDE_ENGINE_HEIGHT / SCALE)
            if self.render_mode is not None:
                puff = self._particle(0.7, at[0], at[1], s_power)
                puff.ApplyLinearImpulse(
                    (ox * SIDE_ENGINE_POWER * s_power, oy * SIDE_ENGINE_POWER * s_power), at, True
                )
            lander.ApplyLinearImpulse(
                (-ox * SIDE_ENGINE_POWER * s_power, -oy * SIDE_ENGINE_POWER * s_power), at, True
            )

        self.world.Step(1.0 / FPS, 6 * 30, 2 * 30)
        if self.particles:
            self._age_particles()

        pos, vel = lander.position, lander.linearVelocity
        angle = lander.angle
        s0 = (pos.x - _HALF_W) / _HALF_W
        s1 = (pos.y - _PAD_Y) / _HALF_H
        s2 = vel.x * _HALF_W / FPS
        s3 = vel.y * _HALF_H / FPS
        s5 = 20.0 * lander.angularVelocity / FPS
        s6 = 1.0 if contact[0] else 0.0
        s7 = 1.0 if contact[1] else 0.0
        obs = np.array((s0, s1, s2, s3, angle, s5, s6, s7), dtype=np.float32)

        # Shaping from the float64 state (not the float32 observation), as Gymnasium.
        shaping = (
            -100 * math.sqrt(s0 * s0 + s1 * s1)
            - 100 * math.sqrt(s2 * s2 + s3 * s3)
            - 100 * abs(angle)
            + 10 * s6
            + 10 * s7
        )
        reward = 0.0 if self.prev_shaping is None else shaping - self.prev_shaping
        self.prev_shaping = shaping
        reward -= m_power * 0.30  # fuel: about -30 for a heuristic landing
        reward -= s_power * 0.03

        terminated = False
        if self.game_over or abs(s0) >= 1.0:
            terminated, reward = True, -100.0
        if not lander.awake:  # at rest: Box2D put the island to sleep
            terminated, reward = True, +100.0
        if self.render_mode == "human":
            self.render()
        self._record_step(action)
        return obs, reward, terminated, False, {}

    # -- exhaust particles (only with a render_mode) -------------------------------------------

    def _particle(self, mass: float, x: float, y: float, ttl: float) -> Any:
        """A small disc body pushed out of an engine; it collides with the ground only."""
        b2 = self._box2d.b2
        p = self.world.CreateDynamicBody(
            position=(x, y),
            angle=0.0,
            fixtures=b2.fixtureDef(
                shape=b2.circleShape(radius=2 / SCALE, pos=(0, 0)),
                density=mass,
                friction=0.1,
                categoryBits=_PARTICLE_BITS,
                maskBits=_GROUND_MASK,
                restitution=0.3,
            ),
        )
        p.ttl = ttl
        self.particles.append(p)
        self._drop_expired_particles()
        return p

    def _age_particles(self) -> None:
        """Exhaust cools by 0.15 per step and goes when cold.

        Gymnasium ages particles in ``render``, so an ``rgb_array`` env that is never rendered
        (SB3's ``make_vec_env`` asks for ``rgb_array``) keeps every puff of the episode as a
        Box2D body: a hovering lander piles up hundreds and each step slows several times.
        Aging once per step gives the same frames when every step is rendered, and the lander
        moves the same either way (particles collide with the ground only).
        """
        for p in self.particles:
            p.ttl -= 0.15
        self._drop_expired_particles()

    def _drop_expired_particles(self) -> None:
        while self.particles and self.particles[0].ttl < 0:
            self.world.DestroyBody(self.particles.pop(0))

    # -- rendering ----------------------------------------------------------------------------

    def _frame(self) -> np.ndarray:
        if self.lander is None:
            raise error.ResetNeeded("Call reset before render.")
        if self._background is None:
            self._background = scenes.lunar_lander_background(
                self.sky_polys, (self.helipad_x1, self.helipad_x2), self.helipad_y
            )
        sparks = [(p.position.x, p.position.y, p.ttl) for p in self.particles]
        hull = [
            [tuple(f.body.transform * v) for v in f.shape.vertices]
            for body in self.drawlist
            for f in body.fixtures
        ]
        return scenes.render_lunar_lander(
            self._background, sparks, hull, (self.helipad_x1, self.helipad_x2), self.helipad_y
        )

    def close(self) -> None:
        """Close the window (if any) and drop the world."""
        super().close()
        if self.world is not None:
            self.world.contactListener = None


class LunarLanderContinuous(LunarLander):
    """``LunarLander(continuous=True)`` under Gymnasium's name.

    Gymnasium's class of this name only raises, telling the user to pass ``continuous=True``;
    here it builds that env (``continuous=False`` is refused: use :class:`LunarLander`).
    """

    def __init__(
        self, render_mode: str | None = None, continuous: bool = True, **kwargs: Any
    ) -> None:
        if continuous is not True:
            raise ValueError(
                f"LunarLanderContinuous is LunarLander(continuous=True), got continuous="
                f"{continuous!r}; use LunarLander for the discrete lander"
            )
        super().__init__(render_mode, continuous=True, **kwargs)
