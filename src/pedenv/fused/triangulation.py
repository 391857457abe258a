"""Triangulation cue: the torso keypoints' rays over the track's history, least squares.

Each ray ``o_j + s d_j`` constrains the point ``p`` across itself,
``(I - d_j d_j^T)(p - o_j) = 0``, with a spread of ``range * angle_std`` (pixel noise) plus
``pedestrian_speed_std * age`` (the person may have walked since). The weighted normal
equations give ``p`` and its covariance ``A^-1``, which is wide along the ray when the
rays are close to parallel: the cue weighs itself by the parallax it has. Past rays with
too little baseline or parallax are left out, rays that miss the solution by more than
``outlier_sigma`` are dropped and the system solved again. With the ego standing still
no past ray is left and the cue declines.
"""

from __future__ import annotations

import numpy as np

from pedenv.config import FusedConfig
from pedenv.fused.cue import CueEstimate, first_reason

NAME = "triangulation"
#: The normal matrix must be at least this well conditioned (smallest / largest eigenvalue).
MIN_CONDITION = 1e-10


def _solve(projectors: np.ndarray, origins: np.ndarray, weights: np.ndarray):
    """Weighted least-squares point of rays: projectors (..., J, 3, 3), origins (..., J, 3),
    weights (..., J). Returns ``(points (..., 3), covariances (..., 3, 3), ok (...,))``."""
    a = np.einsum("...j,...jab->...ab", weights, projectors)
    b = np.einsum("...j,...jab,...jb->...a", weights, projectors, origins)
    eig = np.linalg.eigvalsh(a)
    ok = eig[..., 0] > MIN_CONDITION * np.maximum(eig[..., -1], 1e-300)
    a = np.where(ok[..., None, None], a, np.eye(3))
    cov = np.linalg.inv(a)
    return np.einsum("...ab,...b->...a", cov, b), cov, ok


def triangulation_cue(rays: np.ndarray, usable: np.ndarray, origin: np.ndarray, time: float,
                      past_rays: np.ndarray, past_usable: np.ndarray, past_origins: np.ndarray,
                      past_times: np.ndarray, past_filled: np.ndarray, prior_range: np.ndarray,
                      angle_std: float, config: FusedConfig) -> CueEstimate:
    """Ground point of N pedestrians triangulated from their torso rays now and in the past.

    rays: (N, K, 3) unit, world, now; usable: (N, K) bool. origin: (3,) camera centre now,
    world, metres; time: seconds. past_*: (N, L, ...) the tracks' histories (see
    :class:`~pedenv.fused.history.TrackHistory`). prior_range: (N,) metres, a rough range
    that scales the pixel noise. angle_std: pixel noise / focal length (radians).
    Declines with ``no-history``, ``no-baseline``, ``no-parallax`` or ``degenerate``.
    """
    n = len(rays)
    baseline = np.linalg.norm(past_origins - origin, axis=-1)  # (N, L)
    moved = past_filled & (baseline >= config.min_baseline_m)
    cos = np.einsum("nlkc,nkc->nlk", past_rays, rays)
    candidate = moved[..., None] & past_usable & usable[:, None, :] & (cos <= np.cos(config.min_parallax_rad))
    reasons = first_reason([(~past_filled.any(axis=1), "no-history"), (~moved.any(axis=1), "no-baseline"),
                            (~candidate.any(axis=(1, 2)), "no-parallax")], n)
    if not candidate.any():
        return CueEstimate(NAME, np.zeros((n, 2)), np.tile(np.eye(2), (n, 1, 1)), np.zeros(n, bool), reasons)

    all_rays = np.concatenate([rays[:, None], past_rays], axis=1)  # (N, J, K, 3)
    all_origins = np.concatenate([np.broadcast_to(origin, (n, 1, 3)), past_origins], axis=1)  # (N, J, 3)
    age = np.concatenate([np.zeros((n, 1)), time - past_times], axis=1)  # (N, J)
    var = (prior_range[:, None] * angle_std) ** 2 + (config.pedestrian_speed_std_mps * age) ** 2 + 1e-6
    mask = np.concatenate([usable[:, None], candidate], axis=1)  # (N, J, K)
    mask[:, 0] &= candidate.any(axis=1)  # a keypoint needs a past ray besides the current one
    proj = np.eye(3) - np.einsum("njka,njkb->nkjab", all_rays, all_rays)  # (N, K, J, 3, 3)
    origins_k = np.broadcast_to(all_origins[:, None], (n, rays.shape[1]) + all_origins.shape[1:])
    weights = np.transpose(mask, (0, 2, 1)) / var[:, None, :]  # (N, K, J)
    for _ in range(2):  # solve, drop past rays that miss by more than outlier_sigma, solve again
        point, cov, ok = _solve(proj, origins_k, weights)
        miss = np.linalg.norm(np.einsum("nkjab,nkjb->nkja", proj, point[:, :, None] - origins_k), axis=-1)
        outlier = miss > config.outlier_sigma * np.sqrt(var)[:, None, :]
        outlier[..., 0] = False
        weights = np.where(outlier, 0.0, weights)
    point, cov, ok = _solve(proj, origins_k, weights)
    ahead = np.einsum("nka,nka->nk", point - origin, rays) > 0
    good_k = ok & ahead & (weights[..., 1:] > 0).any(axis=-1)  # (N, K)
    count = good_k.sum(axis=1)
    valid = count > 0
    reasons = np.where(valid | (reasons != ""), reasons, "degenerate")
    share = good_k / np.maximum(count, 1)[:, None]
    xy = np.einsum("nk,nkc->nc", share, point[..., :2])
    # the keypoints share the ego's baseline, so their errors move together: mean covariance
    cov_xy = np.einsum("nk,nkab->nab", share, np.where(good_k[..., None, None], cov[..., :2, :2], 0.0))
    cov_xy = cov_xy + config.lateral_std_m**2 * np.eye(2)
    return CueEstimate(NAME, xy, cov_xy, valid, reasons)
