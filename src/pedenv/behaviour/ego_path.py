"""The ego's own path, predicted from its recent poses: speed and yaw rate, then a constant turn.

Speeds are signed along the ego's heading (negative: reversing); yaw in radians, world frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from pedenv.records import EgoPose

#: With no motion known (the first frame, after a gap) the spreads are this many times the configured ones.
UNKNOWN_MOTION_FACTOR = 5.0
#: The ego's speed and yaw rate are fitted over its poses this far back (s): three to five poses at
#: 5-10 Hz, enough for the quadratic fit, short enough to follow a start or a turn.
EGO_WINDOW_S = 0.5
#: A gap between two frames longer than this (s) forgets the ego's motion (a cut recording).
MAX_EGO_GAP_S = 1.0
#: A fitted yaw rate is clipped to this (rad/s; a car turning at walking pace on a 5 m radius
#: turns at about 0.3), so a pose spike is not followed; its spread widens by the excess.
MAX_YAW_RATE_RADPS = 1.0
#: The fitted acceleration (or braking) is clipped to this (m/s^2): about a car's hard braking.
MAX_EGO_ACCELERATION_MPS2 = 4.0
#: For this long (s) into the prediction the acceleration changes at its fitted jerk (a start or a
#: stop still building up), then holds: 0 against 1 s moved each of the behaviour benchmark's
#: seeds 1-3 by at most 3 conflict events (docs/behaviour.md).
EGO_TREND_S = 1.0
#: The fitted jerk is clipped to this (m/s^3): set, not tuned; the built-in start's jerk peaks at 1.1.
MAX_EGO_JERK_MPS3 = 2.0
#: Poses that jitter along the track by more than this (m, 1 sigma: the rms of their third differences
#: over the latest :data:`EGO_JITTER_POSES` poses, / sqrt(20), white noise's ratio) cannot carry the
#: quadratic's acceleration and jerk: the acceleration is then the slope of a line through the speeds
#: of the last :data:`EGO_ACCELERATION_WINDOW_S` and the jerk 0. The built-in scenes' exact poses
#: jitter by at most 0.14 mm (a start's or a turn's own third differences), ORB-SLAM3's at 10 Hz on
#: the moving KITTI drives by 2-10 mm; there the quadratic's path was 4.0-5.7 m off its real end at 2 s
#: (rms) on the tuning drives and 2.5 m on the kept-aside 0015, the line's 1.2-1.8 and 1.4 m.
EGO_JITTER_M = 0.001
#: About 2 s of poses at 10 Hz: set, not tuned.
EGO_JITTER_POSES = 20
#: Seconds of speeds behind the line's acceleration (and the standing test): of lines over 1, 1.5 and
#: 2 s, 1 s put the path's length at 2 s closest to the real one on each tuning drive (1.1-1.5 m rms).
EGO_ACCELERATION_WINDOW_S = 1.0
#: An ego whose mean speed over the last :data:`EGO_ACCELERATION_WINDOW_S` is below this (m/s) stands:
#: no speed, acceleration or jerk. A parked car's smooth pose drift (ORB-SLAM3, KITTI 0016 / 0017)
#: otherwise reads as a start (jerk up to the clip), its path at 2 s 0.8 m long on 0016 (median; 3.4 m
#: at the 95th percentile; 0017: 0.3 and 1.3 m) and its corridor over people in front of it; 0.01 to
#: 0.05 m/s left the same flags there.
#: A start at the built-in scenes' jerk (1.1 m/s^3) passes 0.01 m/s 0.4 s in.
EGO_STANDING_MPS = 0.01
#: Spread (1 sigma) of the ego's speed (m/s) and yaw rate (rad/s) over the horizon: the driver may
#: brake or steer. Set for the built-in scenes' drivers, not tuned.
EGO_SPEED_STD_MPS = 0.5
EGO_YAW_RATE_STD_RADPS = 0.05


@dataclass(frozen=True)
class EgoMotion:
    """The ego's motion now: speed (m/s, signed), yaw rate (rad/s), their standard deviations
    over the prediction, whether they were measured (False: unknown, taken as standing) and the
    longitudinal acceleration (m/s^2, signed like the speed's axis) and its rate of change (jerk,
    m/s^3)."""

    speed: float
    yaw_rate: float
    speed_std: float
    yaw_rate_std: float
    known: bool
    acceleration: float = 0.0
    jerk: float = 0.0


@dataclass(frozen=True)
class EgoPath:
    """The ego's predicted path: times (K,) s ahead, xy (K, 2) world metres, yaw (K,) radians,
    lateral_std (K,) metres (how far it may lie sideways of this), motion (what it came from);
    its shape: an arc of ``curvature`` (1/m, positive turning left seen in the direction of
    travel) followed for ``length`` metres (the distance covered by the horizon) in ``direction``
    (+1 forwards, -1 reversing)."""

    times: np.ndarray
    xy: np.ndarray
    yaw: np.ndarray
    lateral_std: np.ndarray
    motion: EgoMotion
    curvature: float = 0.0
    length: float = 0.0
    direction: float = 1.0


class EgoHistory:
    """The ego's recent poses (timestamp, x, y, yaw), at most :data:`EGO_WINDOW_S` old; a
    gap longer than :data:`MAX_EGO_GAP_S`, or a time that does not increase, forgets them.
    Between consecutive poses it keeps ``pairs``: their mid time (s), signed speed (m/s) and yaw
    rate (rad/s), each computed once."""

    def __init__(self) -> None:
        self.poses: list[tuple[float, float, float, float]] = []
        self.pairs: list[tuple[float, float, float]] = []
        self.trend: list[tuple[float, float, float]] = []  # (mid time, speed, gap) over EGO_ACCELERATION_WINDOW_S
        self.jitter: list[float] = []  # squared third differences of the along-track positions (m^2)

    def reset(self) -> None:
        self.poses, self.pairs, self.trend, self.jitter = [], [], [], []

    def add(self, timestamp: float, ego: EgoPose) -> None:
        timestamp = float(timestamp)
        if self.poses and not 0.0 < timestamp - self.poses[-1][0] <= MAX_EGO_GAP_S:
            self.reset()  # a gap, or a time that does not increase: start again
        x, y = ego.translation[:2].tolist()
        cos_yaw, sin_yaw = ego.rotation[:2, 0].tolist()
        pose = (timestamp, x, y, math.atan2(sin_yaw, cos_yaw))  # ``EgoPose.yaw``, on Python floats
        if self.poses:
            last = self.poses[-1]
            speed, gap = _speed(last, pose), timestamp - last[0]
            self.pairs.append((0.5 * (last[0] + timestamp), speed, _turn(last, pose)))
            self.trend.append((self.pairs[-1][0], speed, gap))
            if len(self.trend) >= 3:  # the along-track steps' second difference: the positions' third
                a, b, c = (p[1] * p[2] for p in self.trend[-3:])
                self.jitter = [*self.jitter[-(EGO_JITTER_POSES - 4):], (c - 2.0 * b + a) ** 2]
            while timestamp - self.trend[0][0] > EGO_ACCELERATION_WINDOW_S:
                self.trend.pop(0)
        self.poses.append(pose)
        while len(self.poses) > 2 and timestamp - self.poses[1][0] >= EGO_WINDOW_S:
            self.poses.pop(0)
            self.pairs.pop(0)

    def motion(self) -> EgoMotion:
        """Speed, acceleration and jerk, and the yaw rate now, from the window's poses: quadratic
        fits (least squares, in time) of the speeds and yaw rates between consecutive poses,
        evaluated now (a line with 3 poses, the mean with 2). Poses that jitter more than
        :data:`EGO_JITTER_M` give the acceleration of a line over :data:`EGO_ACCELERATION_WINDOW_S`
        and no jerk; an ego slower than :data:`EGO_STANDING_MPS` over that while stands. The
        acceleration is clipped to :data:`MAX_EGO_ACCELERATION_MPS2`, the jerk to
        :data:`MAX_EGO_JERK_MPS3`; a yaw rate beyond :data:`MAX_YAW_RATE_RADPS` (a spike) is clipped
        and its spread widened by the excess."""
        poses = self.poses
        if len(poses) < 2 or poses[-1][0] - poses[0][0] <= 1e-6:
            return EgoMotion(0.0, 0.0, UNKNOWN_MOTION_FACTOR * EGO_SPEED_STD_MPS,
                             UNKNOWN_MOTION_FACTOR * EGO_YAW_RATE_STD_RADPS, False)
        now = poses[-1][0]
        value, slope, bend = _fit_rows(tuple([round(p[0] - now, 6) for p in self.pairs]))
        speeds, rates = [p[1] for p in self.pairs], [p[2] for p in self.pairs]
        speed, rate = _dot(value, speeds), _dot(value, rates)  # a handful of pairs: plain Python, not numpy
        acceleration, jerk = _dot(slope, speeds), 2.0 * _dot(bend, speeds)
        trend = self.trend
        covered = sum([p[1] * p[2] for p in trend])
        if abs(covered) < EGO_STANDING_MPS * sum([p[2] for p in trend]):  # standing (EGO_STANDING_MPS)
            speed, acceleration, jerk = 0.0, 0.0, 0.0
        elif self.jitter and sum(self.jitter) > 20.0 * len(self.jitter) * EGO_JITTER_M**2:  # EGO_JITTER_M
            acceleration, jerk = _slope(trend), 0.0
        clipped = _clip(rate, MAX_YAW_RATE_RADPS)
        return EgoMotion(speed, clipped, EGO_SPEED_STD_MPS, EGO_YAW_RATE_STD_RADPS + abs(rate - clipped),
                         True, _clip(acceleration, MAX_EGO_ACCELERATION_MPS2), _clip(jerk, MAX_EGO_JERK_MPS3))


def _slope(points: list[tuple[float, float, float]]) -> float:
    """The least-squares slope of the speeds over time of ``(t, v, gap)`` points (0 with fewer than two)."""
    if len(points) < 2:
        return 0.0
    mt = sum([p[0] for p in points]) / len(points)
    mv = sum([p[1] for p in points]) / len(points)
    den = sum([(p[0] - mt) ** 2 for p in points])
    return sum([(p[0] - mt) * (p[1] - mv) for p in points]) / den if den > 1e-12 else 0.0


def _clip(value: float, limit: float) -> float:
    return min(max(value, -limit), limit)


@lru_cache(maxsize=32)
def _fit_map(times: tuple[float, ...]) -> np.ndarray:
    """(3, P): the least-squares map from values at ``times`` (P,) to the coefficients (rows of
    degree 2 and above zero where there are too few points); the poses' times repeat frame to frame."""
    degree = min(len(times) - 1, 2)
    design = np.asarray(times)[:, None] ** np.arange(degree + 1.0)
    out = np.zeros((3, len(times)))
    out[: degree + 1] = np.linalg.pinv(design)
    return out


@lru_cache(maxsize=32)
def _fit_rows(times: tuple[float, ...]) -> tuple[tuple[float, ...], ...]:
    """:func:`_fit_map` as three tuples of floats (value, slope, curvature rows)."""
    return tuple(tuple(row) for row in _fit_map(times).tolist())


def _dot(a: tuple[float, ...], b: list[float]) -> float:
    return sum([x * y for x, y in zip(a, b)])


def _speed(a: tuple, b: tuple) -> float:
    """Signed speed (m/s) along the mean heading between poses a and b ``(t, x, y, yaw)``."""
    mid = a[3] + 0.5 * math.remainder(b[3] - a[3], 2.0 * math.pi)
    return ((b[1] - a[1]) * math.cos(mid) + (b[2] - a[2]) * math.sin(mid)) / (b[0] - a[0])


def _turn(a: tuple, b: tuple) -> float:
    return math.remainder(b[3] - a[3], 2.0 * math.pi) / (b[0] - a[0])


@lru_cache(maxsize=8)
def _bases(times: bytes, trend_s: float) -> tuple[np.ndarray, float, float]:
    """(4, K) at ``times`` (K,) s (float64 bytes): ``t``, ``t^2 / 2``, and the first and second
    integrals of a rate rising at 1 per second for ``trend_s`` seconds, then holding; and the
    first and third at the last time."""
    t = np.frombuffer(times, float)
    r = np.minimum(t, trend_s)
    e = t - r
    b = np.stack([t, 0.5 * t**2, 0.5 * r**2 + trend_s * e, r**3 / 6.0 + 0.5 * trend_s**2 * e + 0.5 * trend_s * e**2])
    return b, float(b[0, -1]), float(b[2, -1])


def travelled(motion: EgoMotion, times: np.ndarray, trend_s: float = 0.0, max_acceleration: float = math.inf
              ) -> np.ndarray:
    """Signed distance (K,) metres along the path after ``times`` (K,) s, increasing: ``v t + a t^2 / 2``
    with the acceleration changing at the jerk for ``trend_s`` seconds, then holding (never beyond
    ``max_acceleration``, nor beyond its size now); held once braking reaches a stop (the ego
    does not reverse by braking)."""
    v, a = motion.speed, motion.acceleration
    if trend_s > 0.0 and motion.jerk != 0.0:
        jerk = (_clip(a + motion.jerk * trend_s, max(max_acceleration, abs(a))) - a) / trend_s
    else:
        trend_s, jerk = 0.0, 0.0
    b, end_t, end_rate = _bases(np.ascontiguousarray(times, float).tobytes(), trend_s)
    s = v * b[0]
    if a:
        s += a * b[1]
    if jerk:
        s += jerk * b[3]
    gain = a * end_t + jerk * end_rate  # the speed's change by the end
    sign = math.copysign(1.0, v if abs(v) > 1e-9 else (gain or 1.0))  # standing: the way the speed goes
    if sign > 0:
        return np.maximum.accumulate(s)  # past a stop: held
    return -np.maximum.accumulate(-s)


def predict_ego_path(ego: EgoPose | tuple[float, float, float], motion: EgoMotion, times: np.ndarray,
                     trend_s: float = 0.0, max_acceleration: float = math.inf) -> EgoPath:
    """The path at ``times`` (K,) s ahead (increasing, from 0) from the pose now (or its world
    ``(x, y, yaw)``, metres and radians): an arc of the curvature now (yaw rate over speed),
    along which the ego covers :func:`travelled` (its acceleration changing at the jerk for
    ``trend_s`` s, never beyond ``max_acceleration``)."""
    times = np.asarray(times, float)
    if isinstance(ego, EgoPose):
        ego = (float(ego.translation[0]), float(ego.translation[1]), ego.yaw)
    x0, y0, yaw = ego
    s = travelled(motion, times, trend_s, max_acceleration)
    last = float(s[-1])
    direction = -1.0 if last < 0 or (last == 0 and motion.speed < 0) else 1.0
    dist = np.abs(s)
    speed = abs(motion.speed)
    curvature = motion.yaw_rate / speed if speed > 1e-3 else 0.0
    heading = yaw + (0.0 if direction > 0 else math.pi)
    turn = curvature * dist
    xy = np.empty((len(times), 2))
    x, y = xy[:, 0], xy[:, 1]
    if abs(curvature) < 1e-6:
        np.multiply(dist, math.cos(heading), out=x)
        np.multiply(dist, math.sin(heading), out=y)
    else:
        angle = heading + turn
        np.sin(angle, out=x)
        np.cos(angle, out=y)
        x -= math.sin(heading)
        y -= math.cos(heading)
        x /= curvature
        y /= -curvature
    x += x0
    y += y0
    lateral = np.hypot((0.5 * motion.yaw_rate_std) * times * dist,
                       (0.5 * motion.speed_std) * times * np.abs(np.sin(turn)))
    return EgoPath(times, xy, yaw + turn, lateral, motion, curvature, float(dist[-1]), direction)
