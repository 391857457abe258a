"""Motion state with hysteresis: standing, walking or running, from the posterior of the true speed.

The track's Kalman filter holds its velocity as a Gaussian, with the filter's own prior of a new
track (zero, :data:`pedenv.kalman.INITIAL_VELOCITY_STD_MPS` per axis) in it. :func:`speed_posterior`
divides that prior out, widens the rest into a heavy-tailed likelihood (a filter velocity is now and
then far off its stated spread: :data:`OUTLIER_SHARE`) and puts a population prior on the true speed
in the filter's prior's place (most people stand or walk at about 1.35 m/s, few run), on a grid of
speeds and directions: the posterior's
median speed decides the motion state (:func:`next_state`), its mean velocity is the predicted
path's (:mod:`pedenv.behaviour.estimator`). A young track, whose filter knows little yet, is
called what the population mostly does (walking, at the prior's median of about 1.1 m/s) instead of
standing until its speed is significant; a far track's implausible speed (3-5 m/s from a range
that jumps) is drawn toward a walker's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.behaviour.config import BehaviourConfig
from pedenv.kalman import INITIAL_VELOCITY_STD_MPS

STANDING, WALKING, RUNNING = 0, 1, 2
#: Names of the motion states, indexed by code (the confusion tables of ``evaluation.behaviour``).
MOTION_STATE_NAMES = ("standing", "walking", "running")
#: The walking direction (:mod:`pedenv.behaviour.orientation`) uses a filtered speed only when it
#: exceeds this many of its standard deviations (1.5: about 93 % one-sided), so a standing person's
#: filter noise does not turn the heading.
SPEED_SIGMAS = 1.5

#: The true speeds (m/s) of the posterior's grid: 0 to 5 m/s every 0.1 m/s (a grid of 0.05 m/s gave
#: the same motion states on the KITTI drives within 0.5 points).
SPEED_GRID_MPS = np.linspace(0.0, 5.0, 51)
#: Directions of the posterior's grid, degrees from the filter's velocity either way (the grid is
#: turned per track): dense where a posterior gathers, coarse behind. The mean velocities on the
#: KITTI drives are within 1 % (mean error at 2 s) of a grid of 72 directions and 0.05 m/s.
DIRECTION_OFFSETS_DEG = (0.0, 5.0, 11.0, 18.0, 27.0, 39.0, 55.0, 76.0, 104.0, 140.0, 180.0)
DIRECTIONS = 2 * len(DIRECTION_OFFSETS_DEG) - 2
#: The population prior on the true speed, a mixture: standing (a half-normal of 0.12 m/s: sway and
#: steps on the spot), walking (a normal of 1.35 m/s, spread 0.4 m/s: adults' comfortable walking
#: speed, about 1.3-1.4 m/s, Bohannon 1997, with room for the slow and the hurried) and running
#: (3.2 m/s, spread 0.7 m/s: jogging). Shares 0.3 / 0.65 / 0.05: chosen on the KITTI tuning drives
#: (whose labelled pairs stand 9 % of the time overall, 27 % on 0013, 45 % on 0011) among 0.3, 0.5
#: and 0.7 standing; the built-in scenes' people stand 18 % of the time. With 0.5 the moving drives
#: agree 79.8 % instead of 85.1 % (docs/kitti_tracking.md).
PRIOR_SHARES = (0.3, 0.65, 0.05)
PRIOR_STANDING_STD_MPS = 0.12
PRIOR_WALKING_MPS, PRIOR_WALKING_STD_MPS = 1.35, 0.4
PRIOR_RUNNING_MPS, PRIOR_RUNNING_STD_MPS = 3.2, 0.7
#: Added to the velocity's variance each way ((m/s)^2, a 1 mm/s spread), so that an exact or
#: degenerate covariance is still inverted: far below any filter's.
VELOCITY_VARIANCE_FLOOR = 1e-6
#: The likelihood of the true velocity is a mixture: the filter's Gaussian (its new-track prior divided
#: out) with weight 1 - OUTLIER_SHARE, and the same Gaussian OUTLIER_SPREAD times as wide with weight
#: OUTLIER_SHARE. On the KITTI drives the filter's velocity against the labelled one has a normalised
#: squared error whose median is at or below a Gaussian's but whose mean is 2-10 times it (a range that
#: jumps, a young track's first steps): a Gaussian likelihood follows those few far-off velocities, the
#: mixture lets the population prior overrule them. Chosen on the tuning drives (0013, 0011, 0004, 0001,
#: 0000, 0016) among shares 0.05 / 0.1 / 0.2 and spreads 3 / 4 / 6 / 8 (docs/kitti_tracking.md).
OUTLIER_SHARE, OUTLIER_SPREAD = 0.1, 6.0
#: The likelihood's information is taken at least 1 / (this)^2 each way ((m/s)^-2): a spread wider than
#: the grid's top speed is flat over the grid anyway, and the floor keeps its normaliser finite.
LIKELIHOOD_MAX_STD_MPS = 5.0


def _grid() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The grid's velocities (2, G) m/s (G = directions x speeds, direction major), their quadratic
    terms (3, G) (vx^2 / 2, vx vy, vy^2 / 2) and the log prior (G,) (each speed's prior shared by
    its directions as their widths share the circle)."""
    s = SPEED_GRID_MPS
    parts = [np.exp(-0.5 * ((s - mean) / std) ** 2) for mean, std in
             ((0.0, PRIOR_STANDING_STD_MPS), (PRIOR_WALKING_MPS, PRIOR_WALKING_STD_MPS),
              (PRIOR_RUNNING_MPS, PRIOR_RUNNING_STD_MPS))]
    prior = sum(share * part / part.sum() for share, part in zip(PRIOR_SHARES, parts))
    half = np.radians(DIRECTION_OFFSETS_DEG)
    angle = np.concatenate([-half[:0:-1], half[:-1]])  # [-180, 180) degrees, increasing
    around = np.concatenate([angle[-1:] - 2.0 * np.pi, angle, angle[:1] + 2.0 * np.pi])
    width = 0.5 * (around[2:] - around[:-2])  # each direction's share of the circle (a uniform prior)
    cos = np.cos(angle)
    width *= 1.0 - cos * ((width @ cos) / (width @ (cos * cos)))  # its mean direction exactly none (sums to 0)
    vx, vy = np.outer(np.cos(angle), s).ravel(), np.outer(np.sin(angle), s).ravel()
    return (np.stack([vx, vy]), np.stack([0.5 * vx * vx, vx * vy, 0.5 * vy * vy]),
            (np.log(width / (2.0 * np.pi))[:, None] + np.log(np.maximum(prior, 1e-300))[None, :]).ravel())


_VELOCITIES, _QUADRATIC, _LOG_PRIOR = _grid()
_PRIOR = np.exp(_LOG_PRIOR)  # at least about 1e-6 over the grid's speeds (0-5 m/s)


@dataclass(frozen=True)
class VelocityStats:
    """Velocities (N, 2) m/s with covariances (N, 2, 2) (m/s)^2, summarised once per frame for the
    cues that use them: speed (N,) m/s and var_along (N,) (m/s)^2, the variance along the velocity;
    the rest on demand (the walking direction needs them only when the heading grids are updated)."""

    speed: np.ndarray
    var_along: np.ndarray
    velocities: np.ndarray
    covariances: np.ndarray

    def unit(self) -> np.ndarray:
        """(N, 2) the velocity's direction (zero at standstill)."""
        return self.velocities * (1.0 / np.maximum(self.speed, 1e-9))[:, None]

    def var_across(self) -> np.ndarray:
        """(N,) (m/s)^2 the variance across the velocity (0 at standstill)."""
        vx, vy = self.velocities[:, 0], self.velocities[:, 1]
        a, b, d = self.covariances[:, 0, 0], self.covariances[:, 0, 1], self.covariances[:, 1, 1]
        return (a * (vy * vy) - (2.0 * b) * (vx * vy) + d * (vx * vx)) / np.maximum(self.speed, 1e-9) ** 2

    def var_largest(self) -> np.ndarray:
        """(N,) (m/s)^2 the covariance's larger eigenvalue."""
        a, b, d = self.covariances[:, 0, 0], self.covariances[:, 0, 1], self.covariances[:, 1, 1]
        return 0.5 * (a + d) + np.sqrt(np.maximum(0.25 * (a - d) ** 2 + b**2, 0.0))


def velocity_stats(velocities: np.ndarray, velocity_covariances: np.ndarray) -> VelocityStats:
    """:class:`VelocityStats` of velocities (N, 2) m/s with covariances (N, 2, 2) (m/s)^2."""
    vx, vy = velocities[:, 0], velocities[:, 1]
    a, b, d = velocity_covariances[:, 0, 0], velocity_covariances[:, 0, 1], velocity_covariances[:, 1, 1]
    speed = np.hypot(vx, vy)
    along = (a * (vx * vx) + (2.0 * b) * (vx * vy) + d * (vy * vy)) / np.maximum(speed, 1e-9) ** 2
    return VelocityStats(speed, along, velocities, velocity_covariances)


def speed_and_std(velocities: np.ndarray, velocity_covariances: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Speed (N,) m/s and its standard deviation (N,) of velocities (N, 2) m/s with covariances
    (N, 2, 2) (m/s)^2 (along the velocity; at standstill the larger axis)."""
    return speed_from(velocity_stats(velocities, velocity_covariances))


def speed_from(v: VelocityStats) -> tuple[np.ndarray, np.ndarray]:
    """:func:`speed_and_std` from the :class:`VelocityStats`."""
    moving = len(v.speed) and v.speed.min() > 1e-6
    var = v.var_along if moving else np.where(v.speed > 1e-6, v.var_along, v.var_largest())
    return v.speed, np.sqrt(np.maximum(var, 0.0))


def speed_posterior(velocities: np.ndarray, velocity_covariances: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The posterior of the true velocity under the population prior (module doc), from the filter's
    velocities (N, 2) m/s with covariances (N, 2, 2) (m/s)^2 (finite, positive semi-definite: the
    estimator's states are): its median speed (N,) m/s and its mean velocity (N, 2) m/s, and the mean
    velocity (N, 2) m/s of the posterior under the filter's Gaussian alone (no heavy tail: the
    conflict corridor's, docs/behaviour.md).

    The likelihood (:func:`_log_likelihood`) is mixed with the same OUTLIER_SPREAD times as wide
    (:data:`OUTLIER_SHARE`).
    """
    n = len(velocities)
    if n == 0:
        return np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2))
    p, c, s = _log_likelihood(velocities, velocity_covariances)
    # the mixture (module doc), (1 - e) exp(p) + e exp(p / k^2) / k^2 (the normalisers in 2D), both terms
    # taken relative to the grid's best p, so that neither underflows where the other does not
    k2, top = OUTLIER_SPREAD**2, p.max(axis=1, keepdims=True)
    p -= top
    wide = np.exp(p * (1.0 / k2))
    np.exp(p, out=p)  # the Gaussian's likelihood alone (the corridor's posterior)
    narrow = (1.0 - OUTLIER_SHARE) * np.exp(top * (1.0 - 1.0 / k2))
    wide *= OUTLIER_SHARE / k2
    wide += narrow * p
    means = []
    for q in (wide, p):
        q *= _PRIOR  # the posterior on the grid, not normalised
        turned = (q @ _VELOCITIES.T) / q.sum(axis=1, keepdims=True)
        means.append(np.stack([c * turned[:, 0] - s * turned[:, 1], s * turned[:, 0] + c * turned[:, 1]], axis=1))
    p = wide
    cdf = np.cumsum(p.reshape(n, DIRECTIONS, len(SPEED_GRID_MPS)).sum(axis=1), axis=1)  # the speed's, unnormalised
    median = SPEED_GRID_MPS[np.minimum((cdf < 0.5 * cdf[:, -1:]).sum(axis=1), len(SPEED_GRID_MPS) - 1)]
    return median, means[0], means[1]


def _log_likelihood(velocities: np.ndarray, velocity_covariances: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The filter's Gaussian, its new-track prior divided out, as the log likelihood (N, G) (<= 0, its
    peak 0) of the true velocity on the grid turned per track to the filter's direction, with the
    turn's cosine and sine (N,) each: in information form ``h.v - v'Jv / 2 - h'J^-1 h / 2`` with
    ``J = C^-1 - I / s0^2`` (its eigenvalues at least ``1 / LIKELIHOOD_MAX_STD_MPS^2``: where the
    process noise widened the filter beyond that prior, no information) and ``h = C^-1 m``: two matrix
    products over the grid."""
    a, b, d = velocity_covariances[:, 0, 0], velocity_covariances[:, 0, 1], velocity_covariances[:, 1, 1]
    a, d = a + VELOCITY_VARIANCE_FLOOR, d + VELOCITY_VARIANCE_FLOOR
    det = np.maximum(a * d - b * b, VELOCITY_VARIANCE_FLOOR**2)
    inv = np.stack([d / det, -b / det, a / det], axis=1)  # C^-1: xx, xy, yy
    h = np.stack([inv[:, 0] * velocities[:, 0] + inv[:, 1] * velocities[:, 1],
                  inv[:, 1] * velocities[:, 0] + inv[:, 2] * velocities[:, 1]], axis=1)
    info = inv - np.array([1.0, 0.0, 1.0]) / INITIAL_VELOCITY_STD_MPS**2
    mid, half = 0.5 * (info[:, 0] + info[:, 2]), np.hypot(0.5 * (info[:, 0] - info[:, 2]), info[:, 1])
    floor = 1.0 / LIKELIHOOD_MAX_STD_MPS**2
    low = mid - half < floor  # rare (a track the process noise widened): its eigenvalues raised to the floor
    if low.any():
        info[low] = _clip_below(info[low], floor)
    det = info[:, 0] * info[:, 2] - info[:, 1] ** 2  # h'J^-1 h / 2: the log likelihood's peak is 0
    centre = 0.5 * (h[:, 0] * (info[:, 2] * h[:, 0] - info[:, 1] * h[:, 1])
                    + h[:, 1] * (info[:, 0] * h[:, 1] - info[:, 1] * h[:, 0])) / det
    # the grid turned per track so that its direction 0 is the filter's velocity's (the prior is the same
    # in every direction): a well-measured direction is kept, not rounded to the grid's
    speed = np.hypot(velocities[:, 0], velocities[:, 1])
    c = np.where(speed > 1e-9, velocities[:, 0] / np.maximum(speed, 1e-9), 1.0)
    s = np.where(speed > 1e-9, velocities[:, 1] / np.maximum(speed, 1e-9), 0.0)
    h = np.stack([c * h[:, 0] + s * h[:, 1], c * h[:, 1] - s * h[:, 0]], axis=1)
    cs, cc, ss = c * s, c * c, s * s
    info = np.stack([cc * info[:, 0] + 2.0 * cs * info[:, 1] + ss * info[:, 2],
                     cs * (info[:, 2] - info[:, 0]) + (cc - ss) * info[:, 1],
                     ss * info[:, 0] - 2.0 * cs * info[:, 1] + cc * info[:, 2]], axis=1)
    p = h @ _VELOCITIES
    p -= info @ _QUADRATIC
    p -= centre[:, None]  # -(v - mean)'J(v - mean) / 2
    return p, c, s


def _clip_below(info: np.ndarray, floor: float) -> np.ndarray:
    """Symmetric 2x2 matrices (M, 3) xx, xy, yy with their eigenvalues raised to at least ``floor``."""
    m = np.stack([info[:, [0, 1]], info[:, [1, 2]]], axis=1)
    w, v = np.linalg.eigh(m)
    m = np.einsum("nij,nj,nkj->nik", v, np.maximum(w, floor), v)
    return np.stack([m[:, 0, 0], m[:, 0, 1], m[:, 1, 1]], axis=1)


def next_state(previous: np.ndarray, speed: np.ndarray, config: BehaviourConfig) -> np.ndarray:
    """(N,) int8 states after this frame, from the previous ones (N,) (a new track: standing) and
    the posterior's median speed (N,) m/s (:func:`speed_posterior`; finite).

    Up a state once the speed exceeds its entry threshold; down once it falls below the exit
    threshold. Between the two the state holds, so it does not flicker. The posterior carries
    the speed's uncertainty: an uncertain speed is drawn toward the prior's.
    """
    # the state may fall to the number of exit thresholds the speed stays above, and rises to the
    # number of entry thresholds it exceeds (the entries lie above the exits)
    floor = np.add(speed > config.walk_enter_mps, speed > config.run_enter_mps, dtype=np.int8)  # entries < speed
    ceiling = np.add(speed >= config.walk_exit_mps, speed >= config.run_exit_mps, dtype=np.int8)  # exits <= speed
    return np.maximum(np.minimum(previous, ceiling), floor).astype(np.int8, copy=False)
