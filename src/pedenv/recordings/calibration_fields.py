"""The fields a calibration YAML may hold, and the sane ranges of their values.

A key not listed in :data:`CALIBRATION_FIELDS` is refused (a typo such as ``focal_lenght``,
or ``distortion`` that pedenv would otherwise ignore silently): to support a new key, add it
here with what it holds (a mapping's own keys go under ``"<key>."``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pedenv.errors import InputError
from pedenv.images import MAX_IMAGE_PIXELS
from pedenv.recordings.ego_poses import MAX_EGO_COORDINATE_M

#: Every key of a calibration file, with what it holds. A key with sub-keys lists them in
#: :data:`CALIBRATION_SUBFIELDS`.
CALIBRATION_FIELDS: dict[str, str] = {
    "width": "image width, pixels",
    "height": "image height, pixels",
    "intrinsics": "3x3 camera matrix, pixels (or fx, fy, cx, cy)",
    "fx": "focal length along u, pixels",
    "fy": "focal length along v, pixels",
    "cx": "principal point u, pixels",
    "cy": "principal point v, pixels",
    "cam_to_vehicle": "the camera's mounting (rotation, translation)",
    "mount": "vehicle (the default) or static (a camera fixed to the ground)",
    "fov_deg": "horizontal field of view, degrees, instead of the intrinsics (principal point at the centre)",
    "camera_position": "[x, y] metres: where a vehicle camera whose mounting is estimated (no cam_to_vehicle) sits "
                       "in the vehicle frame of the ego poses (x forward, y left; a tape measure's figures)",
    "estimated": "true: the camera was estimated from the people seen (pedenv calibrate), not measured",
    "uncertainty": "1-sigma of an estimated camera (focal_px, height_m, tilt_deg, roll_deg)",
}
#: The keys of the calibration's mappings.
CALIBRATION_SUBFIELDS: dict[str, dict[str, str]] = {
    "cam_to_vehicle": {"rotation": "quaternion [w, x, y, z] or 3x3 matrix, optical -> vehicle",
                       "translation": "camera position in the vehicle frame, metres"},
    "uncertainty": {"focal_px": "pixels", "height_m": "metres", "tilt_deg": "degrees", "roll_deg": "degrees"},
}

#: Focal lengths (fx, fy) in pixels: a 100,000 px focal length is a 1 degree field of view
#: on a 2,000 px image; beyond it distances overflow.
FOCAL_RANGE_PX = (1.0, 1e5)
#: Horizontal field of view ``fov_deg``, degrees.
FOV_RANGE_DEG = (1.0, 179.0)
#: Image width and height in pixels.
IMAGE_SIDE_RANGE_PX = (8, 20_000)
#: Farthest camera from the vehicle origin, metres (a camera is mounted on the vehicle). A
#: static camera's ``cam_to_vehicle`` places it in the world: up to
#: :data:`pedenv.recordings.ego_poses.MAX_EGO_COORDINATE_M`.
MAX_MOUNT_DISTANCE_M = 100.0


def check_keys(data: dict, path: Path) -> None:
    """InputError naming the file and the first unknown key of ``data`` (a calibration mapping), or
    ``camera_position`` beside ``cam_to_vehicle`` (both place the camera)."""
    if "camera_position" in data and "cam_to_vehicle" in data:
        raise InputError(f"{path}: calibration fields 'camera_position' and 'cam_to_vehicle' both place the camera: "
                         "give cam_to_vehicle alone, or camera_position to have the rest of the mounting estimated")
    for key, value in data.items():
        if key not in CALIBRATION_FIELDS:
            raise InputError(f"{path}: unknown calibration field {str(key)!r}; fields: {', '.join(CALIBRATION_FIELDS)}")
        sub = CALIBRATION_SUBFIELDS.get(key)
        if sub is not None and isinstance(value, dict):
            for name in value:
                if name not in sub:
                    raise InputError(f"{path}: unknown calibration field '{key}.{name}'; fields of {key!r}: "
                                     f"{', '.join(sub)}")


def check_ranges(path: Path, intrinsics: np.ndarray, width: float, height: float, translation: np.ndarray,
                 static: bool = False) -> None:
    """InputError naming the file and field whose value is outside its sane range (above).

    intrinsics: (3, 3) pixels. width, height: pixels. translation: (3,) metres, of a static
    camera (``static``) in the world frame.
    """
    problem = camera_problem(intrinsics, width, height)
    if problem is not None:
        raise InputError(f"{path}: calibration {problem}")
    distance = float(np.linalg.norm(translation))
    limit = MAX_EGO_COORDINATE_M if static else MAX_MOUNT_DISTANCE_M
    if distance > limit:
        origin = "world" if static else "vehicle"
        raise InputError(f"{path}: calibration field 'cam_to_vehicle.translation' puts the camera {distance:g} m "
                         f"from the {origin} origin; at most {limit:g} m")


def camera_problem(intrinsics: np.ndarray, width: float, height: float) -> str | None:
    """What is outside its sane range in a camera (size, focal lengths, principal point, skew), as
    the end of an error line, or None (the ranges above; a bag's CameraInfo is held to them too).

    intrinsics: (3, 3) pixels. width, height: pixels.
    """
    side_lo, side_hi = IMAGE_SIDE_RANGE_PX
    for name, side in (("width", width), ("height", height)):
        if not side_lo <= side <= side_hi:
            return f"field {name!r} must be in [{side_lo}, {side_hi}] pixels, got {side:g}"
    if width * height > MAX_IMAGE_PIXELS:
        return (f"image size {width:g}x{height:g} is above the limit of {MAX_IMAGE_PIXELS / 1e6:g} megapixels "
                "(pedenv.images.MAX_IMAGE_PIXELS)")
    f_lo, f_hi = FOCAL_RANGE_PX
    for name, f in (("fx", intrinsics[0, 0]), ("fy", intrinsics[1, 1])):
        if not f_lo <= f <= f_hi:
            return f"focal length {name} must be in [{f_lo:g}, {f_hi:g}] pixels, got {f:g}"
    for name, c, side in (("cx", intrinsics[0, 2], width), ("cy", intrinsics[1, 2], height)):
        if not -side <= c <= 2 * side:
            return (f"principal point {name} must be in [-{side:g}, {2 * side:g}] pixels (within an image's size "
                    f"of the image), got {c:g}")
    if abs(intrinsics[0, 1]) > intrinsics[0, 0]:
        return f"skew (intrinsics[0][1]) must be at most fx in size, got {intrinsics[0, 1]:g}"
    return None
