"""Pedestrians of a synthetic scene: who they are and where they walk, vectorized.

Each pedestrian follows a polyline of waypoints at a constant speed. Before its start
time it stands at the point ``offset`` metres along the path (a pedestrian waiting at
the kerb, or one already walking when the scene begins); after the path's end it
stands there. A speed of 0 makes a standing pedestrian.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Body height distribution of adults (metres): mean, standard deviation, clip range.
HEIGHT_MEAN_M, HEIGHT_SD_M, HEIGHT_RANGE_M = 1.72, 0.09, (1.50, 1.98)
#: Walking speeds are uniform in this range (m/s).
WALKING_SPEED_RANGE_MPS = (1.0, 1.6)


@dataclass(frozen=True)
class PedestrianState:
    """Where the pedestrians are at one time.

    xy: (N, 2) world frame, metres. heading: (N,) radians, counter-clockwise from +x.
    walked: (N,) metres along the path. moving: (N,) bool, walking at this instant.
    """

    xy: np.ndarray
    heading: np.ndarray
    walked: np.ndarray
    moving: np.ndarray


@dataclass(frozen=True)
class Pedestrians:
    """A group of pedestrians and their paths.

    waypoints: (N, K, 2) world x-y, metres (short paths repeat their last point).
    speeds: (N,) m/s while walking. start_times: (N,) seconds. offsets: (N,) metres
    along the path at the start time. heights: (N,) metres. phases: (N,) radians, gait
    phase at the path's start. sway_phases: (N,) radians, phase of the standing sway.
    """

    waypoints: np.ndarray
    speeds: np.ndarray
    start_times: np.ndarray
    offsets: np.ndarray
    heights: np.ndarray
    phases: np.ndarray
    sway_phases: np.ndarray

    def __len__(self) -> int:
        return self.speeds.shape[0]

    def at(self, t: float) -> PedestrianState:
        """Positions and headings at time ``t`` (seconds)."""
        seg = np.diff(self.waypoints, axis=1)  # (N, K-1, 2)
        seg_len = np.linalg.norm(seg, axis=2)
        cum = np.concatenate([np.zeros((len(self), 1)), np.cumsum(seg_len, axis=1)], axis=1)  # (N, K)
        total = cum[:, -1]
        walking = self.speeds * np.maximum(t - self.start_times, 0.0)
        s = np.minimum(self.offsets + walking, total)
        i = np.clip((cum[:, 1:] <= s[:, None]).sum(axis=1), 0, seg.shape[1] - 1)
        # the segment at s, skipping zero-length padding at the end of short paths
        longest = np.where(seg_len > 1e-9, np.arange(seg.shape[1]), -1)
        last_real = np.maximum(longest.max(axis=1), 0)
        i = np.minimum(i, last_real)
        rows = np.arange(len(self))
        d = seg[rows, i]
        length = np.maximum(seg_len[rows, i], 1e-12)
        xy = self.waypoints[rows, i] + d * ((s - cum[rows, i]) / length)[:, None]
        heading = np.arctan2(d[:, 1], d[:, 0])
        moving = (self.speeds > 0) & (t >= self.start_times) & (s < total)
        return PedestrianState(xy, heading, s, moving)


def concat(*groups: Pedestrians) -> Pedestrians:
    """All pedestrians of ``groups`` in one group (paths padded to one length)."""
    k = max(g.waypoints.shape[1] for g in groups)
    padded = [np.concatenate([g.waypoints, np.repeat(g.waypoints[:, -1:], k - g.waypoints.shape[1], axis=1)], axis=1)
              for g in groups]
    return Pedestrians(np.concatenate(padded), *(np.concatenate([getattr(g, f) for g in groups])
                       for f in ("speeds", "start_times", "offsets", "heights", "phases", "sway_phases")))


def sample_heights(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n,) adult body heights in metres: normal, clipped to :data:`HEIGHT_RANGE_M`."""
    return np.clip(rng.normal(HEIGHT_MEAN_M, HEIGHT_SD_M, n), *HEIGHT_RANGE_M)


def make_group(rng: np.random.Generator, waypoints: np.ndarray, *, walking: bool | np.ndarray = True,
               start_times: np.ndarray | float = 0.0, offsets: np.ndarray | float = 0.0) -> Pedestrians:
    """Pedestrians on ``waypoints`` (n, K, 2) with random heights, speeds and gait phases.

    ``walking`` (bool or (n,) bool) marks who walks; the others stand at their offset.
    """
    waypoints = np.asarray(waypoints, float)
    n = waypoints.shape[0]
    speeds = rng.uniform(*WALKING_SPEED_RANGE_MPS, n) * np.broadcast_to(walking, (n,))
    return Pedestrians(
        waypoints, speeds, np.broadcast_to(np.asarray(start_times, float), (n,)).copy(),
        np.broadcast_to(np.asarray(offsets, float), (n,)).copy(), sample_heights(rng, n),
        rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 2 * np.pi, n))
