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
lift, the stance, the body's spread, ``static_ground_height_std_m``) and declines
``beyond-range`` only where that variance along the ray exceeds
``static_ground_max_relative_std`` of the range, where the ray grazes the ground and the
linearized intersection no longer holds.
"""

from __future__ import annotations

import numpy as np

from pedenv.config import FusedConfig
from pedenv.geometry import inverse_intrinsics
from pedenv.localization.fused.cue import CueEstimate, FrameSkeletons, first_reason, symmetric_2x2
from pedenv.localization.fused.height import KEYPOINT_HEIGHT_FRACTION, LONE_ANKLE_FRACTION_STD
from pedenv.records import Frame
from pedenv.skeleton import ANKLE_KEYPOINTS

NAME = "ground"
#: Below this sine of the angle between a ray and the road plane the ray never meets it.
MIN_GRAZING_SINE = 1e-4
#: Below this |n . g| (n the road normal, g the unnormalized pixel ray) the Jacobian is
#: not evaluated (the ray runs along the road).
MIN_NORMAL_DOT = 1e-12


def plane_intersection(rays: np.ndarray, origin: np.ndarray, normal: np.ndarray, plane_offset: np.ndarray | float):
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


def pixel_jacobians(frame: Frame, rays: np.ndarray, normal: np.ndarray, cam_height: float):
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


def ground_cue(frame: Frame, skeletons: FrameSkeletons, config: FusedConfig) -> CueEstimate:
    """Ground point of N pedestrians from their stance ankle on the vehicle's road plane.

    skeletons: the frame's rays (world) and stance ankles. The frame-to-frame covariance
    holds the pixel noise, the ankle's lift and where the foot stands against the body
    (``stance_std_m``, it changes with each step); the per-person part the road's unknown
    height under the pedestrian and the body's lateral spread.
    Declines with ``no-ankles``, ``camera-below-road``, ``above-horizon`` or ``beyond-range``.
    """
    n, ankles, origin = len(skeletons), list(ANKLE_KEYPOINTS), skeletons.origin
    normal = frame.ego.rotation[:, 2]
    rest = KEYPOINT_HEIGHT_FRACTION[ankles[0]] * config.person_height_mean_m
    offset = float(normal @ frame.ego.translation) + rest
    rays = skeletons.rays[:, ankles]  # (N, 2, 3)
    points, sine, cam_height = plane_intersection(rays, origin, normal, offset)
    seen = skeletons.stance
    hits = seen & (sine > MIN_GRAZING_SINE) & (cam_height > 0)
    xy_all = points[..., :2]
    ranges = np.sqrt((xy_all[..., 0] - origin[0]) ** 2 + (xy_all[..., 1] - origin[1]) ** 2)
    ju, jv = pixel_jacobians(frame, rays, normal, cam_height)
    focal = float(frame.camera.intrinsics[0, 0])
    pixel_var = (skeletons.noise * focal) ** 2  # (N,) the skeleton's own pixel noise, px^2
    lift_std = np.where(skeletons.lone, LONE_ANKLE_FRACTION_STD * config.person_height_mean_m,
                        config.ankle_height_std_m)
    if frame.camera.static:
        # the range the foot point itself allows: its spread (pixels and lift) within a share of the range
        spread = pixel_var[:, None] * (ju**2 + jv**2).sum(-1) + (lift_std[:, None] / np.where(hits, sine, 1.0)) ** 2
        near = hits & (spread <= (config.static_ground_max_relative_std * ranges) ** 2)
    else:
        near = hits & (ranges <= config.ground_max_distance_m)
    count = near.sum(axis=1)
    if not count.any():
        return CueEstimate.declined(NAME, first_reason(
            [(~seen.any(axis=1), "no-ankles"), (np.full(n, cam_height <= 0), "camera-below-road"),
             (~hits.any(axis=1), "above-horizon"), (count == 0, "beyond-range")], n))
    reasons = first_reason([(~seen.any(axis=1), "no-ankles"), (~hits.any(axis=1), "above-horizon"),
                            (count == 0, "beyond-range")], n)
    weight = near / np.maximum(count, 1)[:, None]  # (N, 2)
    xy = (weight[..., None] * np.where(near[..., None], xy_all, 0.0)).sum(axis=1)

    w2 = np.where(near, weight**2, 0.0) * pixel_var[:, None]
    pxx = (w2 * (ju[..., 0] ** 2 + jv[..., 0] ** 2)).sum(1)
    pxy = (w2 * (ju[..., 0] * ju[..., 1] + jv[..., 0] * jv[..., 1])).sum(1)
    pyy = (w2 * (ju[..., 1] ** 2 + jv[..., 1] ** 2)).sum(1)

    # a height error dz of the contact point moves it along the ray by dz / sine
    along = (weight[..., None] * rays[..., :2] / np.where(near, sine, 1.0)[..., None]).sum(axis=1)  # (N, 2)
    ax, ay = along[:, 0], along[:, 1]
    lift, lat = lift_std**2, config.lateral_std_m**2  # the foot's lift changes with the gait
    # a standing foot lies up to half a step ahead of or behind the body (walking direction
    # unknown: the same each way); the midpoint of two standing feet half as far
    stance = config.stance_std_m**2 / count.clip(1) ** 2
    frame_cov = symmetric_2x2(pxx + lift * ax * ax + stance, pxy + lift * ax * ay, pyy + lift * ay * ay + stance)
    # the road under a pedestrian r metres away stays off the vehicle's plane frame after
    # frame, and so does the body's sideways spread about its ground point (lean: the person's)
    r = np.sqrt((xy[:, 0] - origin[0]) ** 2 + (xy[:, 1] - origin[1]) ** 2)
    if frame.camera.static:  # the calibrated ground: only its own unevenness
        road = np.full(n, config.static_ground_height_std_m**2)
    else:
        road = (config.road_height_std_m + 0.5 * config.road_curvature_std_per_m * r**2) ** 2
    bias = symmetric_2x2(road * ax * ax + lat, road * ax * ay, road * ay * ay + lat)
    return CueEstimate(NAME, xy, frame_cov, bias, count > 0, reasons)
