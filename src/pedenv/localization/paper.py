"""World position of pedestrians, the paper's way (Sec. III-C, Algorithm 1).

1. Initial estimate: each keypoint's viewing ray now and at the track's previous
   observation; the midpoint of their closest points (Eqs. 4-5); points behind a camera
   and the lowest-confidence share of keypoints dropped; the mean is the position.
2. Refinement: a person of the assumed height is re-projected at the current estimate
   and the distance rescaled by ``1 + (h_est / h_orig - 1) / lambda`` with
   ``lambda = r + c`` for ``r = 1..steps``. The paper prints ``* lambda`` in Eq. 7 but
   says the step shrinks as ``r`` grows, which only a division gives; pedenv divides.
   The direction is the mean of the keypoint rays.
3. Degenerate geometry (parallel rays of a standing ego and a standing person, no
   previous observation): the distance comes from the height alone, and the result
   says so in ``sources``. No NaN or inf leaves this module.

All functions are vectorized over N pedestrians of one frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.config import Config, PaperConfig
from pedenv.geometry import closest_points, unit_vectors
from pedenv.localization.base import FrameGeometry, Measurement
from pedenv.tracking.table import ColumnGroup

TRIANGULATION = "triangulation"
HEIGHT_FIRST = "height:first-observation"
HEIGHT_PARALLEL = "height:no-intersection"
#: Rays closer to parallel than this angle (radians) do not intersect: the position falls back
#: to the height-based distance. A numerical guard against dividing by ``sin`` of the angle,
#: not a tuned value (the paper gives none).
MIN_PARALLAX_RAD = 1e-6
#: One position measurement's standard deviation per axis (the Kalman filter's R) is
#: ``MEASUREMENT_STD_M + MEASUREMENT_STD_REL * distance`` metres. The paper gives none: set on
#: the built-in scenes with the filter's other settings (the paper's relative errors, about
#: 16 %, make 0.1 per metre the right order).
MEASUREMENT_STD_M = 0.5
MEASUREMENT_STD_REL = 0.1


@dataclass(frozen=True)
class Sighting:
    """N pedestrians' skeletons at one observation, as rays.

    rays: (N, 17, 3) unit keypoint rays, world frame. centre_rays: (N, 3) unit rays of the
    centre of each skeleton's box (the skeleton's midpoint of the ``midpoint`` ablation).
    confidences: (N, 17). origin: the camera centre, world frame, metres: (3,) for this
    frame, (N, 3) for the tracks' previous observations.
    """

    rays: np.ndarray
    centre_rays: np.ndarray
    confidences: np.ndarray
    origin: np.ndarray


@dataclass(frozen=True)
class Reprojection:
    """What the height refinement projects an upright person with (Eq. 6).

    intrinsics: (3, 3) pixels. world_to_cam: (4, 4) world to camera frame. ground_z: the
    height of the road under the ego, world frame, metres.
    """

    intrinsics: np.ndarray
    world_to_cam: np.ndarray
    ground_z: float


@dataclass(frozen=True)
class PositionEstimate:
    """Positions of N pedestrians in one frame.

    positions: (N, 3) world frame, metres; the ground point under each pedestrian.
    distances: (N,) metres from the camera centre to the body centre.
    directions: (N, 3) unit viewing direction of the body centre, world frame.
    sources: (N,) str, how the distance was found (``triangulation`` or ``height:*``).
    """

    positions: np.ndarray
    distances: np.ndarray
    directions: np.ndarray
    sources: np.ndarray


def keep_most_confident(valid: np.ndarray, confidences: np.ndarray, drop_fraction: float) -> np.ndarray:
    """Mask of the valid keypoints left after dropping the least confident share.

    valid: (N, 17) bool, confidences: (N, 17). Of ``n`` valid keypoints of a person the
    ``floor(drop_fraction * n)`` least confident are dropped; among equal confidences
    (exact skeletons all have 1) the lowest COCO indices go first, as an ascending
    stable sort does.
    """
    score = np.where(valid, confidences, -np.inf)
    rank = np.argsort(np.argsort(score, axis=1, kind="stable"), axis=1, kind="stable")
    n_valid = valid.sum(axis=1)
    first_kept = (valid.shape[1] - n_valid) + np.floor(drop_fraction * n_valid + 1e-9)
    return valid & (rank >= first_kept[:, None])


def initial_positions(rays: np.ndarray, origin: np.ndarray, prev_rays: np.ndarray, prev_origins: np.ndarray,
                      usable: np.ndarray, confidences: np.ndarray,
                      config: PaperConfig) -> tuple[np.ndarray, np.ndarray]:
    """Initial 3D body-centre estimate from two observations (Eqs. 3-5).

    rays, prev_rays: (N, K, 3) unit rays, world frame (K = 17, or 1 for the midpoint
    ablation). origin: (3,) camera centre now; prev_origins: (N, 3) at the previous
    observation. usable: (N, K) bool, keypoints seen in both frames. confidences: (N, K).
    Returns ``(centres (N, 3), ok (N,) bool)``; rows with ``ok`` False are undefined.
    """
    s, t, mid, parallel = closest_points(origin, rays, prev_origins[:, None, :], prev_rays,
                                         min_sin=np.sin(MIN_PARALLAX_RAD))
    with np.errstate(invalid="ignore"):
        valid = usable & ~parallel & (s > 0) & (t > 0) & (s < config.max_distance_m) & (t < config.max_distance_m)
    keep = keep_most_confident(valid, confidences, config.low_confidence_fraction)
    count = keep.sum(axis=1)
    total = np.where(keep[..., None], np.nan_to_num(mid), 0.0).sum(axis=1)
    ok = count > 0
    return total / np.maximum(count, 1)[:, None], ok


def refine_distance(distances: np.ndarray, directions: np.ndarray, origin: np.ndarray, pixel_heights: np.ndarray,
                    camera: Reprojection, config: PaperConfig, lambdas: np.ndarray | None = None) -> np.ndarray:
    """Rescale distances so the re-projected person height meets the skeleton's (Eq. 7).

    distances: (N,) metres along ``directions`` (N, 3) from ``origin`` (3,).
    pixel_heights: (N,) the skeletons' heights in pixels. ``lambdas``: the step
    divisors, (S,) or per pedestrian (S, N); by default ``r + c`` for ``r = 1..steps``.
    Returns the refined (N,) distances, kept within [0.1 m, ``max_distance_m``].

    Each step re-projects an upright person of ``person_height_m`` standing under the
    point ``origin + d * direction`` (bottom at ``camera.ground_z``, Eq. 6) and compares its pixel
    height with the skeleton's. The bottom and top points are linear in the distance
    ``d`` (``a + d b`` in the camera frame), so each step is a handful of operations on
    precomputed (4, N) arrays.
    """
    if lambdas is None:
        lambdas = np.arange(1, config.refinement_steps + 1) + config.refinement_lambda_offset
    r, t, intrinsics = camera.world_to_cam[:3, :3], camera.world_to_cam[:3, 3], camera.intrinsics
    base = np.array([origin[0], origin[1], camera.ground_z])
    slope = np.column_stack([directions[:, 0], directions[:, 1], np.zeros(len(directions))])
    a = np.broadcast_to(intrinsics @ (r @ base + t), (len(directions), 3))  # bottom at d = 0, homogeneous px
    b = (slope @ r.T) @ intrinsics.T             # (N, 3) its change per metre
    up = intrinsics @ (r @ np.array([0.0, 0.0, config.person_height_m]))  # (3,) bottom -> top
    num0 = np.stack([a[:, 0], a[:, 1], a[:, 0] + up[0], a[:, 1] + up[1]])
    num1 = np.stack([b[:, 0], b[:, 1], b[:, 0], b[:, 1]])
    den0 = np.stack([a[:, 2], a[:, 2], a[:, 2] + up[2], a[:, 2] + up[2]])
    den1 = np.stack([b[:, 2], b[:, 2], b[:, 2], b[:, 2]])
    d = np.clip(distances, 0.1, config.max_distance_m)
    inv_h = 1.0 / pixel_heights
    for lam in lambdas:
        den = den0 + d * den1
        px = (num0 + d * num1) / den
        h_est = np.hypot(px[2] - px[0], px[3] - px[1])
        # d * (1 + (h_est / h_orig - 1) / lam), written with fewer array operations
        d = d * (h_est * (inv_h / lam) + (1.0 - 1.0 / lam))
        np.clip(d, 0.1, config.max_distance_m, out=d)
    return np.clip(d, 0.1, config.max_distance_m)


#: Full steps (``lambda = 1``) that take the pinhole start to the height-based distance.
FALLBACK_STEPS = 6


def pinhole_distance(pixel_heights: np.ndarray, intrinsics: np.ndarray, config: PaperConfig) -> np.ndarray:
    """``f * H / h``: the distance of an upright person ``h`` pixels tall, camera level (N,)."""
    start = intrinsics[1, 1] * config.person_height_m / np.maximum(pixel_heights, 1.0)
    return np.clip(start, 0.5, config.max_distance_m)


def mean_directions(rays: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Unit mean (N, 3) of the rays (N, K, 3) under ``mask`` (N, K); all rays where none."""
    mask = mask | ~mask.any(axis=1, keepdims=True)
    return unit_vectors(np.where(mask[..., None], rays, 0.0).sum(axis=1))


def pixel_heights(keypoints: np.ndarray, seen: np.ndarray) -> np.ndarray:
    """Height (N,) in pixels of each skeleton's box over its seen keypoints (at least 1 px)."""
    v = keypoints[..., 1]
    top = np.where(seen, v, np.inf).min(axis=1)
    bottom = np.where(seen, v, -np.inf).max(axis=1)
    return np.where(seen.any(axis=1), np.maximum(bottom - top, 1.0), 1.0)


def estimate_positions(now: Sighting, heights_px: np.ndarray, previous: Sighting, has_prev: np.ndarray,
                       camera: Reprojection, config: PaperConfig) -> PositionEstimate:
    """The paper's position of N pedestrians seen in this frame (Algorithm 1).

    now: this frame's skeletons (camera centre (3,)); previous: each track's previous
    observation (camera centres (N, 3)), used where ``has_prev`` (N,) bool.
    heights_px: (N,) skeleton heights in pixels.
    """
    rays, origin = now.rays, now.origin
    n = len(rays)
    seen = now.confidences > 0
    kept = keep_most_confident(seen, now.confidences, config.low_confidence_fraction)
    directions = mean_directions(rays, kept)
    centres = origin + directions  # placeholder row values, replaced below
    ok = np.zeros(n, bool)
    if has_prev.any():
        idx = np.flatnonzero(has_prev)
        if config.initial_estimate == "midpoint":
            here, before = now.centre_rays[idx, None], previous.centre_rays[idx, None]
            usable, conf = np.ones((len(idx), 1), bool), np.ones((len(idx), 1))
        else:
            here, before = rays[idx], previous.rays[idx]
            usable, conf = seen[idx] & (previous.confidences[idx] > 0), now.confidences[idx]
        c, good = initial_positions(here, origin, before, previous.origin[idx], usable, conf, config)
        centres[idx[good]] = c[good]
        ok[idx[good]] = True
    distances = np.linalg.norm(centres - origin, axis=1)
    if not config.refine:
        # The initial estimate as it is: its own direction, no height prior.
        directions = np.where(ok[:, None], (centres - origin) / np.maximum(distances, 1e-9)[:, None], directions)
    if config.refine or not ok.all():
        # One pass for both kinds of rows: the refinement's steps where the rays met, full
        # height-prior steps where they did not (``inf`` leaves a row as it is).
        steps = max(config.refinement_steps, FALLBACK_STEPS)
        r = np.arange(1, steps + 1)[:, None]
        refine = np.where(r <= config.refinement_steps, r + config.refinement_lambda_offset, np.inf)
        fallback = np.where(r <= FALLBACK_STEPS, 1.0, np.inf)
        lambdas = np.where(ok, refine if config.refine else np.inf, fallback)
        start = np.where(ok, distances, pinhole_distance(heights_px, camera.intrinsics, config))
        distances = refine_distance(start, directions, origin, heights_px, camera, config, lambdas=lambdas)
    sources = np.where(ok, TRIANGULATION, np.where(has_prev, HEIGHT_PARALLEL, HEIGHT_FIRST))
    positions = origin + distances[:, None] * directions
    positions[:, 2] = camera.ground_z
    return PositionEstimate(positions, distances, directions, sources)


def keypoints_on_plane(
    rays: np.ndarray, origin: np.ndarray, directions: np.ndarray, distances: np.ndarray
) -> np.ndarray:
    """3D skeleton (N, 17, 3): each keypoint ray (N, 17, 3) cut by the plane through the
    body centre ``origin + distance * direction`` facing the camera. World frame, metres."""
    cos = np.einsum("nkc,nc->nk", rays, directions)
    depth = distances[:, None] / np.maximum(cos, 1e-3)
    return origin + depth[..., None] * rays


class PaperMemory(ColumnGroup):
    """Each track's previous observation (the paper's method intersects two frames):
    keypoint rays ``rays (T, 17, 3)`` and box-centre rays ``centre_rays (T, 3)`` (unit,
    world), ``confidences (T, 17)``, camera centres ``origins (T, 3)`` (world, metres) and
    ``seen (T,)``, the track has a previous observation."""

    rays: np.ndarray
    centre_rays: np.ndarray
    confidences: np.ndarray
    origins: np.ndarray
    seen: np.ndarray

    def __init__(self) -> None:
        super().__init__({"rays": ((17, 3), np.float64), "centre_rays": ((3,), np.float64),
                          "confidences": ((17,), np.float64), "origins": ((3,), np.float64), "seen": ((), bool)})


class PaperLocator:
    """The paper's two-frame intersection with height refinement (Algorithm 1).

    Its memory (``columns``) is each track's previous observation (:class:`PaperMemory`).
    Its measurement covariance is isotropic:
    ``(MEASUREMENT_STD_M + MEASUREMENT_STD_REL * distance)^2`` per axis
    (:data:`MEASUREMENT_STD_M`, :data:`MEASUREMENT_STD_REL`); the paper gives none.
    """

    #: A person with no seen keypoint cannot be placed (the box alone put them 479-500 m
    #: away): the model leaves them out (see :class:`~pedenv.localization.base.Locator`).
    requires_keypoints = True

    def __init__(self, config: Config) -> None:
        self.config = config.paper
        self.max_range_m = config.paper.max_distance_m  # the model clamps beyond (pedenv.localization.bounds)
        self.columns = PaperMemory()

    def locate(self, geo: FrameGeometry, rows: np.ndarray) -> Measurement:
        det, frame, mem, cfg = geo.detections, geo.frame, self.columns, self.config
        now = Sighting(geo.rays, geo.centre_rays, det.confidences, geo.origin)
        previous = Sighting(mem.rays[rows], mem.centre_rays[rows], mem.confidences[rows], mem.origins[rows])
        camera = Reprojection(frame.camera.intrinsics, geo.world_to_cam, float(frame.ego.translation[2]))
        est = estimate_positions(now, pixel_heights(det.keypoints, det.confidences > 0), previous, mem.seen[rows],
                                 camera, cfg)
        mem.rays[rows], mem.centre_rays[rows], mem.confidences[rows] = geo.rays, geo.centre_rays, det.confidences
        mem.origins[rows], mem.seen[rows] = geo.origin, True
        var = (MEASUREMENT_STD_M + MEASUREMENT_STD_REL * est.distances) ** 2
        skeleton = keypoints_on_plane(geo.rays, geo.origin, est.directions, est.distances)
        return Measurement(est.positions, var[:, None, None] * np.eye(2), est.sources, skeleton)
