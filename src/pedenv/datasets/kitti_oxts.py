"""KITTI OXTS (GPS/IMU) files as camera poses, for sequences without an ORB-SLAM3 trajectory.

One line per frame, 30 numbers (KITTI raw ``oxts`` format): latitude, longitude (degrees),
altitude (m), roll, pitch, yaw (radians), then velocities, accelerations, rates and the fix's
flags. The devkit's conversion: a Mercator projection scaled at the first frame's latitude
gives the IMU's metric position, ``Rz(yaw) Ry(pitch) Rx(roll)`` its rotation; the camera's pose is
the IMU's times the calibration's ``cam0 <- IMU`` (``R0_rect Tr_velo_to_cam Tr_imu_to_velo``),
taken relative to frame 0 as :func:`pedenv.datasets.kitti_files.read_camera_trajectory` gives it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pedenv.datasets.kitti_files import KittiCalib
from pedenv.datasets.text_fields import numbers, read_lines
from pedenv.errors import InputError

#: Earth radius of the KITTI devkit's Mercator conversion (m).
EARTH_RADIUS_M = 6378137.0
#: The most the IMU may move between two frames at 10 Hz (m): 60 m/s. More is a GPS jump.
MAX_STEP_M = 6.0
OXTS_FIELDS = 30


def read_oxts_camera_poses(path: str | Path, calib: KittiCalib) -> np.ndarray:
    """(F, 4, 4) ``T_world_from_cam0`` per line of the OXTS file at ``path``, world = cam0 at frame 0."""
    path = Path(path)
    imu: list[np.ndarray] = []
    scale = 1.0
    for line, text in read_lines(path):
        values = numbers(path, line, text.split(), "OXTS fields")
        if values.size != OXTS_FIELDS:
            raise InputError(f"{path}:{line}: an OXTS line has {OXTS_FIELDS} numbers, got {values.size}")
        lat, lon, alt, roll, pitch, yaw = values[:6]
        if abs(lat) > 85.0 or abs(lon) > 180.0 or abs(alt) > 10_000.0 or np.any(np.abs(values[3:6]) > 2 * np.pi):
            raise InputError(f"{path}:{line}: latitude, longitude, altitude or roll/pitch/yaw out of range")
        if not imu:
            scale = float(np.cos(np.radians(lat)))  # the Mercator scale of the first frame, for all
        pose = _imu_pose(lat, lon, alt, roll, pitch, yaw, scale)
        step = np.linalg.norm(pose[:3, 3] - imu[-1][:3, 3]) if imu else 0.0
        if step > MAX_STEP_M:
            raise InputError(f"{path}:{line}: the position jumps {step:.1f} m from the line before "
                             f"(at most {MAX_STEP_M:g} m in one 0.1 s frame)")
        imu.append(pose)
    if not imu:
        raise InputError(f"{path}: no OXTS lines")
    cam_from_imu = _homogeneous(calib.R0_rect) @ _homogeneous(calib.Tr_velo_to_cam) @ _homogeneous(calib.Tr_imu_to_velo)
    imu_from_cam = np.linalg.inv(cam_from_imu)
    world = np.stack(imu) @ imu_from_cam
    return np.linalg.inv(world[0]) @ world


def _imu_pose(lat: float, lon: float, alt: float, roll: float, pitch: float, yaw: float, scale: float) -> np.ndarray:
    x = scale * EARTH_RADIUS_M * np.radians(lon)
    y = scale * EARTH_RADIUS_M * np.log(np.tan(np.radians(90.0 + lat) / 2.0))
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    pose = np.eye(4)
    pose[:3, :3] = rz @ ry @ rx
    pose[:3, 3] = [x, y, alt]
    return pose


def _homogeneous(m: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[: m.shape[0], : m.shape[1]] = m
    return out
