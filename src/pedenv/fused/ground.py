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
"""

from __future__ import annotations

import numpy as np

from pedenv.config import FusedConfig
from pedenv.fused.cue import CueEstimate, first_reason, stance_ankle
from pedenv.fused.height import KEYPOINT_HEIGHT_FRACTION, LONE_ANKLE_FRACTION_STD
from pedenv.records import Frame
from pedenv.skeleton import ANKLE_KEYPOINTS

NAME = "ground"
#: Below this sine of the angle between a ray and the road plane the ray never meets it.
MIN_GRAZING_SINE = 1e-4


def plane_intersection(rays: np.ndarray, origin: np.ndarray, normal: np.ndarray, plane_offset: np.ndarray):
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


def ground_cue(frame: Frame, keypoints: np.ndarray, usable: np.ndarray, rays: np.ndarray, origin: np.ndarray,
               config: FusedConfig) -> CueEstimate:
    """Ground point of N pedestrians from their stance ankle on the vehicle's road plane.

    keypoints: (N, 17, 2) pixels. usable: (N, 17) bool, seen and inside the image.
    rays: (N, 17, 3) unit, world. origin: (3,) camera centre, world, metres.
    Declines with ``no-ankles``, ``camera-below-road``, ``above-horizon`` or ``beyond-range``.
    """
    n = len(keypoints)
    ankles = list(ANKLE_KEYPOINTS)
    normal = frame.ego.rotation[:, 2]
    rest = KEYPOINT_HEIGHT_FRACTION[ankles[0]] * config.person_height_mean_m
    offset = float(normal @ frame.ego.translation) + rest
    points, sine, cam_height = plane_intersection(rays[:, ankles], origin, normal, offset)
    seen, lone = stance_ankle(usable, rays, ANKLE_KEYPOINTS,
                              config.keypoint_pixel_std / float(frame.camera.intrinsics[0, 0]))
    hits = seen & (sine > MIN_GRAZING_SINE) & (cam_height > 0)
    ranges = np.linalg.norm(points[..., :2] - origin[:2], axis=-1)
    near = hits & (ranges <= config.ground_max_distance_m)
    count = near.sum(axis=1)
    reasons = first_reason([(~seen.any(axis=1), "no-ankles"), (np.full(n, cam_height <= 0), "camera-below-road"),
                            (~hits.any(axis=1), "above-horizon"), (count == 0, "beyond-range")], n)
    if not (count > 0).any():
        return CueEstimate(NAME, np.zeros((n, 2)), np.tile(np.eye(2), (n, 1, 1)), np.zeros(n, bool), reasons)
    weight = near / np.maximum(count, 1)[:, None]
    xy = np.einsum("na,nac->nc", weight, points[..., :2])

    # pixel noise through the Jacobian of the intersection: with the unnormalized ray
    # g = M (u, v, 1) (M = R K^-1) the point is o + h g / (-n.g), so
    # dp/du = h (g (n.M_u) - M_u (n.g)) / (n.g)^2, and likewise for v.
    m = frame.cam_to_world[:3, :3] @ np.linalg.inv(frame.camera.intrinsics)
    pix = keypoints[:, ankles]
    g = pix[..., 0:1] * m[:, 0] + pix[..., 1:2] * m[:, 1] + m[:, 2]  # (N, 2 ankles, 3)
    ng = g @ normal
    safe = np.where(np.abs(ng) > 1e-12, ng, -1e-12)
    jac = np.stack([(g * float(normal @ m[:, a]) - m[:, a] * ng[..., None])[..., :2] for a in (0, 1)], axis=-1)
    jac = cam_height * jac / (safe**2)[..., None, None]  # (N, 2 ankles, 2 xy, 2 pixel)
    pixel_cov = config.keypoint_pixel_std**2 * np.einsum("naij,nakj->naik", jac, jac)
    cov = np.einsum("na,naij->nij", weight**2, np.where(near[..., None, None], pixel_cov, 0.0))

    # the road's (and the ankle's) unknown height moves the point along the ray
    r = np.linalg.norm(xy - origin[:2], axis=1)
    road_std = config.road_height_std_m + 0.5 * config.road_curvature_std_per_m * r**2
    lift_std = np.where(lone, LONE_ANKLE_FRACTION_STD * config.person_height_mean_m, config.ankle_height_std_m)
    height_var = road_std**2 + lift_std**2
    along = np.einsum("na,nac->nc", weight, rays[:, ankles, :2] / np.where(hits, sine, 1.0)[..., None])
    cov = cov + height_var[:, None, None] * np.einsum("ni,nj->nij", along, along)
    cov = cov + config.lateral_std_m**2 * np.eye(2)  # feet apart, body lean
    return CueEstimate(NAME, xy, cov, count > 0, reasons)
