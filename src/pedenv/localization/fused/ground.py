"""Ground-contact cue: the stance ankle's viewing ray meets the road under the pedestrian.

Of two seen ankles the lower one is used (the other may be the swing foot, lifted up to
~0.15 of body height, which at 10 m would put the point ~20 % too far); a lone ankle
may be the lifted one and gets a wider variance.

The road is the vehicle's own plane (z = 0 of the vehicle frame, so the vehicle's pitch
and roll tilt it), lifted by the ankle's resting height. The range follows from the
camera's height above that plane and the ray's angle below it; both the pixel noise
(through the Jacobian of the intersection w.r.t. the pixel) and
the road's unknown height under the pedestrian (which grows with distance on rolling
terrain) make the variance, which grows fast with distance: it is tight near the car
and fades where the ray grazes the road.

A ``static`` camera (:attr:`pedenv.records.Camera.mount`) stands on the ground it was
calibrated on: its pitch, roll and height are exact, so the road-height terms and the
range limit ``ground_max_distance_m`` (made for a camera 1.5 m above a pitching vehicle)
do not apply. Its ground cue has the foot point's own variance (pixel noise, the ankle's
lift, the stance, the body's spread, ``static_ground_height_std_m``) plus the calibration's
own error (an estimated camera's height and tilt, ``static_camera_height_std_m`` and
``static_camera_tilt_std_deg``: a tilt error moves the cut by ``r^2 / h`` times it) and declines
``beyond-range`` only where that variance along the ray exceeds
:data:`STATIC_GROUND_MAX_RELATIVE_STD` of the range, where the ray grazes the ground and the
linearized intersection no longer holds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import overload

import numpy as np

from pedenv.config import FusedConfig
from pedenv.geometry import inverse_intrinsics
from pedenv.localization.fused.cue import LATERAL_STD_M, CueEstimate, FrameSkeletons, first_reason, symmetric_2x2
from pedenv.localization.fused.height import KEYPOINT_HEIGHT_FRACTION, LONE_ANKLE_FRACTION_STD
from pedenv.records import Frame
from pedenv.skeleton import ANKLE_KEYPOINTS

NAME = "ground"
#: Below this sine of the angle between a ray and the road plane the ray never meets it.
MIN_GRAZING_SINE = 1e-4
#: Below this |n . g| (n the road normal, g the unnormalized pixel ray) the Jacobian is
#: not evaluated (the ray runs along the road).
MIN_NORMAL_DOT = 1e-12
#: How far (metres, 1 sigma) a stance ankle may sit above its resting height: the foot's
#: roll-off in the swing phase lifts the heel a few centimetres (gait tables).
ANKLE_HEIGHT_STD_M = 0.04
#: How far (metres, 1 sigma) the road under a pedestrian may lie off the vehicle's own plane
#: even nearby: kerbs (10-15 cm), camber and the suspension's pitch.
ROAD_HEIGHT_STD_M = 0.08
#: Spread of the road's curvature (1/m): the road ``r`` metres away lies about
#: ``0.5 * curvature * r^2`` off the vehicle's plane (rolling terrain), so the ground cue fades
#: with distance (0.2 m more spread at the 20 m of ``ground_max_distance_m``). 0.001: on the
#: real KITTI tuning drives (0013, 0011, 0004, 0001, 0000; ORB-SLAM3 poses) the ground cue's
#: errors along the ray are then 0.8 of its spread (RMS of the normalized error; 0.2 at the
#: earlier 0.008, which put a person 15 m away 60 % off in range at 1 sigma where the errors
#: were 12 %); the built-in terrain scenes' figures stay within their golden tolerances.
ROAD_CURVATURE_STD_PER_M = 0.001
#: A ``static`` camera's ground cue declines where the foot point's own spread along the ray
#: (pixel noise and the ankle's lift through the ray's cut with the ground) exceeds this share
#: of the range: the ray grazes the ground, the linearized cut no longer holds and the height
#: prior is sharper there (set on the static synthetic scenes).
STATIC_GROUND_MAX_RELATIVE_STD = 0.2
#: Spread (metres, 1 sigma) of a standing foot's ground point about the body's, per axis: a
#: walker's stance foot lies up to half a step (about 0.2 of body height) ahead of or behind
#: the body, 0.2 m along the unknown walking direction, about 0.14 m each way (geometry of the
#: gait); the midpoint of two standing feet counts half of it. Without it the ground cue's
#: sideways errors were 2.8x (0-10 m) its variance on the terrain scenes.
STANCE_STD_M = 0.14


@overload
def plane_intersection(rays: np.ndarray, origin: np.ndarray, normal: np.ndarray,
                       plane_offset: float) -> tuple[np.ndarray, np.ndarray, float]: ...


@overload
def plane_intersection(rays: np.ndarray, origin: np.ndarray, normal: np.ndarray,
                       plane_offset: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


def plane_intersection(rays: np.ndarray, origin: np.ndarray, normal: np.ndarray,
                       plane_offset: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray | float]:
    """Where rays from ``origin`` meet the plane ``normal . x = plane_offset``.

    rays: (..., 3) unit, world. origin: (3,) world, metres. normal: (3,) unit, world.
    plane_offset: broadcastable to (...,), metres. Returns ``(points (..., 3), sine (...,),
    height (...,))``: the points (garbage where the ray misses), the sine of the ray's angle
    below the plane, and the camera's height above it.
    """
    height = float(normal @ origin) - plane_offset
    sine = -(rays @ normal)
    s = height / np.where(sine > MIN_GRAZING_SINE, sine, 1.0)
    return origin + s[..., None] * rays, sine, height


def box_bottom_ranges(frame: Frame, boxes: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """(N,) horizontal range, metres, at which the ray through each box's bottom centre
    (``boxes`` (N, 4) pixels) meets the road (vehicle z = 0); inf where it does not.

    A person's feet lie at or below their box's bottom edge in the image (a box cut by the
    image's edge or an occluder ends above them), so on a ground known exactly (a static
    camera) they stand no farther than this. origin: (3,) camera centre, world, metres.
    """
    pixels = np.column_stack([0.5 * (boxes[:, 0] + boxes[:, 2]), boxes[:, 3], np.ones(len(boxes))])
    rays = pixels @ (frame.cam_to_world[:3, :3] @ inverse_intrinsics(frame.camera.intrinsics)).T
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    normal = frame.ego.rotation[:, 2]
    points, sine, height = plane_intersection(rays, origin, normal, float(normal @ frame.ego.translation))
    ranges = np.sqrt((points[:, 0] - origin[0]) ** 2 + (points[:, 1] - origin[1]) ** 2)
    return np.where((sine > MIN_GRAZING_SINE) & (height > 0), ranges, np.inf)


def pixel_jacobians(frame: Frame, rays: np.ndarray, normal: np.ndarray,
                    cam_height: float) -> tuple[np.ndarray, np.ndarray]:
    """d ground point / d pixel of rays (N, 2, 3) (unit, world) cut with the plane of unit
    ``normal`` (3,) ``cam_height`` metres below the camera: ``(ju, jv)``, each (N, 2, 2)
    metres per pixel, world x-y per ankle.

    With the unnormalized ray g = M (u, v, 1) (M = R K^-1, so g is the unit ray over its
    optical-axis component) the point is o + h g / (-n.g), and
    dp/du = h (g (n.M_u) - M_u (n.g)) / (n.g)^2.
    """
    m = frame.cam_to_world[:3, :3] @ inverse_intrinsics(frame.camera.intrinsics)
    depth = rays @ frame.cam_to_world[:3, 2]
    g = rays / np.where(np.abs(depth) > MIN_NORMAL_DOT, depth, 1.0)[..., None]
    ng = g @ normal
    scale = cam_height / np.where(np.abs(ng) > MIN_NORMAL_DOT, ng, -MIN_NORMAL_DOT) ** 2
    ju = scale[..., None] * (g[..., :2] * float(normal @ m[:, 0]) - m[:2, 0] * ng[..., None])
    jv = scale[..., None] * (g[..., :2] * float(normal @ m[:, 1]) - m[:2, 1] * ng[..., None])
    return ju, jv


def ankle_height(config: FusedConfig) -> float:
    """Metres above the ground of a standing person's ankle keypoint: the anatomical ankle
    (:data:`~pedenv.localization.fused.height.KEYPOINT_HEIGHT_FRACTION` of
    ``person_height_mean_m``) plus the pose source's ``ankle_keypoint_offset_m``."""
    anatomical = float(KEYPOINT_HEIGHT_FRACTION[ANKLE_KEYPOINTS[0]]) * config.person_height_mean_m
    return anatomical + config.ankle_keypoint_offset_m


def static_ground_variance(ranges: np.ndarray, config: FusedConfig) -> np.ndarray:
    """(N,) m^2, the variance of the calibrated ground's height under a static camera's
    pedestrians ``ranges`` (N,) metres away (horizontal), against the ankle ray's cut: its
    unevenness (``static_ground_height_std_m``), the camera's height error
    (``static_camera_height_std_m``), its pitch and roll error (``static_camera_tilt_std_deg``
    each), which tilts the ground about the camera by ``r`` times the angle at range ``r`` (in
    any direction: pitch in front, roll to the side), and how far this person's ankle keypoint
    sits off the plane's lift (``ankle_keypoint_offset_std_m``). Carried along the ray by
    ``1 / sine`` like any height error, so the range's spread grows like ``r^2 / h`` times the tilt.
    """
    tilt = np.radians(config.static_camera_tilt_std_deg) * np.asarray(ranges, float)
    return (config.static_ground_height_std_m**2 + config.static_camera_height_std_m**2 + tilt**2
            + config.ankle_keypoint_offset_std_m**2)


@dataclass(frozen=True)
class AnkleHits:
    """N pedestrians' two ankle rays (left, right) cut with the road plane under them.

    rays: (N, 2, 3) unit, world. xy: (N, 2, 2) where each ray meets the road, world x-y,
    metres (garbage where it does not). sine: (N, 2) of each ray's angle below the road.
    cam_height: metres, the camera above the road. hits: (N, 2) bool, a stance ankle whose
    ray meets the road. ranges: (N, 2) horizontal range of the meeting points, metres.
    ju, jv: (N, 2, 2) metres per pixel (:func:`pixel_jacobians`). pixel_var: (N,) px^2,
    each skeleton's own pixel noise. lift_std: (N,) metres, how high the ankle may be lifted.
    """

    rays: np.ndarray
    xy: np.ndarray
    sine: np.ndarray
    cam_height: float
    hits: np.ndarray
    ranges: np.ndarray
    ju: np.ndarray
    jv: np.ndarray
    pixel_var: np.ndarray
    lift_std: np.ndarray

    @classmethod
    def of(cls, frame: Frame, skeletons: FrameSkeletons, config: FusedConfig, level_m: float = 0.0) -> AnkleHits:
        """The stance ankles of ``skeletons`` on the vehicle's road plane raised by ``level_m``
        metres (:mod:`~pedenv.localization.fused.road_level`), lifted by the ankle keypoint's
        resting height (:func:`ankle_height`)."""
        origin, normal = skeletons.origin, frame.ego.rotation[:, 2]
        rest = ankle_height(config)
        road = float(normal @ frame.ego.translation) + level_m + rest  # the plane's offset, metres
        rays = skeletons.rays[:, list(ANKLE_KEYPOINTS)]  # (N, 2, 3)
        points, sine, cam_height = plane_intersection(rays, origin, normal, road)
        hits = skeletons.stance & (sine > MIN_GRAZING_SINE) & (cam_height > 0)
        xy = points[..., :2]
        ranges = np.sqrt((xy[..., 0] - origin[0]) ** 2 + (xy[..., 1] - origin[1]) ** 2)
        ju, jv = pixel_jacobians(frame, rays, normal, cam_height)
        pixel_var = (skeletons.noise * float(frame.camera.intrinsics[0, 0])) ** 2  # px^2
        lift_std = np.where(skeletons.lone, LONE_ANKLE_FRACTION_STD * config.person_height_mean_m,
                            ANKLE_HEIGHT_STD_M)
        return cls(rays, xy, sine, cam_height, hits, ranges, ju, jv, pixel_var, lift_std)

    def near(self, static: bool, config: FusedConfig) -> np.ndarray:
        """(N, 2) bool, hits close enough to trust: within ``ground_max_distance_m``, or for
        a ``static`` camera where the foot point's own spread (pixels and lift) stays within
        :data:`STATIC_GROUND_MAX_RELATIVE_STD` of the range."""
        if not static:
            return self.hits & (self.ranges <= config.ground_max_distance_m)
        spread = (self.pixel_var[:, None] * (self.ju**2 + self.jv**2).sum(-1)
                  + (self.lift_std[:, None] / np.where(self.hits, self.sine, 1.0)) ** 2)
        return self.hits & (spread <= (STATIC_GROUND_MAX_RELATIVE_STD * self.ranges) ** 2)


def ground_cue(frame: Frame, skeletons: FrameSkeletons, config: FusedConfig, level_m: float = 0.0,
               level_var: float = 0.0) -> CueEstimate:
    """Ground point of N pedestrians from their stance ankle on the vehicle's road plane.

    skeletons: the frame's rays (world) and stance ankles. level_m: metres, the plane raised
    to the scene's ground level (:mod:`~pedenv.localization.fused.road_level`), with its
    variance ``level_var`` (m^2, part of the per-person covariance). The frame-to-frame covariance
    holds the pixel noise, the ankle's lift and where the foot stands against the body
    (:data:`STANCE_STD_M`, it changes with each step); the per-person part the road's unknown
    height under the pedestrian and the body's lateral spread.
    Declines with ``no-ankles``, ``camera-below-road``, ``above-horizon`` or ``beyond-range``.
    """
    n, seen = len(skeletons), skeletons.stance
    ankles = AnkleHits.of(frame, skeletons, config, level_m)
    near = ankles.near(frame.camera.static, config)
    count = near.sum(axis=1)
    if not count.any():
        return CueEstimate.declined(NAME, first_reason(
            [(~seen.any(axis=1), "no-ankles"), (np.full(n, ankles.cam_height <= 0), "camera-below-road"),
             (~ankles.hits.any(axis=1), "above-horizon"), (count == 0, "beyond-range")], n))
    reasons = first_reason([(~seen.any(axis=1), "no-ankles"), (~ankles.hits.any(axis=1), "above-horizon"),
                            (count == 0, "beyond-range")], n)
    weight = near / np.maximum(count, 1)[:, None]  # (N, 2)
    xy = (weight[..., None] * np.where(near[..., None], ankles.xy, 0.0)).sum(axis=1)
    # a height error dz of the contact point moves it along the ray by dz / sine
    along = (weight[..., None] * ankles.rays[..., :2] / np.where(near, ankles.sine, 1.0)[..., None]).sum(axis=1)
    frame_cov = frame_covariance(ankles, near, weight, along)
    r = np.sqrt((xy[:, 0] - skeletons.origin[0]) ** 2 + (xy[:, 1] - skeletons.origin[1]) ** 2)
    bias = person_covariance(r, along, frame.camera.static, config, level_var)
    return CueEstimate(NAME, xy, frame_cov, bias, count > 0, reasons)


def frame_covariance(ankles: AnkleHits, near: np.ndarray, weight: np.ndarray, along: np.ndarray) -> np.ndarray:
    """(N, 2, 2) m^2, the part of the ground point's error new every frame: the pixel noise,
    the ankle's lift (it changes with the gait) and where the foot stands against the body.

    near: (N, 2) bool, the ankles used; weight: (N, 2) their weights in the mean; along:
    (N, 2) metres per metre of height error, the ground point's move (module notes).
    """
    w2 = np.where(near, weight**2, 0.0) * ankles.pixel_var[:, None]
    ju, jv = ankles.ju, ankles.jv
    pxx = (w2 * (ju[..., 0] ** 2 + jv[..., 0] ** 2)).sum(1)
    pxy = (w2 * (ju[..., 0] * ju[..., 1] + jv[..., 0] * jv[..., 1])).sum(1)
    pyy = (w2 * (ju[..., 1] ** 2 + jv[..., 1] ** 2)).sum(1)
    ax, ay = along[:, 0], along[:, 1]
    lift = ankles.lift_std**2
    # a standing foot lies up to half a step ahead of or behind the body (walking direction
    # unknown: the same each way); the midpoint of two standing feet half as far
    stance = STANCE_STD_M**2 / near.sum(axis=1).clip(1) ** 2
    return symmetric_2x2(pxx + lift * ax * ax + stance, pxy + lift * ax * ay, pyy + lift * ay * ay + stance)


def person_covariance(ranges: np.ndarray, along: np.ndarray, static: bool, config: FusedConfig,
                      level_var: float = 0.0) -> np.ndarray:
    """(N, 2, 2) m^2, the part of the error that repeats for the same person: the road under
    a pedestrian ``ranges`` (N,) metres away stays off the vehicle's plane frame after frame
    (a ``static`` camera's calibrated ground: its unevenness and the calibration's own
    error, :func:`static_ground_variance`), and so does the
    body's sideways spread about its ground point (lean). along: (N, 2) as in :func:`frame_covariance`.
    level_var: m^2, the variance of the scene's ground level the plane was raised to (moving camera).
    """
    if static:
        road = static_ground_variance(ranges, config)
    else:
        road = (ROAD_HEIGHT_STD_M + 0.5 * ROAD_CURVATURE_STD_PER_M * ranges**2) ** 2 + level_var
    ax, ay, lat = along[:, 0], along[:, 1], LATERAL_STD_M**2
    return symmetric_2x2(road * ax * ax + lat, road * ax * ay, road * ay * ay + lat)
