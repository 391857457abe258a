"""The per-camera JSON files of the nuScenes sample ``nuscenes-0061`` (one keyframe, five cameras).

One ``<CAM>.json`` beside ``<image>.jpg`` per camera: intrinsics, camera/ego/global poses
(4x4 matrices) and the pedestrians visible in that camera (3D boxes in the global frame,
their projected 2D boxes). See ``shared/samples/real/README.md`` for the fields.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pedenv.datasets.text_fields import frozen_arrays
from pedenv.errors import InputError


@dataclass(frozen=True)
class NuscenesPedestrians:
    """The pedestrians of one camera (N).

    centers_global: (N, 3) float, gravity centre of the 3D box, global frame (z up), metres.
    sizes_wlh: (N, 3) float, width, length, height in metres. yaws_global: (N,) radians.
    velocities_xy: (N, 2) float m/s, NaN where nuScenes has none.
    centers_cam: (N, 3) float, camera frame (x right, y down, z forward), metres.
    distances_xy: (N,) float, horizontal distance from the ego origin, metres.
    boxes: (N, 4) float, ``bbox_2d`` ``[u_min, v_min, u_max, v_max]`` pixels (projected 3D box, clipped).
    centerlines: (N, 2, 2) float, pixels of the box's top and bottom centre. heights_px: (N,) float.
    num_lidar_pts, num_radar_pts: (N,) int64. attributes: (N,) str.
    """

    centers_global: np.ndarray
    sizes_wlh: np.ndarray
    yaws_global: np.ndarray
    velocities_xy: np.ndarray
    centers_cam: np.ndarray
    distances_xy: np.ndarray
    boxes: np.ndarray
    centerlines: np.ndarray
    heights_px: np.ndarray
    num_lidar_pts: np.ndarray
    num_radar_pts: np.ndarray
    attributes: np.ndarray

    def __post_init__(self) -> None:
        frozen_arrays(self, **{name: getattr(self, name) for name in self.__dataclass_fields__})

    def __len__(self) -> int:
        return len(self.boxes)

    @property
    def ground_points_global(self) -> np.ndarray:
        """(N, 3) bottom centres of the boxes (centre minus half the height), global frame, metres."""
        return self.centers_global - np.c_[np.zeros((len(self), 2)), self.sizes_wlh[:, 2] / 2]


@dataclass(frozen=True)
class NuscenesCamera:
    """One camera image of the keyframe.

    K: (3, 3) intrinsics, pixels. cam_to_ego, ego_to_global, cam_to_global: (4, 4) rigid
    transforms (camera frame x right, y down, z forward; ego x forward, y left, z up).
    timestamp_us: exposure time, integer microseconds.
    """

    camera: str
    image_path: Path
    width: int
    height: int
    timestamp_us: int
    K: np.ndarray
    cam_to_ego: np.ndarray
    ego_to_global: np.ndarray
    cam_to_global: np.ndarray
    pedestrians: NuscenesPedestrians


def _matrix(path: Path, data: dict, key: str, shape: tuple[int, int]) -> np.ndarray:
    try:
        value = np.asarray(data[key], dtype=np.float64)
    except KeyError:
        raise InputError(f"{path}: missing key {key!r}") from None
    except (TypeError, ValueError):
        raise InputError(f"{path}: {key} must be a {shape[0]}x{shape[1]} matrix of numbers") from None
    if value.shape != shape or not np.all(np.isfinite(value)):
        raise InputError(f"{path}: {key} must be a finite {shape[0]}x{shape[1]} matrix, got shape {value.shape}")
    return value


def _pedestrians(path: Path, entries: object) -> NuscenesPedestrians:
    if not isinstance(entries, list):
        raise InputError(f"{path}: 'pedestrians' must be a list")
    columns: dict[str, list] = {name: [] for name in NuscenesPedestrians.__dataclass_fields__}
    for i, p in enumerate(entries):
        where = f"{path}: pedestrians[{i}]"
        try:
            velocity = p["velocity_global_xy"]
            row = {
                "centers_global": (p["center_global"], (3,)),
                "sizes_wlh": (p["size_wlh"], (3,)),
                "yaws_global": (p["yaw_global"], ()),
                "velocities_xy": ([np.nan, np.nan] if velocity is None else velocity, (2,)),
                "centers_cam": (p["center_cam"], (3,)),
                "distances_xy": (p["distance_from_ego_xy_m"], ()),
                "boxes": (p["bbox_2d"], (4,)),
                "centerlines": (p["centerline_2d"], (2, 2)),
                "heights_px": (p["height_px"], ()),
                "num_lidar_pts": (p["num_lidar_pts"], ()),
                "num_radar_pts": (p["num_radar_pts"], ()),
            }
            attribute = str(p["attribute"])
        except (KeyError, TypeError) as exc:
            raise InputError(f"{where}: missing or bad key {exc}") from None
        for name, (value, shape) in row.items():
            try:
                array = np.asarray(value, dtype=np.float64)
            except (TypeError, ValueError):
                raise InputError(f"{where}: {name} must be numeric, got {value!r}") from None
            if array.shape != shape or (name != "velocities_xy" and not np.all(np.isfinite(array))):
                raise InputError(f"{where}: {name} must be finite with shape {shape}, got {array.shape}")
            columns[name].append(array)
        columns["attributes"].append(attribute)
    out = {}
    for name, values in columns.items():
        shape = {"centers_global": (0, 3), "sizes_wlh": (0, 3), "velocities_xy": (0, 2), "centers_cam": (0, 3),
                 "boxes": (0, 4), "centerlines": (0, 2, 2)}.get(name, (0,))
        out[name] = np.array(values).reshape((-1,) + shape[1:]) if values else np.zeros(shape)
    out["num_lidar_pts"] = out["num_lidar_pts"].astype(np.int64)
    out["num_radar_pts"] = out["num_radar_pts"].astype(np.int64)
    out["attributes"] = np.array(columns["attributes"], dtype=str)
    return NuscenesPedestrians(**out)


def read_camera(path: str | Path) -> NuscenesCamera:
    """Read one ``<CAM>.json``; its image must lie beside it."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{path}: not readable JSON: {exc}") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: the top level must be an object")
    for key in ("camera", "image", "width", "height", "timestamp_us", "pedestrians"):
        if key not in data:
            raise InputError(f"{path}: missing key {key!r}")
    for key in ("width", "height", "timestamp_us"):
        if isinstance(data[key], bool) or not isinstance(data[key], int) or data[key] <= 0:
            raise InputError(f"{path}: {key} must be a positive integer, got {data[key]!r}")
    image = path.parent / str(data["image"])
    if not image.is_file():
        raise InputError(f"{path}: image {image.name} not found beside it")
    return NuscenesCamera(str(data["camera"]), image, data["width"], data["height"], data["timestamp_us"],
                          _matrix(path, data, "K", (3, 3)), _matrix(path, data, "cam_to_ego", (4, 4)),
                          _matrix(path, data, "ego_to_global", (4, 4)), _matrix(path, data, "cam_to_global", (4, 4)),
                          _pedestrians(path, data["pedestrians"]))


def read_cameras(folder: str | Path) -> list[NuscenesCamera]:
    """Every ``*.json`` camera file in ``folder``, sorted by camera name."""
    folder = Path(folder)
    files = sorted(folder.glob("*.json"))
    if not files:
        raise InputError(f"{folder}: no <CAM>.json camera files")
    return sorted((read_camera(f) for f in files), key=lambda c: c.camera)
