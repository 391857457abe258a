"""The ego's own path, predicted from its recent poses: speed and yaw rate, then a constant turn.

Speeds are signed along the ego's heading (negative: reversing); yaw in radians, world frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.behaviour.config import BehaviourConfig
from pedenv.records import EgoPose

#: With no motion known (the first frame, after a gap) the spreads are this many times the configured ones.
UNKNOWN_MOTION_FACTOR = 5.0


@dataclass(frozen=True)
class EgoMotion:
    """The ego's motion now: speed (m/s, signed), yaw rate (rad/s), their standard deviations
    over the prediction, and whether they were measured (False: unknown, taken as standing)."""

    speed: float
    yaw_rate: float
    speed_std: float
    yaw_rate_std: float
    known: bool


@dataclass(frozen=True)
class EgoPath:
    """The ego's predicted path: times (K,) s ahead, xy (K, 2) world metres, yaw (K,) radians,
    lateral_std (K,) metres (how far it may lie sideways of this), motion (what it came from)."""

    times: np.ndarray
    xy: np.ndarray
    yaw: np.ndarray
    lateral_std: np.ndarray
    motion: EgoMotion


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
        """Speed and yaw rate from the oldest and newest pose of the window; a yaw rate beyond
        ``max_yaw_rate_radps`` (a spike) is clipped and its spread widened by the excess."""
        cfg = self.config
        if len(self.poses) < 2 or self.poses[-1][0] - self.poses[0][0] <= 1e-6:
            return EgoMotion(0.0, 0.0, UNKNOWN_MOTION_FACTOR * cfg.ego_speed_std_mps,
                             UNKNOWN_MOTION_FACTOR * cfg.ego_yaw_rate_std_radps, False)
        (t0, x0, y0, a0), (t1, x1, y1, a1) = self.poses[0], self.poses[-1]
        dt, turn = t1 - t0, float(np.angle(np.exp(1j * (a1 - a0))))
        mid = a0 + 0.5 * turn
        speed = ((x1 - x0) * np.cos(mid) + (y1 - y0) * np.sin(mid)) / dt
        rate = turn / dt
        clipped = float(np.clip(rate, -cfg.max_yaw_rate_radps, cfg.max_yaw_rate_radps))
        return EgoMotion(float(speed), clipped, cfg.ego_speed_std_mps,
                         cfg.ego_yaw_rate_std_radps + abs(rate - clipped), True)


def predict_ego_path(ego: EgoPose, motion: EgoMotion, times: np.ndarray) -> EgoPath:
    """The path at ``times`` (K,) s ahead, from the pose now, at constant speed and yaw rate."""
    yaw = ego.yaw + motion.yaw_rate * times
    w = motion.yaw_rate
    if abs(w) < 1e-6:
        dx, dy = motion.speed * times * np.cos(ego.yaw), motion.speed * times * np.sin(ego.yaw)
    else:
        dx = motion.speed / w * (np.sin(yaw) - np.sin(ego.yaw))
        dy = motion.speed / w * (np.cos(ego.yaw) - np.cos(yaw))
    xy = ego.translation[None, :2] + np.column_stack([dx, dy])
    lateral = np.sqrt((0.5 * abs(motion.speed) * motion.yaw_rate_std * times**2) ** 2
                      + (0.5 * motion.speed_std * times * np.abs(np.sin(motion.yaw_rate * times))) ** 2)
    return EgoPath(np.asarray(times, float), xy, yaw, lateral, motion)
