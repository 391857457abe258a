"""Triangulation over the track's history: each keypoint's rays now and in the past,
least squares; the torso keypoints make the triangulation cue, all 17 the 3D skeleton.

Each ray ``o_j + s d_j`` constrains the point ``p`` across itself,
``(I - d_j d_j^T)(p - o_j) = 0``, with a spread of ``range * angle_std`` (pixel noise).
The weighted normal equations give ``p`` and its covariance ``A^-1``, which is wide along
the ray when the rays are close to parallel: the estimate weighs itself by the parallax
it has. Past rays with too little baseline or parallax are left out. Outliers: the start
is the track's last fused range along the current ray; past rays that miss it by more
than ``outlier_sigma`` times their spread plus ``pedestrian_speed_std * age`` (the person
may have walked since) are dropped before the least squares. With the ego standing still
no past ray is left and the cue declines.

A walker moves every past ray the same way, so that error does not average out over the
rays, nor over the frames: a drift of ``speed_std * age`` across a past ray at parallax
``a`` moves the point ``drift / sin(a)`` along the current ray, and it is the cue's
per-person covariance; the pixel noise is its frame-to-frame one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.config import FusedConfig
from pedenv.localization.fused.cue import (
    REASON_CODE,
    CueEstimate,
    FrameSkeletons,
    first_reason,
    horizontal_bearing,
    symmetric_2x2,
)
from pedenv.localization.fused.history import CENTRE, CENTRE_SQ, TIME, TORSO_KEYPOINTS

NAME = "triangulation"
#: The normal matrix must be at least this well conditioned (determinant / (trace / 3)^3).
MIN_CONDITION = 1e-12
#: A triangulated point must lie at least this far ahead of the camera (metres).
MIN_RANGE_M = 0.5
#: Variance floor of a ray's miss distance (m^2), so a ray through the start keeps a finite weight.
MIN_RAY_VARIANCE = 1e-6
#: Floor of a kept past ray's squared sine of parallax (it is at least ``min_parallax_rad``).
MIN_SINE2 = 1e-12


@dataclass(frozen=True)
class Triangulated:
    """N pedestrians' K keypoints triangulated over their history.

    points: (N, K, 3) world, metres. covariances: (N, K, 3) m^2, components (xx, xy, yy)
    of the x-y covariance from the pixel noise. drift_var: (N, K) m^2, the walker's drift
    along the current ray. good: (N, K) bool, the keypoint was triangulated.
    reasons: (N,) int, why no keypoint was (codes of :data:`~pedenv.localization.fused.cue.REASONS`).
    """

    points: np.ndarray
    covariances: np.ndarray
    drift_var: np.ndarray
    good: np.ndarray
    reasons: np.ndarray


def _solve_3x3(s: np.ndarray):
    """Solve the normal equations from summed features (..., 9): the upper triangle of A
    (6) then b (3). Returns ``(points (..., 3), x-y covariance components (..., 3), ok (...,))``."""
    a, b, c, d, e, f = (s[..., i] for i in range(6))
    c00, c01, c02 = d * f - e * e, c * e - b * f, b * e - c * d
    c11, c12, c22 = a * f - c * c, b * c - a * e, a * d - b * b
    det = a * c00 + b * c01 + c * c02
    ok = det > MIN_CONDITION * np.maximum(((a + d + f) / 3.0) ** 3, 1e-300)
    inv = 1.0 / np.where(ok, det, 1.0)
    rx, ry, rz = s[..., 6], s[..., 7], s[..., 8]
    points = np.empty(s.shape[:-1] + (3,))
    points[..., 0] = (c00 * rx + c01 * ry + c02 * rz) * inv
    points[..., 1] = (c01 * rx + c11 * ry + c12 * rz) * inv
    points[..., 2] = (c02 * rx + c12 * ry + c22 * rz) * inv
    cov = np.empty(s.shape[:-1] + (3,))
    cov[..., 0], cov[..., 1], cov[..., 2] = c00 * inv, c01 * inv, c11 * inv
    return points, cov, ok


def triangulate(rays: np.ndarray, terms: np.ndarray, usable: np.ndarray, origin: np.ndarray, time: float,
                start: np.ndarray, has_start: np.ndarray, past_rays: np.ndarray, past_terms: np.ndarray,
                past_dots: np.ndarray, past_usable: np.ndarray, cameras: np.ndarray, filled: np.ndarray,
                angle_std: float | np.ndarray, config: FusedConfig) -> Triangulated:
    """Triangulate N pedestrians' K keypoints from their rays now and in the past.

    rays: (N, K, 3) unit, world, now; terms: (N, K, 9) their least-squares terms
    (:func:`~pedenv.localization.fused.history.ray_terms`); usable: (N, K) bool.
    origin: (3,) camera centre now, world, metres; time: seconds.
    start: (N, K, 3) world, metres, where each keypoint is believed to be (outlier test);
    has_start: (N,) bool. past_rays, past_terms, past_dots, past_usable, cameras, filled:
    the tracks' histories (N, K, L, 3), (N, K, L, 9), (N, K, L), (N, K, L), (N, L, 5), (N, L)
    (see :class:`~pedenv.localization.fused.history.TrackHistory`).
    angle_std: keypoint noise (radians), scalar or (N,) per person. Reasons: ``no-history``,
    ``no-baseline``, ``unplaced``, ``no-parallax``, ``degenerate``.
    """
    n, k = usable.shape
    d_now = rays
    centres = cameras[..., CENTRE]  # (N, L, 3)
    offset = centres - origin
    moved = filled & ((offset**2).sum(-1) >= config.min_baseline_m**2)  # (N, L)
    both = np.empty((n, k, 3, 2))
    both[..., 0], both[..., 1] = d_now, start
    dots = past_rays @ both  # (N, K, L, 2): each past ray . the current ray, . the start
    cos = dots[..., 0]
    candidate = (moved[:, None, :] & past_usable & (usable & has_start[:, None])[..., None]
                 & (cos <= np.cos(config.min_parallax_rad)))
    nothing = ~candidate.any(axis=(1, 2))
    reasons = first_reason([(~filled.any(axis=1), "no-history"), (~moved.any(axis=1), "no-baseline"),
                            (~has_start, "unplaced"), (nothing, "no-parallax")], n)
    if nothing.all():
        return Triangulated(np.zeros((n, k, 3)), np.zeros((n, k, 3)), np.zeros((n, k)), np.zeros((n, k), bool), reasons)

    # each past ray's spread at the start, and how far it misses the start
    age = time - cameras[..., TIME]  # (N, L)
    reach2 = ((start**2).sum(-1)[..., None] - 2.0 * (start @ centres.transpose(0, 2, 1))
              + cameras[:, None, :, CENTRE_SQ])
    along = dots[..., 1] - past_dots
    angle_var = np.broadcast_to(np.asarray(angle_std, float) ** 2, (n,))[:, None]
    pixel_var = reach2 * angle_var[..., None] + MIN_RAY_VARIANCE
    var = pixel_var + ((config.pedestrian_speed_std_mps * age) ** 2)[:, None, :]
    keep = candidate & (reach2 - along**2 <= config.outlier_sigma**2 * var)
    weight = np.where(keep, 1.0 / pixel_var, 0.0)
    any_kept = weight.sum(axis=-1) > 0  # (N, K) the current ray needs a past ray besides it
    reach_now2 = ((start - origin) ** 2).sum(-1)
    w_now = np.where(any_kept, 1.0 / (reach_now2 * angle_var + MIN_RAY_VARIANCE), 0.0)
    summed = (weight[..., None, :] @ past_terms)[..., 0, :] + w_now[..., None] * terms
    points, cov, ok = _solve_3x3(summed)
    ahead = ((points - origin) * d_now).sum(-1) > MIN_RANGE_M
    good = ok & ahead & any_kept
    # the walker's drift, at the past ray that pins the range best against it
    # the walker's drift is the person's: measured at the torso, shared by every keypoint
    t_keep, t_cos = keep[:, TORSO_KEYPOINTS], cos[:, TORSO_KEYPOINTS]
    ratio2 = np.where(t_keep, (age**2)[:, None, :] / np.maximum(1.0 - t_cos**2, MIN_SINE2), np.inf).min(axis=-1)
    torso = good[:, TORSO_KEYPOINTS]
    person = (np.where(torso, ratio2, 0.0).sum(1) / np.maximum(torso.sum(1), 1))[:, None]
    # a keypoint triangulated without the torso has no drift measure: infinitely loose
    drift_var = np.where(good & torso.any(1)[:, None], config.pedestrian_speed_std_mps**2 * person,
                         np.where(good, np.inf, 0.0))
    reasons = np.where((reasons == 0) & ~good.any(axis=1), REASON_CODE["degenerate"], reasons)
    return Triangulated(points, cov, drift_var, good, reasons)


def triangulation_cue(tri: Triangulated, skeletons: FrameSkeletons, config: FusedConfig) -> CueEstimate:
    """Ground point of N pedestrians: the mean x-y of their triangulated torso keypoints.

    tri: the triangulation of all 17 keypoints (:func:`triangulate`). The keypoints share
    the ego's baseline, so their errors move together: the covariance is their mean.
    """
    good = tri.good[:, TORSO_KEYPOINTS]
    count = good.sum(axis=1)
    valid = count > 0
    if not valid.any():
        return CueEstimate.declined(NAME, tri.reasons)
    share = good / np.maximum(count, 1)[:, None]  # (N, 4)
    xy = (share[..., None] * np.where(good[..., None], tri.points[:, TORSO_KEYPOINTS, :2], 0.0)).sum(axis=1)
    cov = (share[..., None] * np.where(good[..., None], tri.covariances[:, TORSO_KEYPOINTS], 0.0)).sum(axis=1)
    lat = config.lateral_std_m**2  # the body's own spread about its ground point: the person's
    frame_cov = symmetric_2x2(cov[:, 0], cov[:, 1], cov[:, 2])
    drift = (share * tri.drift_var[:, TORSO_KEYPOINTS]).sum(axis=1)
    bearing = horizontal_bearing((share[..., None] * skeletons.rays[:, TORSO_KEYPOINTS]).sum(axis=1))
    bx, by = bearing[:, 0], bearing[:, 1]
    bias = symmetric_2x2(drift * bx * bx + lat, drift * bx * by, drift * by * by + lat)
    reasons = np.where(valid, 0, np.where(tri.reasons == 0, REASON_CODE["degenerate"], tri.reasons))
    return CueEstimate(NAME, xy, frame_cov, bias, valid, reasons)
