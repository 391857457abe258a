"""The camera as detection sees it, and the ground band where people can stand.

:class:`CameraGeometry` (intrinsics, tilt relative to gravity, height) is computed once per
frame (:meth:`CameraGeometry.from_frame`) and handed to every pass planner; the *ground band*
(:func:`far_band`: the image rows where a person ``near_m``..``far_m`` away stands) is derived
from it once per frame too (:class:`FrameBand`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pedenv.detection.config import BAND_MARGIN_PX, MAX_PITCH_DOWN_DEG, MAX_PITCH_UP_DEG, TOP_M

if TYPE_CHECKING:
    from pedenv.detection.config import DetectionConfig
    from pedenv.records import Camera, Frame


@dataclass(frozen=True)
class CameraGeometry:
    """What the band needs: intrinsics, the camera's tilt relative to gravity and its height.

    K: (3, 3) pixels. cam_to_level: (3, 3) rotation, optical camera frame (x right, y down,
    z forward) -> a frame with z up (gravity-aligned; its yaw does not matter).
    height_m: camera height above the ground under it, metres.
    """

    K: np.ndarray
    cam_to_level: np.ndarray
    height_m: float

    @classmethod
    def level(cls, K: np.ndarray, height_m: float, pitch_down_rad: float = 0.0,
              roll_rad: float = 0.0) -> CameraGeometry:
        """A camera ``height_m`` above flat ground, pitched down by ``pitch_down_rad``, rolled by ``roll_rad``."""
        base = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])  # optical -> (x right, y forward, z up)
        cp, sp, cr, sr = math.cos(pitch_down_rad), math.sin(pitch_down_rad), math.cos(roll_rad), math.sin(roll_rad)
        pitch = np.array([[1, 0, 0], [0, cp, sp], [0, -sp, cp]])  # about x: forward axis goes down
        roll = np.array([[cr, 0, sr], [0, 1, 0], [-sr, 0, cr]])  # about the forward axis
        return cls(np.asarray(K, float), pitch @ roll @ base, float(height_m))

    @classmethod
    def of_camera(cls, camera: Camera) -> CameraGeometry:
        """From a :class:`~pedenv.records.Camera` on a level vehicle (its mount's rotation and height)."""
        mount = camera.cam_to_vehicle
        return cls(np.asarray(camera.intrinsics, float), mount[:3, :3], float(mount[2, 3]))

    @classmethod
    def from_frame(cls, frame: Frame) -> CameraGeometry:
        """From a :class:`~pedenv.records.Frame`: camera intrinsics and mount, ego pitch and roll."""
        cam_to_vehicle = frame.camera.cam_to_vehicle
        rotation = frame.ego.rotation @ cam_to_vehicle[:3, :3]
        height = float((frame.ego.rotation @ cam_to_vehicle[:3, 3])[2])
        return cls(np.asarray(frame.camera.intrinsics, float), rotation, height)


@dataclass(frozen=True)
class Band:
    """Rows ``[top, bottom)`` of the image where far people can stand, or the reason there is none."""

    top: int
    bottom: int
    reason: str = ""


def usable_calibration(geometry: CameraGeometry | None) -> bool:
    """Whether the calibration can place the far band: given, the camera above the ground,
    tilted down by at most ``max_pitch_down_deg`` and up by at most ``max_pitch_up_deg``."""
    if geometry is None or geometry.height_m <= 0:
        return False
    pitch_down = math.degrees(math.asin(float(np.clip(-geometry.cam_to_level[2, 2], -1.0, 1.0))))
    return pitch_down <= MAX_PITCH_DOWN_DEG and -pitch_down <= MAX_PITCH_UP_DEG


def ground_rows(geometry: CameraGeometry, width: int, height: int, near_m: float, far_m: float,
                max_height_px: float = math.inf) -> Band | None:
    """Rows where a person ``near_m``..``far_m`` away stands (the ground there up to ``top_m``,
    or up to the height a person ``max_height_px`` tall in the image has there, if lower;
    +-72 deg around the optical axis, plus ``band_margin_px``); None when they miss the image."""
    R, K = geometry.cam_to_level, geometry.K
    forward = R[:, 2]
    horizontal = np.array([forward[0], forward[1], 0.0])
    horizontal /= max(float(np.linalg.norm(horizontal)), 1e-9)
    left = np.cross([0.0, 0.0, 1.0], horizontal)
    d = np.geomspace(near_m, far_m, 24)[:, None, None]
    lateral = np.linspace(-3.0, 3.0, 61)[None, :, None] * d  # +-72 deg around the axis
    head_m = np.minimum(TOP_M, max_height_px * d / float(K[1, 1]))  # (24, 1, 1) metres
    z = np.concatenate(np.broadcast_arrays(np.full_like(head_m, -geometry.height_m), head_m - geometry.height_m),
                       axis=2)
    points = d[..., None] * horizontal + lateral[..., None] * left + z[..., None] * np.array([0, 0, 1.0])
    cam = points.reshape(-1, 3) @ R  # level -> camera: R^T p, as row vectors
    ahead = cam[:, 2] > 0.1
    uv = cam[ahead] @ K.T
    uv = uv[:, :2] / uv[:, 2:3]
    inside = (uv[:, 0] >= 0) & (uv[:, 0] <= width)
    if not inside.any():
        return None
    top = int(math.floor(uv[inside, 1].min())) - BAND_MARGIN_PX
    bottom = int(math.ceil(uv[inside, 1].max())) + BAND_MARGIN_PX
    top, bottom = max(top, 0), min(bottom, height)
    if bottom - top < 8:
        return None  # the band lies above or below the image
    return Band(top, bottom)


def far_band(geometry: CameraGeometry | None, width: int, height: int, config: DetectionConfig) -> Band | None:
    """The image rows where a person ``near_m``..``far_m`` away stands; None -> no usable band.

    None comes back (with no error) for: no calibration, a camera looking down by more than
    ``max_pitch_down_deg`` or up by more than ``max_pitch_up_deg``, a camera below the
    ground, or a band that lies wholly above or below the image.
    """
    if not usable_calibration(geometry):
        return None
    assert geometry is not None
    return ground_rows(geometry, width, height, config.near_m, config.far_m)


