"""The built-in scenarios: the ego's motion and the pedestrians of each, like the paper's CARLA set.

Every recipe takes a seeded generator and the scene duration and returns a
:class:`ScenarioPlan`. The ego drives along world +x in the right-hand lane (y = -1.75 m)
unless the recipe says otherwise; pedestrian numbers grow with the stretch of street
the ego sees during the scene, so longer scenes stay as busy.

:data:`SCENARIOS` are the paper's kind, a camera on a vehicle (the default set of every
command and of the golden figures); :data:`STATIC_SCENARIOS` have a camera fixed to the
ground (``mount: static``) and are generated only when named.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pedenv.errors import InputError
from pedenv.records import Camera, default_cam_to_vehicle
from pedenv.synthetic.ego_motion import Profile, integrate_track, smooth_step
from pedenv.synthetic.population import Pedestrians, concat
from pedenv.synthetic.streets import Road, crossers, plaza_walkers, sidewalk_walkers, standing_group

LANE_Y_M = -1.75
#: How far ahead the scenes place pedestrians (the camera sees them up to ~150 m).
VIEW_RANGE_M = 170.0
TURN_YAW_RATE_RAD_S = np.radians(20.0)


@dataclass(frozen=True)
class ScenarioPlan:
    """What a scenario does: ego speed and yaw-rate profiles (functions of time in s,
    in m/s and rad/s), its start pose (world x-y metres, yaw radians) and the pedestrians."""

    description: str
    speed: Profile
    yaw_rate: Profile
    pedestrians: Pedestrians
    start_xy: tuple[float, float] = (0.0, LANE_Y_M)
    start_yaw: float = 0.0
    camera: Camera | None = None  # None: the paper's vehicle camera (generator.default_camera)


def _constant(value: float) -> Profile:
    return lambda t: np.full(np.shape(t), float(value))


def _travel(speed: Profile, duration_s: float) -> float:
    t = np.linspace(0.0, duration_s, 400)
    return float(np.trapezoid(speed(t), t) if hasattr(np, "trapezoid") else np.trapz(speed(t), t))


def _count(density_per_m: float, length_m: float) -> int:
    return max(int(round(density_per_m * length_m)), 1)


def red_light_crossing(rng: np.random.Generator, duration_s: float) -> ScenarioPlan:
    main = Road(half_width_m=7.0, sidewalk_m=4.0)
    cross = Road(origin=(25.0, 0.0), yaw=np.pi / 2, half_width_m=7.0)
    peds = concat(
        crossers(rng, main, _count(0.55, duration_s), (10.0, 13.0), (-8.0, duration_s - 8.0)),
        crossers(rng, main, 6, (33.0, 36.0), (-10.0, duration_s - 5.0)),
        sidewalk_walkers(rng, main, 14, (6.0, VIEW_RANGE_M)),
        sidewalk_walkers(rng, cross, 6, (-60.0, 60.0)),
    )
    return ScenarioPlan("the ego waits at a red light; pedestrians cross on the crosswalk in front",
                        _constant(0.0), _constant(0.0), peds)


def _drive_past(speed_mps: float, density: float) -> Callable[[np.random.Generator, float], ScenarioPlan]:
    def recipe(rng: np.random.Generator, duration_s: float) -> ScenarioPlan:
        road = Road(half_width_m=5.0, sidewalk_m=4.0)
        reach = speed_mps * duration_s + VIEW_RANGE_M
        peds = concat(
            sidewalk_walkers(rng, road, _count(density, reach), (0.0, reach)),
            crossers(rng, road, 3, (60.0, reach), (-5.0, duration_s)),
        )
        return ScenarioPlan(f"the ego drives at {speed_mps * 3.6:.0f} km/h past pedestrians on the sidewalks",
                            _constant(speed_mps), _constant(0.0), peds)
    return recipe


def turn_intersection(rng: np.random.Generator, duration_s: float) -> ScenarioPlan:
    sign = rng.choice([-1.0, 1.0])  # +1 turns left
    turn_start, turn_s = 6.0, 4.5  # 4.5 s at 20 deg/s (plus ramps) = 90 deg
    speed = lambda t: 8.0 - 3.0 * smooth_step(t, 2.0, 3.0) + 3.0 * smooth_step(t, 12.0, 3.0)  # noqa: E731
    yaw_rate = lambda t: sign * TURN_YAW_RATE_RAD_S * (  # noqa: E731
        smooth_step(t, turn_start, 0.5) - smooth_step(t, turn_start + turn_s, 0.5))
    end_of_turn = turn_start + turn_s + 0.5
    track = integrate_track(np.array([0.0, end_of_turn]), speed, yaw_rate, start_xy=(0.0, LANE_Y_M))
    x_c = float(track.xy[-1, 0]) + sign * LANE_Y_M  # the cross street's centre line
    main = Road(half_width_m=5.0)
    cross = Road(origin=(x_c, 0.0), yaw=np.pi / 2, half_width_m=5.0)
    after = _travel(speed, duration_s) - _travel(speed, end_of_turn)
    y_end = float(track.xy[-1, 1])
    far = y_end + sign * (after + VIEW_RANGE_M)  # the farthest the ego sees along the cross street
    ahead = (min(-30.0 * sign, far), max(-30.0 * sign, far))
    peds = concat(
        sidewalk_walkers(rng, main, 24, (0.0, x_c + 60.0)),
        sidewalk_walkers(rng, cross, _count(0.12, ahead[1] - ahead[0]), ahead),
        crossers(rng, cross, 8, (sign * 8.0, sign * 11.0), (-6.0, duration_s - 6.0)),
        crossers(rng, main, 6, (x_c + 8.0, x_c + 11.0), (-6.0, duration_s - 6.0)),
        standing_group(
            rng, np.array([[x_c + dx, dy] for dx in (-7.0, 7.0) for dy in (-7.0, 7.0)]), rng.integers(1, 4, 4)
        ),
    )
    side = "left" if sign > 0 else "right"
    return ScenarioPlan(f"the ego turns {side} at an intersection (yaw rate 20 deg/s for {turn_s} s)",
                        speed, yaw_rate, peds)


def start_from_standstill(rng: np.random.Generator, duration_s: float) -> ScenarioPlan:
    road = Road(half_width_m=5.0)
    speed = lambda t: 11.0 * smooth_step(t, 4.0, 7.0)  # noqa: E731
    reach = _travel(speed, duration_s) + VIEW_RANGE_M
    peds = concat(
        crossers(rng, road, 6, (7.0, 10.0), (-6.0, 1.0)),
        sidewalk_walkers(rng, road, _count(0.15, reach), (3.0, reach)),
    )
    return ScenarioPlan("the ego waits, then accelerates to 40 km/h (up to 2.5 m/s^2)",
                        speed, _constant(0.0), peds)


def crowd(rng: np.random.Generator, duration_s: float) -> ScenarioPlan:
    road = Road(half_width_m=4.0, sidewalk_m=7.0)
    speed_mps = 2.5
    reach = speed_mps * duration_s + 90.0
    peds = concat(
        sidewalk_walkers(rng, road, _count(0.3, reach), (0.0, reach), standing_share=0.15),
        crossers(rng, road, _count(0.8, duration_s), (12.0, reach), (-8.0, duration_s - 4.0)),
        plaza_walkers(rng, 15, (70.0, 110.0), (-12.0, 12.0)),
    )
    return ScenarioPlan("the ego creeps at 9 km/h through a busy shopping street with crowds",
                        _constant(speed_mps), _constant(0.0), peds)


def standing_pedestrians(rng: np.random.Generator, duration_s: float) -> ScenarioPlan:  # noqa: ARG001 - a recipe
    road = Road(half_width_m=5.0)
    singles = sidewalk_walkers(rng, road, 12, (6.0, 150.0), standing_share=1.0)
    centres = road.point(rng.uniform(10.0, 120.0, 4), road.sidewalk_offsets(rng, 4))
    peds = concat(singles, standing_group(rng, centres, rng.integers(2, 5, 4)))
    return ScenarioPlan("the ego stands still; pedestrians stand alone or in groups on the sidewalks",
                        _constant(0.0), _constant(0.0), peds)


#: The static scenes' camera: this high above the ground (metres), pitched down this much (degrees).
STATIC_CAMERA_HEIGHT_M, STATIC_CAMERA_PITCH_DEG = 6.0, 20.0


def static_camera(height_m: float = STATIC_CAMERA_HEIGHT_M, pitch_down_deg: float = STATIC_CAMERA_PITCH_DEG) -> Camera:
    """The paper's 1600x900, 64.5 deg camera fixed ``height_m`` above the ground over the
    vehicle frame's origin, looking along +x and pitched down ``pitch_down_deg`` (``mount: static``)."""
    mount = default_cam_to_vehicle(height_m)
    a = np.radians(pitch_down_deg)
    pitch = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])  # about y (left)
    mount[:3, :3] = pitch @ mount[:3, :3]
    base = Camera.from_fov(1600, 900, 64.5)
    return Camera(base.intrinsics, base.width, base.height, mount, "static")


def static_plaza(rng: np.random.Generator, duration_s: float) -> ScenarioPlan:
    plaza = (8.0, 60.0), (-22.0, 22.0)
    street = Road(origin=(38.0, 0.0), yaw=np.pi / 2, half_width_m=4.0, sidewalk_m=3.0)
    peds = concat(
        plaza_walkers(rng, 28, *plaza),
        crossers(rng, street, _count(0.6, duration_s), (-15.0, 15.0), (-6.0, duration_s - 4.0)),
        standing_group(rng, np.array([[14.0, -6.0], [26.0, 9.0], [50.0, -12.0]]), rng.integers(2, 4, 3)),
    )
    return ScenarioPlan(f"a static camera {STATIC_CAMERA_HEIGHT_M:g} m up, {STATIC_CAMERA_PITCH_DEG:g} deg down, "
                        "over a plaza: people wander, cross a street through it and stand in groups",
                        _constant(0.0), _constant(0.0), peds, start_xy=(0.0, 0.0), camera=static_camera())


#: Scenario name -> (recipe, default duration in seconds).
_RECIPES: dict[str, tuple[Callable[[np.random.Generator, float], ScenarioPlan], float]] = {
    "red-light-crossing": (red_light_crossing, 20.0),
    "drive-30kmh-sidewalk": (_drive_past(30.0 / 3.6, 0.13), 20.0),
    "drive-50kmh-sidewalk": (_drive_past(50.0 / 3.6, 0.13), 15.0),
    "turn-intersection": (turn_intersection, 20.0),
    "start-from-standstill": (start_from_standstill, 20.0),
    "crowd": (crowd, 15.0),
    "standing-pedestrians": (standing_pedestrians, 15.0),
}
_STATIC_RECIPES: dict[str, tuple[Callable[[np.random.Generator, float], ScenarioPlan], float]] = {
    "static-plaza": (static_plaza, 15.0),
}

#: Names of the built-in vehicle-camera scenarios, in their default order (the default set).
SCENARIOS: tuple[str, ...] = tuple(_RECIPES)
#: Names of the built-in static-camera scenarios (generated only when named).
STATIC_SCENARIOS: tuple[str, ...] = tuple(_STATIC_RECIPES)
#: Every name :func:`build_scenario` knows.
ALL_SCENARIOS: tuple[str, ...] = SCENARIOS + STATIC_SCENARIOS


def default_duration(name: str) -> float:
    """Default length of scenario ``name`` in seconds."""
    return {**_RECIPES, **_STATIC_RECIPES}[name][1]


def build_scenario(name: str, rng: np.random.Generator, duration_s: float) -> ScenarioPlan:
    """The plan of scenario ``name``; raises ValueError listing the valid names."""
    recipes = {**_RECIPES, **_STATIC_RECIPES}
    if name not in recipes:
        raise InputError(f"unknown scenario {name!r}; valid: {', '.join(ALL_SCENARIOS)}")
    return recipes[name][0](rng, duration_s)
