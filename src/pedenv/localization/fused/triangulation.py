"""Triangulation over the track's history: each keypoint's rays now and in the past,
least squares; the torso keypoints make the triangulation cue, all 17 the 3D skeleton.

Each ray ``o_j + s d_j`` constrains the point ``p`` across itself,
``(I - d_j d_j^T)(p - o_j) = 0``, with a spread of ``range * angle_std`` (pixel noise).
The weighted normal equations give ``p`` and its covariance ``A^-1``, which is wide along
the ray when the rays are close to parallel: the estimate weighs itself by the parallax
it has. Past rays with too little baseline or parallax are left out. Outliers: the start
is the track's last fused range along the current ray; past rays that miss it by more
than :data:`OUTLIER_SIGMA` times their spread plus ``pedestrian_speed_std * age`` (the person
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

from pedenv.localization.fused.cue import (
    LATERAL_STD_M,
    REASON_CODE,
    CueEstimate,
    FrameSkeletons,
    first_reason,
    horizontal_bearing,
    symmetric_2x2,
)
from pedenv.localization.fused.history import TORSO_KEYPOINTS, HistoryView

NAME = "triangulation"
#: The normal matrix must be at least this well conditioned (determinant / (trace / 3)^3).
MIN_CONDITION = 1e-12
#: A triangulated point must lie at least this far ahead of the camera (metres).
MIN_RANGE_M = 0.5
#: Variance floor of a ray's miss distance (m^2), so a ray through the start keeps a finite weight.
MIN_RAY_VARIANCE = 1e-6
#: Floor of a kept past ray's squared sine of parallax (it is at least :data:`MIN_PARALLAX_RAD`).
MIN_SINE2 = 1e-12
#: A past camera centre closer than this (metres) to the current one gives no ray: the ego
#: stands still (the keypoints' pixel noise then dominates any parallax).
MIN_BASELINE_M = 0.3
#: Past rays closer to parallel than this (radians) with the current one are left out.
MIN_PARALLAX_RAD = 0.01
#: How fast (m/s, 1 sigma) a pedestrian may have moved since a past observation: widens old
#: rays so a walker does not bias the cue (about half a walking speed; built-in scenes).
PEDESTRIAN_SPEED_STD_MPS = 0.8
#: A past ray whose miss of the start exceeds this many of its standard deviations is dropped
#: (3 sigma: a Gaussian ray is kept 99.7 % of the time).
OUTLIER_SIGMA = 3.0


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


def _solve_3x3(s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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


@dataclass(frozen=True)
class RaysNow:
    """This frame's keypoint rays of N pedestrians, as triangulation uses them.

    rays: (N, K, 3) unit, world. terms: (N, K, 9) their least-squares terms
    (:func:`~pedenv.localization.fused.history.ray_terms`). usable: (N, K) bool.
    origin: (3,) camera centre, world, metres. time: seconds. angle_std: keypoint noise,
    radians, scalar or (N,) per person.
    """

    rays: np.ndarray
    terms: np.ndarray
    usable: np.ndarray
    origin: np.ndarray
    time: float
    angle_std: float | np.ndarray


def triangulate(now: RaysNow, start: np.ndarray, has_start: np.ndarray, past: HistoryView) -> Triangulated:
    """Triangulate N pedestrians' K keypoints from their rays now and in the past.

    start: (N, K, 3) world, metres, where each keypoint is believed to be (outlier test);
    has_start: (N,) bool. past: the tracks' histories
    (:meth:`~pedenv.localization.fused.history.TrackHistory.of`). Reasons: ``no-history``,
    ``no-baseline``, ``unplaced``, ``no-parallax``, ``degenerate``.
    """
    n, k = now.usable.shape
    moved = past.filled & (((past.centres - now.origin) ** 2).sum(-1) >= MIN_BASELINE_M**2)  # (N, L)
    both = np.empty((n, k, 3, 2))
    both[..., 0], both[..., 1] = now.rays, start
    dots = past.rays @ both  # (N, K, L, 2): each past ray . the current ray, . the start
    cos = dots[..., 0]
    candidate = (moved[:, None, :] & past.usable & (now.usable & has_start[:, None])[..., None]
                 & (cos <= np.cos(MIN_PARALLAX_RAD)))
    nothing = ~candidate.any(axis=(1, 2))
    reasons = first_reason([(~past.filled.any(axis=1), "no-history"), (~moved.any(axis=1), "no-baseline"),
                            (~has_start, "unplaced"), (nothing, "no-parallax")], n)
    if nothing.all():
        return Triangulated(np.zeros((n, k, 3)), np.zeros((n, k, 3)), np.zeros((n, k)), np.zeros((n, k), bool), reasons)
    age = now.time - past.times  # (N, L)
    keep, weight, w_now, any_kept = ray_weights(now, start, past, candidate, dots[..., 1], age)
    summed = (weight[..., None, :] @ past.terms)[..., 0, :] + w_now[..., None] * now.terms
    points, cov, ok = _solve_3x3(summed)
    ahead = ((points - now.origin) * now.rays).sum(-1) > MIN_RANGE_M
    good = ok & ahead & any_kept
    drift_var = walker_drift(keep, cos, age, good, PEDESTRIAN_SPEED_STD_MPS)
    reasons = np.where((reasons == 0) & ~good.any(axis=1), REASON_CODE["degenerate"], reasons)
    return Triangulated(points, cov, drift_var, good, reasons)


def ray_weights(now: RaysNow, start: np.ndarray, past: HistoryView, candidate: np.ndarray, start_dots: np.ndarray,
                age: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The past rays that pass the outlier test and the least-squares weights.

    candidate: (N, K, L) bool, past rays with baseline and parallax. start_dots: (N, K, L)
    each past ray . the start. age: (N, L) seconds. Returns ``(keep (N, K, L) bool,
    weights (N, K, L) 1/m^2, the current ray's weights (N, K) 1/m^2, any kept (N, K) bool)``.
    """
    n = len(start)
    # each past ray's spread at the start, and how far it misses the start
    reach2 = (start**2).sum(-1)[..., None] - 2.0 * (start @ past.centres.transpose(0, 2, 1)) + past.centres_sq[:, None]
    along = start_dots - past.dots
    angle_var = np.broadcast_to(np.asarray(now.angle_std, float) ** 2, (n,))[:, None]
    pixel_var = reach2 * angle_var[..., None] + MIN_RAY_VARIANCE
    var = pixel_var + ((PEDESTRIAN_SPEED_STD_MPS * age) ** 2)[:, None, :]
    keep = candidate & (reach2 - along**2 <= OUTLIER_SIGMA**2 * var)
    weight = np.where(keep, 1.0 / pixel_var, 0.0)
    any_kept = weight.sum(axis=-1) > 0  # (N, K) the current ray needs a past ray besides it
    reach_now2 = ((start - now.origin) ** 2).sum(-1)
    w_now = np.where(any_kept, 1.0 / (reach_now2 * angle_var + MIN_RAY_VARIANCE), 0.0)
    return keep, weight, w_now, any_kept


def walker_drift(keep: np.ndarray, cos: np.ndarray, age: np.ndarray, good: np.ndarray, speed_std: float) -> np.ndarray:
    """(N, K) m^2 the walker's drift along the current ray, at the kept past ray that pins
    the range best against it: the person's, measured at the torso and shared by every
    keypoint; inf for a keypoint triangulated without the torso, 0 where none was.

    keep: (N, K, L) bool kept past rays; cos: (N, K, L) their angle to the current ray;
    age: (N, L) seconds; good: (N, K) bool triangulated; speed_std: m/s.
    """
    t_keep, t_cos = keep[:, TORSO_KEYPOINTS], cos[:, TORSO_KEYPOINTS]
    ratio2 = np.where(t_keep, (age**2)[:, None, :] / np.maximum(1.0 - t_cos**2, MIN_SINE2), np.inf).min(axis=-1)
    torso = good[:, TORSO_KEYPOINTS]
    person = (np.where(torso, ratio2, 0.0).sum(1) / np.maximum(torso.sum(1), 1))[:, None]
    return np.where(good & torso.any(1)[:, None], speed_std**2 * person, np.where(good, np.inf, 0.0))


def triangulation_cue(tri: Triangulated, skeletons: FrameSkeletons) -> CueEstimate:
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
    lat = LATERAL_STD_M**2  # the body's own spread about its ground point: the person's
    frame_cov = symmetric_2x2(cov[:, 0], cov[:, 1], cov[:, 2])
    drift = (share * tri.drift_var[:, TORSO_KEYPOINTS]).sum(axis=1)
    bearing = horizontal_bearing((share[..., None] * skeletons.rays[:, TORSO_KEYPOINTS]).sum(axis=1))
    bx, by = bearing[:, 0], bearing[:, 1]
    bias = symmetric_2x2(drift * bx * bx + lat, drift * bx * by, drift * by * by + lat)
    reasons = np.where(valid, 0, np.where(tri.reasons == 0, REASON_CODE["degenerate"], tri.reasons))
    return CueEstimate(NAME, xy, frame_cov, bias, valid, reasons)
