"""Unreal Engine / CARLA axes and pedenv's axes, converted both ways.

CARLA (Unreal) is left-handed: x forward, y right, z up, metres, angles in degrees. pedenv's
world is right-handed z up. Flipping y maps one to the other:
``p_ours = FLIP_Y @ p_unreal`` for points, ``R_ours = FLIP_Y @ R_unreal @ FLIP_Y`` for rotations
(which gives ``yaw_ours = -yaw``, ``pitch_ours = -pitch`` with pedenv's nose-down-positive pitch,
``roll_ours = roll``). CARLA's camera-local axes are x forward, y right, z up; the recording
script takes ``(y, -z, x)`` as the optical frame (x right, y down, z forward).

Checked against the independently generated recording in ``shared/samples/carla-recording``:
the converted bones project onto ``2d_skel`` with 0.20 px RMS (the generator's noise).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

#: (3, 3) reflection of the y axis: Unreal's world <-> pedenv's world (its own inverse).
FLIP_Y = np.diag([1.0, -1.0, 1.0])

#: (3, 3) optical camera axes -> CARLA camera-local axes: local = OPTICAL_TO_UNREAL_CAM @ optical.
OPTICAL_TO_UNREAL_CAM = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def carla_rotation(yaw_deg: float, pitch_deg: float, roll_deg: float) -> np.ndarray:
    """(3, 3) rotation of a CARLA transform, as ``carla.Transform.get_matrix()`` builds it (Unreal axes).

    That matrix is ``Rz(yaw) Ry(-pitch) Rx(-roll)`` in the usual right-hand-rule matrices
    (CARLA's pitch and roll turn the other way round); the test compares it entry by entry.
    """
    return Rotation.from_euler("ZYX", [yaw_deg, -pitch_deg, -roll_deg], degrees=True).as_matrix()


def carla_ypr(rotation: np.ndarray) -> np.ndarray:
    """(3,) yaw, pitch, roll in degrees of a (3, 3) CARLA rotation (inverse of :func:`carla_rotation`).

    Pitch lies in [-90, 90] degrees, yaw and roll in [-180, 180].
    """
    yaw, pitch, roll = Rotation.from_matrix(np.asarray(rotation, float)).as_euler("ZYX", degrees=True)
    return np.array([yaw, -pitch, -roll])


def points_from_unreal(points: np.ndarray) -> np.ndarray:
    """(..., 3) Unreal world points, metres -> pedenv world points (flip y). Also the reverse."""
    return np.asarray(points, float) * np.array([1.0, -1.0, 1.0])


points_to_unreal = points_from_unreal


def ego_from_unreal(xyz: np.ndarray, yaw_pitch_roll_deg: np.ndarray) -> np.ndarray:
    """(4, 4) vehicle -> pedenv world of CARLA's ``ego_pos`` (location (3,), yaw/pitch/roll degrees)."""
    m = np.eye(4)
    m[:3, :3] = FLIP_Y @ carla_rotation(*np.asarray(yaw_pitch_roll_deg, float)) @ FLIP_Y
    m[:3, 3] = points_from_unreal(xyz)
    return m


def ego_to_unreal(vehicle_to_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CARLA's ``(xyz (3,), yaw_pitch_roll (3,) degrees)`` of a (4, 4) pedenv vehicle -> world pose."""
    m = np.asarray(vehicle_to_world, float)
    return points_to_unreal(m[:3, 3]), carla_ypr(FLIP_Y @ m[:3, :3] @ FLIP_Y)


def cam_to_world_from_unreal(cam2world: np.ndarray) -> np.ndarray:
    """(4, 4) optical camera -> pedenv world, from CARLA's (4, 4) ``cam2world`` (camera-local -> Unreal world)."""
    c = np.asarray(cam2world, float)
    m = np.eye(4)
    m[:3, :3] = FLIP_Y @ c[:3, :3] @ OPTICAL_TO_UNREAL_CAM
    m[:3, 3] = points_from_unreal(c[:3, 3])
    return m


def cam_to_world_to_unreal(cam_to_world: np.ndarray) -> np.ndarray:
    """CARLA's (4, 4) ``cam2world`` from a (4, 4) pedenv optical camera -> world transform."""
    c = np.asarray(cam_to_world, float)
    m = np.eye(4)
    m[:3, :3] = FLIP_Y @ c[:3, :3] @ OPTICAL_TO_UNREAL_CAM.T
    m[:3, 3] = points_to_unreal(c[:3, 3])
    return m


def project_unreal(points: np.ndarray, intrinsics: np.ndarray, world2cam: np.ndarray) -> np.ndarray:
    """Pixels of Unreal world points the way the recording script computes them.

    points: (..., 3) Unreal world, metres. world2cam: (4, 4) CARLA. Returns (..., 2) pixels
    (not clamped; points behind the camera give meaningless pixels).
    """
    local = np.asarray(points, float) @ world2cam[:3, :3].T + world2cam[:3, 3]
    optical = np.stack([local[..., 1], -local[..., 2], local[..., 0]], axis=-1)
    uvw = optical @ np.asarray(intrinsics, float).T
    depth = np.where(np.abs(uvw[..., 2:3]) < 1e-12, 1e-12, uvw[..., 2:3])
    return uvw[..., :2] / depth
