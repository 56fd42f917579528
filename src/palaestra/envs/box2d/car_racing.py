"""CarRacing-v3: drive a top-down car round a random track, seeing it as a 96x96 picture.

Gymnasium 1.4.0's environment (Oleg Klimov's), rebuilt on the same ``box2d`` package: the track
is generated from ``np_random`` with Gymnasium's draws and float operations (12 jittered
checkpoints, a steering walk between them, retried until the loop closes), the road tiles are
Box2D sensors created in the same order, and the car is :mod:`.car_dynamics`. Rewards
(+1000/N per new tile, -0.1 per step, -100 off the playfield) and endings are Gymnasium's.

The observation is a picture drawn without pygame by :mod:`palaestra.rendering.car_racing`,
which reproduces the pygame primitives Gymnasium uses (tests/envs/box2d measure the share of
pixels equal to Gymnasium's frames).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.box2d import car_dynamics
from palaestra.envs.box2d._common import (
    ReplayCopies,
    box_action,
    check_bool,
    check_real,
    discrete_action,
    import_box2d,
)
from palaestra.envs.box2d.car_dynamics import Car, Wheel
from palaestra.envs.classic_control._common import ClassicControlEnv, checked_options
from palaestra.rendering import car_racing as scene
from palaestra.spaces import Box, Discrete

STATE_W, STATE_H = 96, 96
VIDEO_W, VIDEO_H = 600, 400
WINDOW_W, WINDOW_H = 1000, 800
SCALE = 6.0  # track scale
TRACK_RAD = 900 / SCALE  # the track is a heavily morphed circle of this radius
PLAYFIELD = 2000 / SCALE  # leaving this square ends the episode
FPS = 50
ZOOM = 2.7
TRACK_DETAIL_STEP = 21 / SCALE
TRACK_TURN_RATE = 0.31
TRACK_WIDTH = 40 / SCALE
BORDER = 8 / SCALE
BORDER_MIN_COUNT = 4
GRASS_DIM = PLAYFIELD / 20.0
MAX_SHAPE_DIM = max(GRASS_DIM, TRACK_WIDTH, TRACK_DETAIL_STEP) * math.sqrt(2) * ZOOM * SCALE

# What the picture needs of this module's constants (rendering never imports the env).
_DIMS = scene.Dims(
    playfield=PLAYFIELD,
    grass_dim=GRASS_DIM,
    max_shape_dim=MAX_SHAPE_DIM,
    scale=SCALE,
    zoom=ZOOM,
    state_size=(STATE_W, STATE_H),
    video_size=(VIDEO_W, VIDEO_H),
    hull_color=car_dynamics.HULL_COLOR,
    wheel_w=car_dynamics.WHEEL_W,
    wheel_r=car_dynamics.WHEEL_R,
    car_size=car_dynamics.SIZE,
    wheel_white=car_dynamics.WHEEL_WHITE,
)
CHECKPOINTS = 12


class Tile:
    """A road tile: its sensor body, shade, and whether the car has driven over it."""

    __slots__ = ("body", "color", "idx", "road_friction", "road_visited")

    def __init__(self, body: Any, color: np.ndarray, idx: int) -> None:
        self.body = body
        self.color = color  # shared with the drawing list: contacts reset it in place
        self.idx = idx
        self.road_visited = False
        self.road_friction = 1.0


@lru_cache(maxsize=1)
def _friction_detector_class() -> type:
    """A ``b2ContactListener`` that scores new tiles and tracks what each wheel touches."""
    b2 = import_box2d().b2

    class FrictionDetector(b2.contactListener):  # type: ignore[name-defined]
        def __init__(self, env: CarRacing, lap_complete_percent: float) -> None:
            super().__init__()
            self.env = env
            self.lap_complete_percent = lap_complete_percent

        def BeginContact(self, contact: Any) -> None:
            self._contact(contact, True)

        def EndContact(self, contact: Any) -> None:
            self._contact(contact, False)

        def _contact(self, contact: Any, begin: bool) -> None:
            u1, u2 = contact.fixtureA.body.userData, contact.fixtureB.body.userData
            tile = obj = None
            if isinstance(u1, Tile):
                tile, obj = u1, u2
            if isinstance(u2, Tile):
                tile, obj = u2, u1
            if tile is None:
                return
            env = self.env
            tile.color[:] = env.road_color  # touched tiles lose their shade (Gymnasium)
            if not isinstance(obj, Wheel):
                return
            if begin:
                obj.tiles.add(tile)
                if not tile.road_visited:
                    tile.road_visited = True
                    env.reward += 1000.0 / len(env.track)
                    env.tile_visited_count += 1
                    # A lap counts once enough of the track was covered.
                    if (
                        tile.idx == 0
                        and env.tile_visited_count / len(env.track) > self.lap_complete_percent
                    ):
                        env.new_lap = True
            else:
                obj.tiles.remove(tile)

    return FrictionDetector


def _sign(x: float) -> float:
    return 1.0 if x > 0 else (-1.0 if x < 0 else 0.0)


class CarRacing(ReplayCopies, ClassicControlEnv):
    """Continuous ``[steer, gas, brake]`` actions, or 5 discrete ones with
    ``continuous=False`` (nothing, right, left, gas, brake)."""

    metadata: dict[str, Any] = {
        "render_modes": ["human", "rgb_array", "state_pixels"],
        "render_fps": FPS,
    }

    def __init__(
        self,
        render_mode: str | None = None,
        verbose: bool = False,
        lap_complete_percent: float = 0.95,
        domain_randomize: bool = False,
        continuous: bool = True,
    ) -> None:
        self._record_init(
            render_mode=render_mode,
            verbose=verbose,
            lap_complete_percent=lap_complete_percent,
            domain_randomize=domain_randomize,
            continuous=continuous,
        )
        self.continuous = check_bool("continuous", continuous)
        self.domain_randomize = check_bool("domain_randomize", domain_randomize)
        self.verbose = check_bool("verbose", verbose)
        self.lap_complete_percent = check_real("lap_complete_percent", lap_complete_percent)
        if not 0.0 <= self.lap_complete_percent <= 1.0:
            raise ValueError(
                "lap_complete_percent must be in [0, 1] (the share of tiles a lap needs), "
                f"got {lap_complete_percent!r}"
            )
        self._init_render(render_mode)
        b2 = import_box2d().b2  # after the argument checks: they need no Box2D
        self._init_colors()
        self._listener = _friction_detector_class()(self, self.lap_complete_percent)
        self.world = b2.world((0, 0), contactListener=self._listener)
        self._fd_tile = b2.fixtureDef(
            shape=b2.polygonShape(vertices=[(0, 0), (1, 0), (1, -1), (0, -1)])
        )
        self.road: list[Tile] = []
        self.road_poly: list[tuple[list[tuple[float, float]], Any]] = []
        self.track: list[tuple[float, float, float, float]] = []
        self.car: Car | None = None
        self.reward = 0.0
        self.prev_reward = 0.0
        self.tile_visited_count = 0
        self.new_lap = False
        self.t = 0.0
        self.state: np.ndarray | None = None
        if self.continuous:
            self.action_space: Box | Discrete = Box(
                np.array([-1, 0, 0]).astype(np.float32), np.array([+1, +1, +1]).astype(np.float32)
            )
        else:
            self.action_space = Discrete(5)
        self.observation_space = Box(low=0, high=255, shape=(STATE_H, STATE_W, 3), dtype=np.uint8)

    # -- colours ----------------------------------------------------------------------------

    def _init_colors(self) -> None:
        if self.domain_randomize:
            self._random_colors()
        else:
            self.road_color = np.array([102, 102, 102])
            self.bg_color = np.array([102, 204, 102])
            self.grass_color = np.array([102, 230, 102])

    def _random_colors(self) -> None:
        """Gymnasium's draws: road, background, then which channel of the grass is +20."""
        rng = self._own_random()
        self.road_color = rng.uniform(0, 210, size=3)
        self.bg_color = rng.uniform(0, 210, size=3)
        self.grass_color = np.copy(self.bg_color)
        idx = rng.integers(3)
        self.grass_color[idx] += 20

    # -- track ------------------------------------------------------------------------------

    def _create_track(self) -> bool:
        """One attempt at Gymnasium's track; False (after the same draws) if it fails."""
        rng = self._own_random()
        checkpoints = []
        for c in range(CHECKPOINTS):
            noise = rng.uniform(0, 2 * math.pi * 1 / CHECKPOINTS)
            alpha = 2 * math.pi * c / CHECKPOINTS + noise
            rad = rng.uniform(TRACK_RAD / 3, TRACK_RAD)
            if c == 0:
                alpha = 0
                rad = 1.5 * TRACK_RAD
            if c == CHECKPOINTS - 1:
                alpha = 2 * math.pi * c / CHECKPOINTS
                self.start_alpha = 2 * math.pi * (-0.5) / CHECKPOINTS
                rad = 1.5 * TRACK_RAD
            checkpoints.append((alpha, rad * math.cos(alpha), rad * math.sin(alpha)))
        self.road = []

        # Walk from checkpoint to checkpoint, turning at most TRACK_TURN_RATE per step.
        # Floats from the start (Gymnasium's ints 0 give the same values: 0 -> 0.0 is exact).
        x, y, beta = 1.5 * TRACK_RAD, 0.0, 0.0
        dest_i = 0
        laps = 0
        track: list[tuple[float, float, float, float]] = []
        no_freeze = 2500
        visited_other_side = False
        while True:
            alpha = math.atan2(y, x)
            if visited_other_side and alpha > 0:
                laps += 1
                visited_other_side = False
            if alpha < 0:
                visited_other_side = True
                alpha += 2 * math.pi
            while True:  # the next checkpoint ahead
                failed = True
                while True:
                    dest_alpha, dest_x, dest_y = checkpoints[dest_i % len(checkpoints)]
                    if alpha <= dest_alpha:
                        failed = False
                        break
                    dest_i += 1
                    if dest_i % len(checkpoints) == 0:
                        break
                if not failed:
                    break
                alpha -= 2 * math.pi
            r1x = math.cos(beta)
            r1y = math.sin(beta)
            p1x = -r1y
            p1y = r1x
            dest_dx = dest_x - x
            dest_dy = dest_y - y
            proj = r1x * dest_dx + r1y * dest_dy  # destination projected on the radius
            while beta - alpha > 1.5 * math.pi:
                beta -= 2 * math.pi
            while beta - alpha < -1.5 * math.pi:
                beta += 2 * math.pi
            prev_beta = beta
            proj *= SCALE
            if proj > 0.3:
                beta -= min(TRACK_TURN_RATE, abs(0.001 * proj))
            if proj < -0.3:
                beta += min(TRACK_TURN_RATE, abs(0.001 * proj))
            x += p1x * TRACK_DETAIL_STEP
            y += p1y * TRACK_DETAIL_STEP
            track.append((alpha, prev_beta * 0.5 + beta * 0.5, x, y))
            if laps > 4:
                break
            no_freeze -= 1
            if no_freeze == 0:
                break

        # The closed loop: between the last two passes through the start angle.
        i1, i2 = -1, -1
        i = len(track)
        while True:
            i -= 1
            if i == 0:
                return False
            through_start = track[i][0] > self.start_alpha and track[i - 1][0] <= self.start_alpha
            if through_start and i2 == -1:
                i2 = i
            elif through_start and i1 == -1:
                i1 = i
                break
        if self.verbose:
            print(f"Track generation: {i1}..{i2} -> {i2 - i1}-tiles track")
        track = track[i1 : i2 - 1]

        first_beta = track[0][1]
        first_perp_x = math.cos(first_beta)
        first_perp_y = math.sin(first_beta)
        # How far head and tail are apart across the track.
        gap_x = first_perp_x * (track[0][2] - track[-1][2])
        gap_y = first_perp_y * (track[0][3] - track[-1][3])
        if math.sqrt(gap_x * gap_x + gap_y * gap_y) > TRACK_DETAIL_STEP:
            return False

        # Red-white kerbs on the hard turns: BORDER_MIN_COUNT same-direction sharp steps.
        n = len(track)
        border = [False] * n
        for i in range(n):
            good = True
            oneside = 0.0
            for neg in range(BORDER_MIN_COUNT):
                beta1 = track[i - neg - 0][1]
                beta2 = track[i - neg - 1][1]
                good &= abs(beta1 - beta2) > TRACK_TURN_RATE * 0.2
                oneside += _sign(beta1 - beta2)
            good &= abs(oneside) == BORDER_MIN_COUNT
            border[i] = good
        for i in range(n):
            for neg in range(BORDER_MIN_COUNT):
                border[i - neg] |= border[i]

        for i in range(n):
            _, beta1, x1, y1 = track[i]
            _, beta2, x2, y2 = track[i - 1]
            c1, s1, c2, s2 = math.cos(beta1), math.sin(beta1), math.cos(beta2), math.sin(beta2)
            road1_l = (x1 - TRACK_WIDTH * c1, y1 - TRACK_WIDTH * s1)
            road1_r = (x1 + TRACK_WIDTH * c1, y1 + TRACK_WIDTH * s1)
            road2_l = (x2 - TRACK_WIDTH * c2, y2 - TRACK_WIDTH * s2)
            road2_r = (x2 + TRACK_WIDTH * c2, y2 + TRACK_WIDTH * s2)
            vertices = [road1_l, road1_r, road2_r, road2_l]
            self._fd_tile.shape.vertices = vertices
            body = self.world.CreateStaticBody(fixtures=self._fd_tile)
            tile = Tile(body, self.road_color + 0.01 * (i % 3) * 255, i)
            body.userData = tile
            body.fixtures[0].sensor = True
            self.road_poly.append((vertices, tile.color))
            self.road.append(tile)
            if border[i]:
                side = _sign(beta2 - beta1)
                b1_l = (x1 + side * TRACK_WIDTH * c1, y1 + side * TRACK_WIDTH * s1)
                b1_r = (
                    x1 + side * (TRACK_WIDTH + BORDER) * c1,
                    y1 + side * (TRACK_WIDTH + BORDER) * s1,
                )
                b2_l = (x2 + side * TRACK_WIDTH * c2, y2 + side * TRACK_WIDTH * s2)
                b2_r = (
                    x2 + side * (TRACK_WIDTH + BORDER) * c2,
                    y2 + side * (TRACK_WIDTH + BORDER) * s2,
                )
                kerb = (255, 255, 255) if i % 2 == 0 else (255, 0, 0)
                self.road_poly.append(([b1_l, b1_r, b2_r, b2_l], kerb))
        self.track = track
        return True

    # -- episode ----------------------------------------------------------------------------

    def _destroy(self) -> None:
        if not self.road:
            return
        for tile in self.road:
            self.world.DestroyBody(tile.body)
        self.road = []
        assert self.car is not None
        self.car.destroy()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """A new track (``options={"randomize": False}`` keeps the colours when randomizing)."""
        super().reset(seed=seed)
        fresh_world = self._start_reset(seed)
        self._destroy()
        self._listener = _friction_detector_class()(self, self.lap_complete_percent)
        if fresh_world:  # the history a copy replays restarts here (ReplayCopies)
            self.world = import_box2d().b2.world((0, 0), contactListener=self._listener)
        self.world.contactListener = self._listener
        self.reward = 0.0
        self.prev_reward = 0.0
        self.tile_visited_count = 0
        self.t = 0.0
        self.new_lap = False
        self.road_poly = []
        if self.domain_randomize:
            randomize = True
            given = checked_options(options, ("randomize",))
            if "randomize" in given:
                randomize = given["randomize"]
            if randomize:
                self._random_colors()
        while not self._create_track():
            if self.verbose:
                print(
                    "retry to generate track (normal if there are not many"
                    "instances of this message)"
                )
        self.car = Car(self.world, *self.track[0][1:4])
        if self.render_mode == "human":
            self.render()
        obs = self._advance(None)[0]
        self._record_reset(options)
        return obs, {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Steer, accelerate or brake for 1/50 s; the observation is the new 96x96 frame."""
        if self.car is None:
            raise error.ResetNeeded("Call reset before using step method.")
        self._start_step()
        if self.continuous:
            steer, gas, brake = box_action(action, self.action_space).tolist()
            result = self._advance((-steer, gas, brake))  # positive steer turns right
        else:
            act = discrete_action(action, self.action_space)
            result = self._advance((-0.6 * (act == 1) + 0.6 * (act == 2), 0.2 * (act == 3),
                                    0.8 * (act == 4)))  # fmt: skip
        self._record_step(action)
        return result

    def _advance(
        self, controls: tuple[float, float, float] | None
    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        car = self.car
        assert car is not None
        if controls is not None:
            car.steer(controls[0])
            car.gas(controls[1])
            car.brake(controls[2])
        car.step(1.0 / FPS)
        self.world.Step(1.0 / FPS, 6 * 30, 2 * 30)
        self.t += 1.0 / FPS
        # A copy replaying its history draws only the last observation (_after_replay): the
        # picture never feeds back into the physics, and drawing is most of a step's time.
        self.state = None if self._replaying else self._draw("state_pixels")

        step_reward = 0.0
        terminated = False
        info: dict[str, Any] = {}
        if controls is not None:  # the step reset takes scores nothing
            self.reward -= 0.1
            car.fuel_spent = 0.0
            step_reward = self.reward - self.prev_reward
            self.prev_reward = self.reward
            if self.tile_visited_count == len(self.track) or self.new_lap:
                terminated = True
                info["lap_finished"] = True
            x, y = car.hull.position
            if abs(x) > PLAYFIELD or abs(y) > PLAYFIELD:
                terminated = True
                info["lap_finished"] = False
                step_reward = -100.0
        if self.render_mode == "human":
            self.render()
        return self.state, step_reward, terminated, False, info  # type: ignore[return-value]

    # -- rendering --------------------------------------------------------------------------

    def _draw(self, mode: str) -> np.ndarray:
        assert self.car is not None
        return scene.render(self, mode, _DIMS)

    def _frame(self) -> np.ndarray:
        if self.car is None:
            raise error.ResetNeeded("Call reset before render.")
        return self._draw("rgb_array")

    def render(self) -> np.ndarray | None:
        """``rgb_array``: a 600x400 frame; ``state_pixels``: the 96x96 observation."""
        if self.render_mode == "state_pixels":
            if self.car is None:
                raise error.ResetNeeded("Call reset before render.")
            return self._draw("state_pixels")
        return super().render()

    def _after_replay(self) -> None:
        if self.car is not None:
            self.state = self._draw("state_pixels")

    def close(self) -> None:
        """Close the window, if any."""
        super().close()
