"""The ego's own path, predicted from its recent poses: speed and yaw rate, then a constant turn.

Speeds are signed along the ego's heading (negative: reversing); yaw in radians, world frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pedenv.behaviour.config import BehaviourConfig
from pedenv.records import EgoPose

#: With no motion known (the first frame, after a gap) the spreads are this many times the configured ones.
UNKNOWN_MOTION_FACTOR = 5.0


@dataclass(frozen=True)
class EgoMotion:
    """The ego's motion now: speed (m/s, signed), yaw rate (rad/s), their standard deviations
    over the prediction, whether they were measured (False: unknown, taken as standing) and the
    longitudinal acceleration (m/s^2, signed like the speed's axis)."""

    speed: float
    yaw_rate: float
    speed_std: float
    yaw_rate_std: float
    known: bool
    acceleration: float = 0.0


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
    """The ego's recent poses (timestamp, x, y, yaw), at most ``config.ego_window_s`` old; a
    gap longer than ``config.max_ego_gap_s`` forgets them."""

    def __init__(self, config: BehaviourConfig) -> None:
        self.config = config
        self.poses: list[tuple[float, float, float, float]] = []

    def reset(self) -> None:
        self.poses = []

    def add(self, timestamp: float, ego: EgoPose) -> None:
        if self.poses and timestamp - self.poses[-1][0] > self.config.max_ego_gap_s:
            self.poses = []
        self.poses.append((float(timestamp), float(ego.translation[0]), float(ego.translation[1]), ego.yaw))
        while len(self.poses) > 2 and timestamp - self.poses[1][0] >= self.config.ego_window_s:
            self.poses.pop(0)

    def motion(self) -> EgoMotion:
        """Speed, yaw rate and acceleration from the window's poses: the speeds over its older and
        newer half give the acceleration (clipped to ``max_ego_acceleration_mps2``); the speed is
        the newer half's carried to now. A yaw rate beyond ``max_yaw_rate_radps`` (a spike) is
        clipped and its spread widened by the excess."""
        cfg, poses = self.config, self.poses
        if len(poses) < 2 or poses[-1][0] - poses[0][0] <= 1e-6:
            return EgoMotion(0.0, 0.0, UNKNOWN_MOTION_FACTOR * cfg.ego_speed_std_mps,
                             UNKNOWN_MOTION_FACTOR * cfg.ego_yaw_rate_std_radps, False)
        mid = len(poses) // 2
        speed, rate = _speed(poses[0], poses[-1]), _turn(poses[0], poses[-1])
        acceleration = 0.0
        if len(poses) >= 3:
            older, newer = _speed(poses[0], poses[mid]), _speed(poses[mid], poses[-1])
            gap = 0.5 * (poses[-1][0] - poses[0][0])
            acceleration = min(max((newer - older) / gap, -cfg.max_ego_acceleration_mps2),
                               cfg.max_ego_acceleration_mps2)
            speed = newer + acceleration * 0.5 * (poses[-1][0] - poses[mid][0])
        clipped = min(max(rate, -cfg.max_yaw_rate_radps), cfg.max_yaw_rate_radps)
        return EgoMotion(speed, clipped, cfg.ego_speed_std_mps, cfg.ego_yaw_rate_std_radps + abs(rate - clipped),
                         True, acceleration)


def _speed(a: tuple, b: tuple) -> float:
    """Signed speed (m/s) along the mean heading between poses a and b ``(t, x, y, yaw)``."""
    mid = a[3] + 0.5 * math.remainder(b[3] - a[3], 2.0 * math.pi)
    return ((b[1] - a[1]) * math.cos(mid) + (b[2] - a[2]) * math.sin(mid)) / (b[0] - a[0])


def _turn(a: tuple, b: tuple) -> float:
    return math.remainder(b[3] - a[3], 2.0 * math.pi) / (b[0] - a[0])


def travelled(motion: EgoMotion, times: np.ndarray) -> np.ndarray:
    """Signed distance (K,) metres along the path after ``times`` (K,) s: ``v t + a t^2 / 2``,
    held once braking reaches a stop (the ego does not reverse by braking)."""
    v, a = motion.speed, motion.acceleration
    t = np.asarray(times, float)
    if a * v < 0:  # braking: stop at -v / a
        t = np.minimum(t, -v / a)
    return v * t + 0.5 * a * t**2


def predict_ego_path(ego: EgoPose, motion: EgoMotion, times: np.ndarray) -> EgoPath:
    """The path at ``times`` (K,) s ahead from the pose now: an arc of the curvature now (yaw rate
    over speed), along which the ego covers :func:`travelled`."""
    times = np.asarray(times, float)
    s = travelled(motion, times)
    last = float(s[-1])
    direction = -1.0 if last < 0 or (last == 0 and motion.speed < 0) else 1.0
    dist = np.abs(s)
    speed = abs(motion.speed)
    curvature = motion.yaw_rate / speed if speed > 1e-3 else 0.0
    yaw = ego.yaw
    heading = yaw + (0.0 if direction > 0 else math.pi)
    turn = curvature * dist
    xy = np.empty((len(times), 2))
    if abs(curvature) < 1e-6:
        xy[:, 0] = ego.translation[0] + dist * math.cos(heading)
        xy[:, 1] = ego.translation[1] + dist * math.sin(heading)
    else:
        xy[:, 0] = ego.translation[0] + (np.sin(heading + turn) - math.sin(heading)) / curvature
        xy[:, 1] = ego.translation[1] + (math.cos(heading) - np.cos(heading + turn)) / curvature
    lateral = np.hypot((0.5 * motion.yaw_rate_std) * times * dist,
                       (0.5 * motion.speed_std) * times * np.abs(np.sin(turn)))
    return EgoPath(times, xy, yaw + turn, lateral, motion, curvature, float(dist[-1]), direction)
