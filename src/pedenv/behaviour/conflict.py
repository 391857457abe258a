"""Conflict with the ego's path: does a pedestrian enter the corridor around it within the horizon?

The ego's path (:mod:`pedenv.behaviour.ego_path`) is a circular arc (or a straight line), so
each point has a closed-form arc length ``s`` along it and offset ``d`` across it. The corridor
is the band ``|d| < corridor_half_width_m`` for ``0 <= s <= L + corridor_front_m`` (L: the
distance the ego covers within the horizon, accelerating or braking; the extension is its front). At each time step
the pedestrian's predicted position (a Gaussian) lies inside with probability
``P(|d| < w)`` (its spread across the path plus the path's own). The probability of entering
within the horizon is the largest of these (a lower bound of the union); the entry time's
distribution is the rise of their running maximum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from pedenv.behaviour.ego_path import EgoPath


@dataclass(frozen=True)
class Conflict:
    """Per pedestrian (N,): probability of entering the corridor within the horizon; the time
    until then (s, its mean given entry; the horizon where the probability is below 1e-3) and
    its standard deviation; the closest approach to the ego (metres, same time on both paths),
    its standard deviation and when it happens (s ahead)."""

    probability: np.ndarray
    time_s: np.ndarray
    time_std_s: np.ndarray
    closest_m: np.ndarray
    closest_std_m: np.ndarray
    closest_time_s: np.ndarray


def path_coordinates(path: EgoPath, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Arc length ``s`` (...) metres along the path from the ego now (in its direction of travel),
    offset ``d`` (...) metres across it (left positive) and the unit normal (..., 2) there, of
    points (..., 2) world x-y."""
    e0 = path.xy[0]
    heading = np.array([np.cos(path.yaw[0]), np.sin(path.yaw[0])]) * path.direction
    normal0 = np.array([-heading[1], heading[0]])
    rel = points - e0
    curvature = path.curvature
    if abs(curvature) < 1e-4:
        s, d = rel @ heading, rel @ normal0
        return s, d, np.broadcast_to(normal0, points.shape)
    r = 1.0 / curvature  # signed: positive turning left
    to_point = rel - r * normal0  # from the turn's centre
    dist = np.linalg.norm(to_point, axis=-1)
    start = -r * normal0
    cross = start[0] * to_point[..., 1] - start[1] * to_point[..., 0]
    angle = np.arctan2(cross, to_point @ start) * np.sign(r)  # swept angle, in the direction of travel
    outward = to_point / np.maximum(dist, 1e-9)[..., None]
    return abs(r) * angle, np.sign(r) * (abs(r) - dist), -np.sign(r) * outward


def corridor_conflict(path: EgoPath, positions: np.ndarray, covariances: np.ndarray, half_width_m: float,
                      front_m: float) -> Conflict:
    """The conflict of N pedestrians with the corridor of ``path`` (K times).

    positions: (N, K, 2) world x-y metres at the path's times; covariances: (N, K, 2, 2) m^2
    (zeros for exact positions, as the ground truth). A pedestrian whose predicted positions stay
    more than :data:`GATE_SIGMAS` standard deviations beyond the corridor's reach (its length
    plus half width, from the ego now) gets probability 0 without the per-step computation.
    """
    n = positions.shape[0]
    sep = positions - path.xy[None]
    dist = np.linalg.norm(sep, axis=2)
    j = dist.argmin(axis=1)
    rows = np.arange(n)
    u = sep[rows, j] / np.maximum(dist[rows, j], 1e-9)[:, None]
    closest_var = np.einsum("ni,nij,nj->n", u, covariances[rows, j], u) + path.lateral_std[j] ** 2
    horizon = path.times[-1]
    prob, mean, spread = np.zeros(n), np.full(n, horizon), np.zeros(n)
    reach = path.length + front_m + half_width_m
    trace = (covariances[..., 0, 0] + covariances[..., 1, 1]).max(axis=1)
    spread_max = np.sqrt(np.maximum(trace, 0.0) + path.lateral_std[-1] ** 2)
    near = np.linalg.norm(positions - path.xy[0], axis=2).min(axis=1) < reach + GATE_SIGMAS * spread_max
    if near.any():
        prob[near], mean[near], spread[near] = _entry(path, positions[near], covariances[near], half_width_m,
                                                      path.length + front_m)
    return Conflict(prob, mean, spread, dist[rows, j], np.sqrt(np.maximum(closest_var, 0.0)), path.times[j])


#: Pedestrians farther than this many standard deviations beyond the corridor's reach are not in conflict.
GATE_SIGMAS = 6.0


def _entry(path: EgoPath, positions: np.ndarray, covariances: np.ndarray, half_width_m: float,
           length: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Probability (M,) of entering within the horizon, the entry time's mean and std (M,) s."""
    s, d, normal = path_coordinates(path, positions)
    var = np.einsum("nki,nkij,nkj->nk", normal, covariances, normal) + path.lateral_std[None, :] ** 2
    sd = np.sqrt(np.maximum(var, 1e-8))
    inside = ndtr((half_width_m - d) / sd) - ndtr((-half_width_m - d) / sd)
    inside = np.where((s >= 0.0) & (s <= length), inside, 0.0)
    running = np.maximum.accumulate(inside, axis=1)
    prob = np.clip(running[:, -1], 0.0, 1.0)
    rise = np.diff(running, axis=1, prepend=0.0)
    t = path.times[None, :]
    some = prob > 1e-3
    mean = np.where(some, (rise * t).sum(1) / np.maximum(prob, 1e-12), path.times[-1])
    spread = np.sqrt(np.maximum((rise * (t - mean[:, None]) ** 2).sum(1) / np.maximum(prob, 1e-12), 0.0))
    return prob, mean, np.where(some, spread, 0.0)
