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

import math
from dataclasses import dataclass
from typing import Any

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
    s, d, nx, ny = _coordinates(path, points[..., 0], points[..., 1])
    return s, d, np.stack(np.broadcast_arrays(nx, ny, s)[:2], axis=-1)


def _coordinates(path: EgoPath, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray, Any, Any]:
    """:func:`path_coordinates` of points given by their world coordinates px, py (...): ``s``,
    ``d`` and the normal's components (... or scalars)."""
    hx, hy = math.cos(path.yaw[0]) * path.direction, math.sin(path.yaw[0]) * path.direction
    rx, ry = px - path.xy[0, 0], py - path.xy[0, 1]
    curvature = path.curvature
    if abs(curvature) < 1e-4:
        return rx * hx + ry * hy, ry * hx - rx * hy, -hy, hx
    r = 1.0 / curvature  # signed: positive turning left
    tx, ty = rx + r * hy, ry - r * hx  # from the turn's centre
    dist = np.hypot(tx, ty)
    sx, sy = -r * -hy, -r * hx  # from the centre to the ego now
    angle = np.arctan2(sx * ty - sy * tx, tx * sx + ty * sy)  # swept angle, signed like r
    sign = math.copysign(1.0, r)
    scale = -sign / np.maximum(dist, 1e-9)  # the normal: the inward unit vector for a left turn
    return (abs(r) * sign) * angle, sign * (abs(r) - dist), tx * scale, ty * scale


def corridor_conflict(path: EgoPath, positions: np.ndarray, covariances: np.ndarray, half_width_m: float,
                      front_m: float) -> Conflict:
    """The conflict of N pedestrians with the corridor of ``path`` (K times).

    positions: (N, K, 2) world x-y metres at the path's times; covariances: (N, K, 2, 2) m^2
    (zeros for exact positions, as the ground truth). A pedestrian whose predicted positions stay
    more than :data:`GATE_SIGMAS` standard deviations beyond the corridor's reach (its length
    plus half width, from the ego now) gets probability 0 without the per-step computation.
    """
    parts = (positions[..., 0], positions[..., 1], covariances[..., 0, 0], covariances[..., 0, 1],
             covariances[..., 1, 1])
    return conflict_of(path, tuple(np.ascontiguousarray(a, float) for a in parts), half_width_m, front_m)


def conflict_of(path: EgoPath, parts: tuple[np.ndarray, ...], half_width_m: float, front_m: float) -> Conflict:
    """:func:`corridor_conflict` from the predicted positions and covariances by component:
    ``parts`` = x, y (N, K) metres and the covariances' xx, xy, yy (N, K) m^2
    (:meth:`pedenv.behaviour.prediction.PathPredictor.components`)."""
    px, py, cxx, cxy, cyy = parts
    n, k = px.shape
    sx, sy = px - path.xy[:, 0], py - path.xy[:, 1]
    sep = np.hypot(sx, sy)
    j = sep.argmin(axis=1)  # the closest step
    at = np.arange(n) * k + j
    closest, ux, uy = sep.ravel()[at], sx.ravel()[at], sy.ravel()[at]
    across = ux * ux * cxx.ravel()[at] + 2.0 * ux * uy * cxy.ravel()[at] + uy * uy * cyy.ravel()[at]
    closest_var = across / np.maximum(closest, 1e-9) ** 2 + path.lateral_std[j] ** 2  # along the separation
    horizon = path.times[-1]
    prob, mean, spread = np.zeros(n), np.full(n, horizon), np.zeros(n)
    reach = path.length + front_m + half_width_m
    spread_max = np.sqrt(np.maximum((cxx + cyy).max(axis=1), 0.0) + path.lateral_std[-1] ** 2)
    near = np.hypot(px - path.xy[0, 0], py - path.xy[0, 1]).min(axis=1) < reach + GATE_SIGMAS * spread_max
    if near.all():
        prob, mean, spread = _entry(path, parts, half_width_m, path.length + front_m)
    elif near.any():
        prob[near], mean[near], spread[near] = _entry(path, tuple(a[near] for a in parts), half_width_m,
                                                      path.length + front_m)
    return Conflict(prob, mean, spread, closest, np.sqrt(np.maximum(closest_var, 0.0)), path.times[j])


#: Pedestrians farther than this many standard deviations beyond the corridor's reach are not in conflict.
GATE_SIGMAS = 6.0


def _entry(path: EgoPath, parts: tuple[np.ndarray, ...], half_width_m: float, length: float
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Probability (M,) of entering within the horizon, the entry time's mean and std (M,) s, from
    the positions and covariances by component (M, K) (see :func:`conflict_of`)."""
    px, py, cxx, cxy, cyy = parts
    s, d, nx, ny = _coordinates(path, px, py)
    var = nx * nx * cxx + 2.0 * nx * ny * cxy + ny * ny * cyy + path.lateral_std**2
    sd = np.sqrt(np.maximum(var, 1e-8))
    inside = ndtr((half_width_m - d) / sd) - ndtr((-half_width_m - d) / sd)
    inside *= (s >= 0.0) & (s <= length)  # behind the ego or beyond the corridor: 0
    running = np.maximum.accumulate(inside, axis=1)
    prob = np.minimum(np.maximum(running[:, -1], 0.0), 1.0)
    some = prob > 1e-3
    t = path.times
    if not some.any():
        return prob, np.full(len(prob), t[-1]), np.zeros(len(prob))
    rise = running.copy()
    rise[:, 1:] -= running[:, :-1]
    mean = np.where(some, (rise @ t) / np.maximum(prob, 1e-12), t[-1])
    spread = np.sqrt(np.maximum((rise * (t - mean[:, None]) ** 2).sum(1) / np.maximum(prob, 1e-12), 0.0))
    return prob, mean, np.where(some, spread, 0.0)
