"""Seeded generation of the built-in synthetic scenes as :class:`~pedenv.records.Scene` objects.

Each scene's random numbers come from ``(seed, scenario name)`` alone, so a scenario
generated on its own equals the same scenario generated with all the others.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence

import numpy as np

from pedenv.body import world_keypoints
from pedenv.errors import InputError
from pedenv.records import Camera, Frame, GroundTruth, Scene
from pedenv.synthetic.ego_motion import ego_poses, integrate_track
from pedenv.synthetic.population import Pedestrians
from pedenv.synthetic.scenarios import ALL_SCENARIOS, SCENARIOS, build_scenario, default_duration
from pedenv.synthetic.terrain import Terrain, random_terrain
from pedenv.synthetic.visibility import VisibilityRules, visible_pedestrians
from pedenv.synthetic.walker import body_keypoints, gait_amplitude, stride_length
from pedenv.validation import check_number

#: Standing people lean about their ankles by up to this angle (radians) with this period (s).
SWAY_RAD, SWAY_PERIOD_S = 0.012, 4.0

#: The default visibility rules (frozen, shared).
DEFAULT_VISIBILITY = VisibilityRules()


def scenario_rng(seed: int, name: str, purpose: str = "scene") -> np.random.Generator:
    """A generator determined by ``seed``, the scene ``name`` and a ``purpose`` label."""
    return np.random.default_rng([int(seed) & 0xFFFFFFFF, zlib.crc32(name.encode()), zlib.crc32(purpose.encode())])


def scene_terrain(seed: int, name: str, terrain: bool = True) -> Terrain:
    """The ground of scene ``name`` generated with ``seed`` (flat unless ``terrain``)."""
    return random_terrain(scenario_rng(seed, name, "terrain")) if terrain else Terrain.flat()


def default_camera() -> Camera:
    """The paper's camera: 1600x900 pixels, 64.5 deg horizontal field of view, 1.5 m above the road."""
    return Camera.from_fov(1600, 900, 64.5, height_m=1.5)


def generate_scenes(seed: int = 0, names: Sequence[str] | None = None, *, frame_rate_hz: float = 10.0,
                    duration_s: float | None = None, terrain: bool = False) -> list[Scene]:
    """Generate the built-in scenes.

    seed: the same seed gives identical scenes. names: scenario names (default: all of
    :data:`~pedenv.synthetic.SCENARIOS`, in that order; the static-camera scenes of
    :data:`~pedenv.synthetic.scenarios.STATIC_SCENARIOS` only when named). frame_rate_hz: camera frame
    rate. duration_s: length of every scene (default: each scenario's own, 15-20 s).
    terrain: rolling terrain with grades up to 5 % instead of the flat plane z = 0.
    Raises InputError for an unknown name or an out-of-range option.
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise InputError(f"seed must be an integer, got {seed!r}")
    if isinstance(names, str):
        names = [names]
    names = list(SCENARIOS if names is None else names)
    unknown = [n for n in names if n not in ALL_SCENARIOS]
    if unknown:
        raise InputError(f"unknown scenario {unknown[0]!r}; valid: {', '.join(ALL_SCENARIOS)}")
    check_number("frame_rate_hz", frame_rate_hz, 0.5, 100)
    if duration_s is not None:
        check_number("duration_s", duration_s, 1, 600)
    return [generate_scene(seed, name, frame_rate_hz=frame_rate_hz,
                           duration_s=default_duration(name) if duration_s is None else float(duration_s),
                           terrain=terrain) for name in names]


def generate_scene(seed: int, name: str, *, frame_rate_hz: float, duration_s: float, terrain: bool,
                   rules: VisibilityRules = DEFAULT_VISIBILITY) -> Scene:
    """One scene of scenario ``name`` (see :func:`generate_scenes` for the arguments)."""
    rng = scenario_rng(seed, name)
    plan = build_scenario(name, rng, duration_s)
    ground = scene_terrain(seed, name, terrain)
    times = np.arange(int(np.floor(duration_s * frame_rate_hz + 1e-9))) / frame_rate_hz
    track = integrate_track(times, plan.speed, plan.yaw_rate, start_xy=plan.start_xy, start_yaw=plan.start_yaw)
    camera = plan.camera or default_camera()
    frames = []
    for index, (t, ego) in enumerate(zip(times, ego_poses(track, ground))):
        cam_to_world = ego.matrix @ camera.cam_to_vehicle
        truth = _ground_truth(plan.pedestrians, ground, float(t), cam_to_world, camera, rules)
        frames.append(Frame(index, float(t), camera, ego, ground_truth=truth, scene=name))
    relief = f"rolling terrain (grades up to {ground.max_grade:.1%})" if terrain else "flat ground"
    return Scene(name, tuple(frames), f"{plan.description}; {relief}; seed {seed}")


def scene_pedestrians(seed: int, name: str, duration_s: float | None = None) -> Pedestrians:
    """The pedestrians of scene ``name`` generated with ``seed`` (the same plan :func:`generate_scene`
    builds): ``.at(t)`` gives every one's true position and facing (``heading``) at any time ``t``
    (seconds), before, during and after the scene; row ``i`` is ground-truth id ``i``."""
    duration = default_duration(name) if duration_s is None else float(duration_s)
    return build_scenario(name, scenario_rng(seed, name), duration).pedestrians


def pedestrian_skeletons(peds: Pedestrians, ground: Terrain, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Ground points (N, 3) and 3D skeletons (N, 17, 3), world frame, metres, at time ``t`` (s)."""
    state = peds.at(t)
    feet = np.concatenate([state.xy, ground.height(state.xy)[:, None]], axis=1)
    phase = peds.phases + 2.0 * np.pi * state.walked / stride_length(peds.heights, np.maximum(peds.speeds, 0.5))
    gait = np.where(state.moving, gait_amplitude(peds.speeds), 0.0)
    still = 1.0 - np.minimum(gait, 1.0)
    angle = 2.0 * np.pi * t / SWAY_PERIOD_S + peds.sway_phases
    sway = SWAY_RAD * still[:, None] * np.stack([np.sin(angle), np.sin(0.7 * angle + 1.0)], axis=1)
    return feet, world_keypoints(feet, state.heading, body_keypoints(peds.heights, phase, gait, sway))


def _ground_truth(peds: Pedestrians, ground: Terrain, t: float, cam_to_world: np.ndarray, camera: Camera,
                  rules: VisibilityRules) -> GroundTruth:
    feet, skeletons = pedestrian_skeletons(peds, ground, t)
    seen = visible_pedestrians(skeletons, feet, camera, cam_to_world, rules)
    keep = np.flatnonzero(seen.keep)
    return GroundTruth(keep.astype(np.int64), feet[keep], seen.boxes[keep], seen.keypoints[keep],
                       seen.visible[keep], peds.heights[keep], skeletons[keep])
