"""Triangulation cue: the torso keypoints' rays over the track's history, least squares.

Each ray ``o_j + s d_j`` constrains the point ``p`` across itself,
``(I - d_j d_j^T)(p - o_j) = 0``, with a spread of ``range * angle_std`` (pixel noise) plus
``pedestrian_speed_std * age`` (the person may have walked since). The weighted normal
equations give ``p`` and its covariance ``A^-1``, which is wide along the ray when the
rays are close to parallel: the cue weighs itself by the parallax it has. Past rays with
too little baseline or parallax are left out. Outliers: each past ray meets the current
one at some range; the median of those ranges is a robust start, and past rays that miss
it by more than ``outlier_sigma`` are dropped before the least squares. With the ego standing still
no past ray is left and the cue declines.
"""

from __future__ import annotations

import numpy as np

from pedenv.config import FusedConfig
from pedenv.fused.cue import CueEstimate, first_reason, horizontal_bearing, inverse_3x3_symmetric
from pedenv.geometry import closest_points

NAME = "triangulation"
#: The normal matrix must be at least this well conditioned (determinant / (trace / 3)^3).
MIN_CONDITION = 1e-12
#: A triangulated point must lie at least this far ahead of the camera (metres).
MIN_RANGE_M = 0.5


def _solve(rays: np.ndarray, origins: np.ndarray, weights: np.ndarray):
    """Weighted least-squares point of rays: rays (..., J, 3) unit, origins (..., J, 3),
    weights (..., J). With ``A = sum w (I - d d^T)`` and ``b = sum w (o - d (d . o))``
    returns ``(points (..., 3), covariances A^-1 (..., 3, 3), ok (...,))``."""
    sw = weights.sum(axis=-1)
    wd = weights[..., None] * rays
    a = sw[..., None, None] * np.eye(3) - np.einsum("...ja,...jb->...ab", wd, rays)
    b = (weights[..., None] * origins).sum(axis=-2) - np.einsum("...ja,...j->...a", wd, np.sum(rays * origins, axis=-1))
    cov, det = inverse_3x3_symmetric(a)
    scale = (np.trace(a, axis1=-2, axis2=-1) / 3.0) ** 3
    ok = det > MIN_CONDITION * np.maximum(scale, 1e-300)
    cov = np.where(ok[..., None, None], cov, np.eye(3))
    return np.einsum("...ab,...b->...a", cov, b), cov, ok


def triangulation_cue(rays: np.ndarray, usable: np.ndarray, origin: np.ndarray, time: float,
                      past_rays: np.ndarray, past_usable: np.ndarray, past_origins: np.ndarray,
                      past_times: np.ndarray, past_filled: np.ndarray, angle_std: float,
                      config: FusedConfig) -> CueEstimate:
    """Ground point of N pedestrians triangulated from their torso rays now and in the past.

    rays: (N, K, 3) unit, world, now; usable: (N, K) bool. origin: (3,) camera centre now,
    world, metres; time: seconds. past_*: (N, L, ...) the tracks' histories (see
    :class:`~pedenv.fused.history.TrackHistory`). angle_std: pixel noise / focal length
    (radians). Declines with ``no-history``, ``no-baseline``, ``no-parallax`` or ``degenerate``.
    """
    n, k = rays.shape[:2]
    baseline = np.linalg.norm(past_origins - origin, axis=-1)  # (N, L)
    moved = past_filled & (baseline >= config.min_baseline_m)
    cos = np.einsum("nlkc,nkc->nkl", past_rays, rays)
    candidate = (moved[:, None, :] & np.transpose(past_usable, (0, 2, 1)) & usable[..., None]
                 & (cos <= np.cos(config.min_parallax_rad)))  # (N, K, L)
    reasons = first_reason([(~past_filled.any(axis=1), "no-history"), (~moved.any(axis=1), "no-baseline"),
                            (~candidate.any(axis=(1, 2)), "no-parallax")], n)
    if not candidate.any():
        return CueEstimate(NAME, np.zeros((n, 2)), np.tile(np.eye(2), (n, 1, 1)), np.zeros(n, bool), reasons)

    # robust start: the median over past rays of the two-ray range along the current ray
    past_k = np.transpose(past_rays, (0, 2, 1, 3))  # (N, K, L, 3)
    s, _, _, parallel = closest_points(origin, rays[:, :, None], past_origins[:, None], past_k)
    with np.errstate(invalid="ignore"):
        pair_ok = candidate & ~parallel & (s > MIN_RANGE_M)
    ordered = np.sort(np.where(pair_ok, s, np.inf), axis=-1)
    count = pair_ok.sum(axis=-1)
    start = np.take_along_axis(ordered, np.maximum((count - 1) // 2, 0)[..., None], axis=-1)[..., 0]
    has_start = count > 0
    p0 = origin + np.where(has_start, start, 1.0)[..., None] * rays  # (N, K, 3)

    all_rays = np.concatenate([rays[:, :, None], past_k], axis=2)  # (N, K, J, 3)
    all_origins = np.concatenate([np.broadcast_to(origin, (n, 1, 3)), past_origins], axis=1)[:, None]  # (N, 1, J, 3)
    age = np.concatenate([np.zeros((n, 1)), time - past_times], axis=1)[:, None, :]  # (N, 1, J)
    reach = np.linalg.norm(p0[:, :, None] - all_origins, axis=-1)  # (N, K, J)
    var = (reach * angle_std) ** 2 + (config.pedestrian_speed_std_mps * age) ** 2 + 1e-6
    offset = p0[:, :, None] - all_origins
    across = offset - np.sum(offset * all_rays, axis=-1, keepdims=True) * all_rays
    miss = np.linalg.norm(across, axis=-1) / np.sqrt(var)
    keep = np.concatenate([has_start[..., None], pair_ok & (miss[..., 1:] <= config.outlier_sigma)], axis=2)
    keep[..., 0] &= keep[..., 1:].any(axis=-1)  # the current ray needs a past ray besides it
    point, cov, ok = _solve(all_rays, np.broadcast_to(all_origins, offset.shape), keep / var)
    ahead = np.einsum("nka,nka->nk", point - origin, rays) > MIN_RANGE_M
    good_k = ok & ahead & keep[..., 0]  # (N, K)
    count = good_k.sum(axis=1)
    valid = count > 0
    reasons = np.where(valid | (reasons != ""), reasons, "degenerate")
    share = good_k / np.maximum(count, 1)[:, None]
    xy = np.einsum("nk,nkc->nc", share, point[..., :2])
    # the keypoints share the ego's baseline, so their errors move together: mean covariance
    cov_xy = np.einsum("nk,nkab->nab", share, np.where(good_k[..., None, None], cov[..., :2, :2], 0.0))
    cov_xy = cov_xy + config.lateral_std_m**2 * np.eye(2)
    # a walker moves every past ray the same way, so its error does not average out over
    # the rays: a drift of ``speed_std * age`` across the widest-parallax past ray moves
    # the point ``drift / sin(parallax)`` along the current ray
    sin = np.sqrt(np.clip(1.0 - cos**2, 0.0, 1.0))  # (N, K, L)
    widest = np.argmax(np.where(keep[..., 1:], sin, -1.0), axis=-1)[..., None]  # (N, K, 1)
    drift = config.pedestrian_speed_std_mps * np.take_along_axis(age[..., 1:] + 0.0 * sin, widest, -1)[..., 0]
    along_std = drift / np.maximum(np.take_along_axis(sin, widest, -1)[..., 0], 1e-6)  # (N, K)
    along_var = np.einsum("nk,nk->n", share, np.where(good_k, along_std, 0.0) ** 2)
    bearing = horizontal_bearing(np.einsum("nk,nkc->nc", share, rays))
    cov_xy = cov_xy + along_var[:, None, None] * np.einsum("ni,nj->nij", bearing, bearing)
    return CueEstimate(NAME, xy, cov_xy, valid, reasons)
