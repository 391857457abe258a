"""The static camera's geometry: (f, H, tilt, roll) -> rotation, projection, the ground under a pixel.

Angles in radians; tilt > 0 looks down. The world is the ground under the camera (z = 0), x the
horizontal viewing direction, y left, z up; the camera sits at (0, 0, H).
"""

from __future__ import annotations

import numpy as np

from pedenv.records import OPTICAL_TO_VEHICLE, Camera


def camera_rotation(tilt: float, roll: float) -> np.ndarray:
    """(3, 3) optical camera axes (x right, y down, z forward) -> world: rolled about the
    optical axis by ``roll``, then pitched down by ``tilt`` about the world's y axis."""
    ct, st, cr, sr = np.cos(tilt), np.sin(tilt), np.cos(roll), np.sin(roll)
    pitch = np.array([[ct, 0.0, st], [0.0, 1.0, 0.0], [-st, 0.0, ct]])
    rolled = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return pitch @ rolled @ OPTICAL_TO_VEHICLE


def intrinsics(focal: float, centre: tuple[float, float]) -> np.ndarray:
    """(3, 3) camera matrix, square pixels, principal point ``centre`` (u, v) pixels."""
    return np.array([[focal, 0.0, centre[0]], [0.0, focal, centre[1]], [0.0, 0.0, 1.0]])


def project(points: np.ndarray, k: np.ndarray, rotation: np.ndarray, height: float) -> np.ndarray:
    """World points (N, 3) metres -> pixels (N, 2) of the camera at (0, 0, ``height``); points
    behind the camera come out NaN."""
    cam = (points - np.array([0.0, 0.0, height])) @ rotation  # rows: rotation.T @ (p - c)
    z = cam[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = (cam @ k.T)[:, :2] / z[:, None]
    uv[z <= 1e-6] = np.nan
    return uv


def ground_points(pixels: np.ndarray, k: np.ndarray, rotation: np.ndarray, height: float,
                  plane_z: np.ndarray | float = 0.0) -> np.ndarray:
    """Pixels (N, 2) -> (N, 3) world points where their rays cut the plane z = ``plane_z``
    (metres, per pixel or one); rays that do not reach the plane ahead come out NaN."""
    rays = np.concatenate([pixels, np.ones((len(pixels), 1))], axis=1) @ np.linalg.inv(k).T @ rotation.T
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = (np.asarray(plane_z, float) - height) / rays[:, 2]
    scale = np.where(scale > 0, scale, np.nan)
    return np.array([0.0, 0.0, height]) + rays * scale[:, None]


def horizon_line(k: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """The horizon as a homogeneous image line (3,) (a u + b v + c = 0, (a, b) unit length)."""
    normal = rotation.T @ np.array([0.0, 0.0, 1.0])  # world up in camera axes
    line = np.linalg.inv(k).T @ normal
    return line / np.hypot(line[0], line[1])


def static_camera(focal: float, height: float, tilt: float, roll: float, size: tuple[int, int],
                  centre: tuple[float, float] | None = None) -> Camera:
    """The :class:`~pedenv.records.Camera` (``mount: static``) of these parameters; ``size`` (width,
    height) pixels, ``centre`` the principal point (default: the image centre)."""
    c = centre if centre is not None else (size[0] / 2.0, size[1] / 2.0)
    mount = np.eye(4)
    mount[:3, :3] = camera_rotation(tilt, roll)
    mount[:3, 3] = [0.0, 0.0, height]
    return Camera(intrinsics(focal, c), size[0], size[1], mount, "static")


def parameters_of(camera: Camera) -> tuple[float, float, float, float]:
    """(focal, height, tilt, roll) of a camera's mounting (the inverse of :func:`static_camera`
    for a camera looking along the world's x axis; its yaw is ignored)."""
    r = camera.cam_to_vehicle[:3, :3]
    forward = r[:, 2]
    tilt = float(np.arcsin(np.clip(-forward[2], -1.0, 1.0)))
    yaw = np.arctan2(forward[1], forward[0])
    cy, sy = np.cos(-yaw), np.sin(-yaw)
    unyawed = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]]) @ r
    ct, st = np.cos(tilt), np.sin(tilt)
    unpitched = np.array([[ct, 0.0, -st], [0.0, 1.0, 0.0], [st, 0.0, ct]]) @ unyawed
    rolled = unpitched @ OPTICAL_TO_VEHICLE.T
    roll = float(np.arctan2(rolled[2, 1], rolled[1, 1]))
    return float(camera.intrinsics[0, 0]), float(camera.cam_to_vehicle[2, 3]), tilt, roll
