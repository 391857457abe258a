"""The GPS/IMU motion that visual odometry is measured against: KITTI's OXTS records (pure functions).

An OXTS file holds one line of 30 numbers per frame (KITTI's ``oxts/dataformat.txt``): lat, lon
(degrees), alt (m), roll, pitch, yaw (rad, yaw 0 = east, counter-clockwise), vn, ve, vf, vl,
vu (m/s), ... Positions are projected as KITTI's devkit does (``latToScale``, ``latlonToMercator``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pedenv.errors import InputError
from pedenv.geometry import wrap_angle

#: The earth's radius in KITTI's devkit (``convertOxtsToPose``), metres.
EARTH_RADIUS_M = 6378137.0
OXTS_VALUES = 30


def read_oxts(paths: list[Path] | Path) -> np.ndarray:
    """(N, 30) OXTS values: the lines of one file (tracking's ``oxts/<seq>.txt``) or one line per file
    (raw's ``oxts/data/*.txt``, given in frame order)."""
    files = [paths] if isinstance(paths, Path) else list(paths)
    rows = [line.split() for f in files for line in Path(f).read_text().splitlines() if line.strip()]
    if not rows or any(len(r) != OXTS_VALUES for r in rows):
        raise InputError(f"{files[0]}: OXTS lines must hold {OXTS_VALUES} numbers each")
    return np.array(rows, dtype=np.float64)


def mercator_positions(oxts: np.ndarray) -> np.ndarray:
    """(N, 2) east and north metres of the rows' lat/lon, with the first row's Mercator scale (KITTI devkit)."""
    lat, lon = oxts[:, 0], oxts[:, 1]
    scale = np.cos(np.radians(lat[0]))
    east = scale * np.radians(lon) * EARTH_RADIUS_M
    north = scale * EARTH_RADIUS_M * np.log(np.tan(np.radians(90.0 + lat) / 2.0))
    return np.column_stack([east, north])


def travelled(positions: np.ndarray) -> float:
    """The length of the path through ``positions`` (N, 2 or 3), metres."""
    return float(np.linalg.norm(np.diff(positions, axis=0), axis=1).sum())


def integrated_distance(oxts: np.ndarray, times: np.ndarray) -> float:
    """The distance travelled, metres: the speed over the ground (``vf``, ``vl``) integrated over the
    rows' ``times`` (N,) seconds (trapezoids); free of the GPS positions' timing jitter."""
    speed = np.hypot(oxts[:, 8], oxts[:, 9])
    return float(np.sum(0.5 * (speed[1:] + speed[:-1]) * np.diff(times)))


def yaw_change(oxts: np.ndarray) -> float:
    """The heading's change from the first row to the last, radians (counter-clockwise positive)."""
    return float(wrap_angle(oxts[-1, 5] - oxts[0, 5]))
