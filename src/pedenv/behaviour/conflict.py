"""Conflict with the ego's path: does a pedestrian enter the corridor around it within the horizon?

The ego's path (:mod:`pedenv.behaviour.ego_path`) is a circular arc (or a straight line), so
each point has a closed-form arc length ``s`` along it and offset ``d`` across it. The corridor
is the band ``|d| < corridor_half_width_m`` for ``0 <= s <= L + corridor_front_m`` (L: the
distance the ego covers within the horizon, accelerating or braking; the extension is its front),
closed by a half disc of that radius (every point within the half width of the path's end, as
``benchmarks/behaviour_synthetic.py``'s truth). At each time step
the pedestrian's predicted position (a Gaussian) lies inside with probability
``P(|d| < w)`` (its spread across the path plus the path's own). The probability of entering
within the horizon is the largest of these (a lower bound of the union); the entry time's
distribution is the rise of their running maximum.

All pedestrians and time steps are computed together, the x and y components stacked on one
axis, so that a frame costs a few dozen numpy calls whatever the number of pedestrians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from pedenv.behaviour.ego_path import EgoPath

#: A pedestrian whose probability of entering the corridor within the horizon reaches this counts
#: as a predicted conflict in the behaviour benchmarks (the model reports the probability itself).
#: Chosen on seeds 0-3 of ``benchmarks/behaviour.py`` (synthetic; the KITTI drives hold no entry):
#: with the corridor's spread below, 0.3 gives 88.4 % recall at 87.0 % precision there, 0.2 88.8 % at
#: 84.1 %, 0.1 90.0 % at 75.3 %, 0.4 86.8 % at 88.2 % (docs/behaviour.md); on the KITTI drives it flags
#: 8 (moving) and 3 (parked) pairs at 0.3, 36 and 4 at 0.2, 112 and 4 at 0.1. The probability is the
#: largest per-step one, a lower bound of entering at all, so a threshold below 0.5 is what it calls for.
CONFLICT_PROBABILITY = 0.3


#: The pedestrian's acceleration spread (m/s^2) in the corridor's predicted positions, in place of
#: the track filter's (``kalman.acceleration_std_mps2``, 1.0): its closed form adds ``a^2 t^4 / 4`` per
#: axis, a 2 m spread at 2 s, while pedenv's predicted positions on the whole KITTI drives (real
#: motion, modelled perception) are off by 0.9 m (median) there. With 0.3 the 2-sigma ellipse at 2 s
#: holds 92 % of the labelled positions on the moving tuning drives and 91 % on 0016 (86.5 % nominal;
#: kept aside 0015: 90 %, 0017: 93 %); with 1.0, 97-99 % and its 1-sigma ellipse 91-95 % (39 % nominal).
#: The reported path keeps the filter's.
CORRIDOR_ACCELERATION_STD_MPS2 = 0.3


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


#: Pedestrians farther than this many standard deviations beyond the corridor's reach are not in conflict.
GATE_SIGMAS = 6.0
#: The gate is checked only from this many pedestrians on (below, checking costs more than it saves;
#: a gated pedestrian's probability is below ``ndtr(-GATE_SIGMAS)`` = 1e-9 either way).
GATE_MIN_PEDESTRIANS = 32
#: Weights of the stacked covariance components ``xx, xy, yy`` in a quadratic form ``u^T C u``.
_QUADRATIC = np.array([1.0, 2.0, 1.0])
_FIRST, _SECOND = np.array([0, 0, 1]), np.array([0, 1, 1])  # the products ``ux ux, ux uy, uy uy``


def path_coordinates(path: EgoPath, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Arc length ``s`` (M,) metres along the path from the ego now (in its direction of travel),
    offset ``d`` (M,) metres across it (left positive) and the unit normal (M, 2) there, of
    points (M, 2) world x-y."""
    frame = PathFrame(path)
    s, d, rel, dist2 = frame.coordinates(np.asarray(points, float).T[None])
    return s[0], d[0], np.broadcast_to(frame.normal(rel, dist2)[0].T, (len(points), 2)).copy()


class PathFrame:
    """The path's closed-form coordinates: for an arc its centre and the rotation that measures
    the swept angle from the ego now; for a line its start and the rotation into along and across."""

    def __init__(self, path: EgoPath) -> None:
        hx, hy = math.cos(path.yaw[0]) * path.direction, math.sin(path.yaw[0]) * path.direction
        self.straight = abs(path.curvature) < 1e-4
        self.radius, self.sign = 0.0, 1.0
        if self.straight:
            self.origin = path.xy[0][None, :, None]
            self.rotation = np.array([[hx, hy], [-hy, hx]])  # -> along, across (left)
            self.weights = np.array([hy * hy, -2.0 * hx * hy, hx * hx])  # the normal's quadratic form
            return
        r = 1.0 / path.curvature  # signed: positive turning left
        self.radius, self.sign = abs(r), math.copysign(1.0, r)
        self.origin = np.array([path.xy[0, 0] - r * hy, path.xy[0, 1] + r * hx])[None, :, None]  # the centre
        sx, sy = r * hy, -r * hx  # from the centre to the ego now
        self.rotation = np.array([[sx, sy], [-sy, sx]])  # -> the swept angle's cosine and sine, times radii

    def coordinates(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """``s``, ``d`` (N, K) metres of points (N, 2, K) world x, y; the points from the origin
        (N, 2, K) and, for an arc, their squared distances from the centre (N, K) (None for a line)."""
        rel = points - self.origin
        turned = np.matmul(self.rotation, rel)
        first, second = turned[:, 0], turned[:, 1]
        if self.straight:
            return first, second, rel, None
        sq = rel * rel
        dist2 = sq[:, 0] + sq[:, 1]
        angle = np.arctan2(second, first)  # swept angle, signed like r
        across = self.radius - np.sqrt(dist2) if self.sign > 0 else np.sqrt(dist2) - self.radius
        return (self.radius * self.sign) * angle, across, rel, dist2

    def across_variance(self, rel: np.ndarray, dist2: np.ndarray | None, cov: np.ndarray) -> np.ndarray:
        """(N, K) m^2: the variance across the path of positions with covariances ``cov`` (N, 3, K)
        (xx, xy, yy), given :meth:`coordinates`' ``rel`` and ``dist2``."""
        if dist2 is None:
            return np.matmul(self.weights, cov)
        return np.matmul(_QUADRATIC, rel[:, _FIRST] * rel[:, _SECOND] * cov) / np.maximum(dist2, 1e-18)

    def normal(self, rel: np.ndarray, dist2: np.ndarray | None) -> np.ndarray:
        """(N, 2, K) (a line: (1, 2, 1)) the unit normal, left of the path, given :meth:`coordinates`'
        ``rel`` and ``dist2``."""
        if dist2 is None:
            return self.rotation[1][None, :, None]
        return rel * (-self.sign / np.maximum(np.sqrt(dist2), 1e-9))[:, None]  # inward for a left turn


def corridor_conflict(path: EgoPath, positions: np.ndarray, covariances: np.ndarray, half_width_m: float,
                      front_m: float) -> Conflict:
    """The conflict of N pedestrians with the corridor of ``path`` (K times).

    positions: (N, K, 2) world x-y metres at the path's times; covariances: (N, K, 2, 2) m^2
    (zeros for exact positions, as the ground truth). A pedestrian whose predicted positions stay
    more than :data:`GATE_SIGMAS` standard deviations beyond the corridor's reach (its length
    plus half width, from the ego now) gets probability 0 without the per-step computation.
    """
    positions, covariances = np.asarray(positions, float), np.asarray(covariances, float)
    stacked = np.stack([covariances[..., 0, 0], covariances[..., 0, 1], covariances[..., 1, 1]], axis=1)
    return conflict_of(path, np.ascontiguousarray(positions.transpose(0, 2, 1)), stacked, half_width_m, front_m)


def conflict_of(path: EgoPath, positions: np.ndarray, covariances: np.ndarray, half_width_m: float,
                front_m: float) -> Conflict:
    """:func:`corridor_conflict` from the predicted positions (N, 2, K) world x, y metres and their
    covariances (N, 3, K) m^2, the components xx, xy, yy
    (:meth:`pedenv.behaviour.prediction.PathPredictor.stacked`)."""
    n = len(positions)
    lateral_var = path.lateral_std**2
    sep = positions - path.xy.T  # from the ego at the same time
    sq = sep * sep
    sep2 = sq[:, 0] + sq[:, 1]
    j = sep2.argmin(axis=1)  # the closest step
    people = np.arange(n)
    u, c = sep[people, :, j], covariances[people, :, j]  # (N, 2), (N, 3)
    closest2 = sep2[people, j]
    across = (u[:, _FIRST] * u[:, _SECOND] * c) @ _QUADRATIC
    closest_var = across / np.maximum(closest2, 1e-18) + lateral_var[j]  # along the separation
    horizon, length = path.times[-1], path.length + front_m
    near = _near(path, positions, covariances, length + half_width_m) if n >= GATE_MIN_PEDESTRIANS else None
    if near is None or near.all():
        prob, mean, spread = _entry(path, positions, covariances, half_width_m, length, lateral_var)
    else:
        prob, mean, spread = np.zeros(n), np.full(n, horizon), np.zeros(n)
        if near.any():
            prob[near], mean[near], spread[near] = _entry(path, positions[near], covariances[near], half_width_m,
                                                          length, lateral_var)
    return Conflict(prob, mean, spread, np.sqrt(closest2), np.sqrt(np.maximum(closest_var, 0.0)), path.times[j])


def _near(path: EgoPath, positions: np.ndarray, covariances: np.ndarray, reach: float) -> np.ndarray:
    """(N,) bool: the pedestrians that come within ``reach`` metres plus :data:`GATE_SIGMAS` of their
    largest spread of the ego's position now."""
    spread_max = np.sqrt(np.maximum((covariances[:, 0] + covariances[:, 2]).max(axis=1), 0.0)
                         + path.lateral_std[-1] ** 2)
    rel = positions - path.xy[0][None, :, None]
    return np.sqrt((rel * rel).sum(axis=1).min(axis=1)) < reach + GATE_SIGMAS * spread_max


#: The corridor's two edges, as multiples of its half width.
_EDGES = np.array([1.0, -1.0])[:, None, None]


def _entry(path: EgoPath, positions: np.ndarray, covariances: np.ndarray, half_width_m: float, length: float,
           lateral_var: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Probability (M,) of entering within the horizon, the entry time's mean and std (M,) s, from
    the positions (M, 2, K) and covariances (M, 3, K) (see :func:`conflict_of`; lateral_var (K,) m^2:
    the path's own variance across). The corridor's half chord is 0 behind the ego (``s < 0``) and
    beyond its round end; where it is 0 at every step for everyone, each step's probability is
    exactly 0 and the Gaussian work is skipped (a standing ego, people beside or ahead of it)."""
    frame = PathFrame(path)
    s, d, rel, dist2 = frame.coordinates(positions)
    t = path.times
    beyond = np.maximum(s - length, 0.0)  # past the corridor's straight part: its round end's half chord
    half = np.sqrt(np.maximum(half_width_m * half_width_m - beyond * beyond, 0.0))
    half *= s >= 0.0  # behind the ego: none (both edges at 0, so the difference below is exactly 0)
    if not half.any():
        return np.zeros(len(s)), np.full(len(s), t[-1]), np.zeros(len(s))  # what the steps below give
    sd = np.sqrt(np.maximum(frame.across_variance(rel, dist2, covariances) + lateral_var, 1e-8))
    edges = ndtr((half * _EDGES - d) / sd)
    inside = edges[0] - edges[1]
    running = np.maximum.accumulate(inside, axis=1)
    prob = np.maximum(running[:, -1], 0.0)  # at most 1: a difference of two ndtr's (NaN stays NaN)
    some = prob > 1e-3
    if not some.any():
        return prob, np.full(len(prob), t[-1]), np.zeros(len(prob))
    rise = running.copy()
    rise[:, 1:] -= running[:, :-1]
    weight = np.maximum(prob, 1e-12)
    mean = np.where(some, (rise @ t) / weight, t[-1])
    dev = t - mean[:, None]
    spread = np.sqrt(np.maximum((rise * dev * dev).sum(axis=1) / weight, 0.0))
    return prob, mean, np.where(some, spread, 0.0)
