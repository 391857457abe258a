"""KITTI files: calibration, tracking (label_02) and object (label_2) labels, ORB-SLAM3 poses.

Conventions kept as KITTI has them: 2D boxes in image_02 pixels ``[x1, y1, x2, y2]``
clipped to the image; 3D locations are the bottom-face centres of the boxes in the
rectified reference camera frame (x right, y down, z forward, metres).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pedenv.datasets.text_fields import RowTable, numbers, read_lines
from pedenv.errors import InputError

#: Calibration keys -> (shape, accepted spellings: the object benchmark's and the tracking originals').
CALIB_KEYS: dict[str, tuple[tuple[int, int], tuple[str, ...]]] = {
    "P0": ((3, 4), ("P0",)),
    "P1": ((3, 4), ("P1",)),
    "P2": ((3, 4), ("P2",)),
    "P3": ((3, 4), ("P3",)),
    "R0_rect": ((3, 3), ("R0_rect", "R_rect")),
    "Tr_velo_to_cam": ((3, 4), ("Tr_velo_to_cam", "Tr_velo_cam")),
    "Tr_imu_to_velo": ((3, 4), ("Tr_imu_to_velo", "Tr_imu_velo")),
}
#: Object types of the KITTI labels (``Person``: the tracking labels' name for a seated person).
TYPES = ("Car", "Van", "Truck", "Pedestrian", "Person_sitting", "Person", "Cyclist", "Tram", "Misc", "DontCare")

# Bounds of the values a KITTI file may hold (beyond them a file is broken, not a drive): a label's
# frame number (KITTI's longest sequence has 1,059 frames), 3D location (m; labels reach 80 m),
# box size (m), image coordinates (px; images are 1242x375), focal length (px; KITTI 707-721),
# camera offset from cam0 (m; cam3 is 0.54 m away) and a pose's translation (m; drives of a few km).
MAX_FRAME = 1_000_000
MAX_LOCATION_M = 1000.0
MAX_DIMENSION_M = 50.0
MAX_PIXEL = 100_000.0
FOCAL_PX = (10.0, 100_000.0)
MAX_CAMERA_OFFSET_M = 10.0
MAX_TRANSLATION_M = 100_000.0
#: A pose's 3x3 part may differ from a rotation by this much (|R R^T - I|, ORB-SLAM3 writes 9 digits:
#: about 1e-8) and is then made exactly orthonormal; more is a broken file.
ROTATION_TOLERANCE = 1e-5


@dataclass(frozen=True)
class KittiCalib:
    """One KITTI calibration file.

    P0..P3: (3, 4) projection of rectified reference-camera points (metres) to each camera's pixels.
    R0_rect: (3, 3) rectifying rotation; Tr_velo_to_cam, Tr_imu_to_velo: (3, 4) rigid transforms.
    """

    P0: np.ndarray
    P1: np.ndarray
    P2: np.ndarray
    P3: np.ndarray
    R0_rect: np.ndarray
    Tr_velo_to_cam: np.ndarray
    Tr_imu_to_velo: np.ndarray

    @property
    def K(self) -> np.ndarray:
        """(3, 3) intrinsics of image_02 (the left colour camera), pixels."""
        return self.P2[:, :3].copy()

    @property
    def cam2_position(self) -> np.ndarray:
        """(3,) optical centre of cam2 in the rectified reference frame, metres (about 6 cm left: x = -0.06)."""
        return -np.linalg.solve(self.P2[:, :3], self.P2[:, 3])

    def project(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) rectified reference-frame points, metres -> (N, 2) image_02 pixels."""
        uvw = np.c_[np.asarray(points, float), np.ones(len(points))] @ self.P2.T
        return uvw[:, :2] / uvw[:, 2:3]


def read_calib(path: str | Path) -> KittiCalib:
    """Read a KITTI calibration file in either spelling (``R0_rect:`` or ``R_rect``, ...)."""
    path = Path(path)
    found: dict[str, np.ndarray] = {}
    lines: dict[str, int] = {}
    for line, text in read_lines(path):
        key, _, rest = text.partition(" ")
        key = key.rstrip(":")
        for name, (shape, spellings) in CALIB_KEYS.items():
            if key in spellings:
                values = numbers(path, line, rest.split(), key)
                if values.size != shape[0] * shape[1]:
                    raise InputError(f"{path}:{line}: {key} must have {shape[0] * shape[1]} numbers, got {values.size}")
                found[name] = values.reshape(shape)
                lines[name] = line
    missing = [name for name in CALIB_KEYS if name not in found]
    if missing:
        raise InputError(f"{path}: calibration lacks {', '.join(missing)}")
    _check_projection(path, lines.get("P2", 0), found["P2"])
    return KittiCalib(**found)


def _check_projection(path: Path, line: int, p: np.ndarray) -> None:
    """P2 = K [I | t] with a positive focal length in range, the principal point and t bounded."""
    where = f"{path}:{line}: P2"
    fx, fy = p[0, 0], p[1, 1]
    if not (FOCAL_PX[0] <= fx <= FOCAL_PX[1] and FOCAL_PX[0] <= fy <= FOCAL_PX[1]):
        raise InputError(f"{where} focal lengths must lie in [{FOCAL_PX[0]:g}, {FOCAL_PX[1]:g}] px, got "
                         f"fx {fx:.6g}, fy {fy:.6g}")
    if abs(p[2, 2] - 1.0) > 1e-6 or np.any(np.abs(p[2, :2]) > 1e-6) or abs(p[1, 0]) > 1e-6:
        raise InputError(f"{where} must be K [I | t] with K's last row (0, 0, 1), got {p[2, :3].tolist()}")
    if np.any(np.abs(p[:2, 1:3]) > MAX_PIXEL) or abs(p[0, 1]) > fx:
        raise InputError(f"{where} has a principal point or skew beyond {MAX_PIXEL:g} px")
    offset = np.linalg.solve(p[:, :3], p[:, 3])
    if not np.all(np.abs(offset) <= MAX_CAMERA_OFFSET_M):
        raise InputError(f"{where} places the camera {float(np.linalg.norm(offset)):.3g} m from cam0 "
                         f"(at most {MAX_CAMERA_OFFSET_M:g})")


#: The labelled types that stand on the ground, whose boxes' bottoms give the ground's plane.
SOLID_TYPES = ("Pedestrian", "Car", "Van", "Cyclist", "Truck")


@dataclass(frozen=True)
class KittiLabels(RowTable):
    """KITTI object labels, one row per object (N rows).

    frame, track_id: (N,) int64; -1 where the file has no such column (object benchmark)
        and track_id -1 for DontCare. types: (N,) str. truncated: (N,) float (0..2 tracking,
        0..1 object). occluded: (N,) int64 (0 visible .. 3 unknown). alpha: (N,) radians.
    boxes: (N, 4) float ``[x1, y1, x2, y2]`` image_02 pixels, clipped to the image.
    dimensions: (N, 3) float ``[h, w, l]`` metres. locations: (N, 3) float, bottom-face
        centre in the rectified reference camera frame, metres. rotation_y: (N,) radians.
    line: (N,) int64, the row's line in its file (for error messages).
    """

    frame: np.ndarray
    track_id: np.ndarray
    types: np.ndarray
    truncated: np.ndarray
    occluded: np.ndarray
    alpha: np.ndarray
    boxes: np.ndarray
    dimensions: np.ndarray
    locations: np.ndarray
    rotation_y: np.ndarray
    line: np.ndarray

    def of_type(self, *types: str) -> KittiLabels:
        """The rows whose type is one of ``types`` (e.g. ``"Pedestrian"``, ``"DontCare"``)."""
        return self.take(np.isin(self.types, types))

    def camera_over_ground(self) -> tuple[float, float, float]:
        """(height m, tilt rad, roll rad) of the camera over the plane fitted (least squares) to the
        bottom-face centres of every labelled object that stands on the ground (:data:`SOLID_TYPES`),
        the rectified camera frame's x right, y down, z forward: where KITTI's labels put the ground."""
        loc = self.locations[np.isin(self.types, SOLID_TYPES)]
        a = np.c_[np.ones(len(loc)), loc[:, 2], loc[:, 0]]
        h, slope_z, slope_x = np.linalg.lstsq(a, loc[:, 1], rcond=None)[0]
        return float(h), float(np.arctan(-slope_z)), float(np.arctan(slope_x))


def read_labels(path: str | Path) -> KittiLabels:
    """Read a tracking ``label_02/<seq>.txt`` (17 fields) or object ``label_2/<id>.txt`` (15 fields).

    The layout is taken from the first line; every line must have the same number of fields.
    Refused with one InputError naming file and line: a wrong field count, an unknown type, a
    number that is not one (or NaN), a frame or track id that is not an integer in range (-1
    only for DontCare), an inverted box, values beyond the bounds above, and the same
    (frame, track) twice.
    """
    path = Path(path)
    rows, types, width = [], [], None
    for line, text in read_lines(path):
        fields = text.split()
        if width is None:
            if len(fields) not in (15, 17):
                raise InputError(f"{path}:{line}: a KITTI label has 17 fields (tracking) or 15 (object), "
                                 f"got {len(fields)}")
            width = len(fields)
        elif len(fields) != width:
            raise InputError(f"{path}:{line}: expected {width} fields like the first line, got {len(fields)}")
        head = fields[:2] if width == 17 else ["-1", "-1"]
        kind = fields[width - 15]
        if kind not in TYPES:
            raise InputError(f"{path}:{line}: unknown object type {kind!r}; valid: {', '.join(TYPES)}")
        values = numbers(path, line, head + fields[width - 14:], "label fields")
        if width == 17:
            _check_ids(path, line, values, kind, fields)
        if kind != "DontCare":
            _check_object(path, line, values)
        rows.append(np.r_[values, line])
        types.append(kind)
    table = np.array(rows, dtype=np.float64).reshape(-1, 17)
    labels = KittiLabels(
        frame=table[:, 0].astype(np.int64), track_id=table[:, 1].astype(np.int64), types=np.array(types, dtype=str),
        truncated=table[:, 2], occluded=table[:, 3].astype(np.int64), alpha=table[:, 4], boxes=table[:, 5:9],
        dimensions=table[:, 9:12], locations=table[:, 12:15], rotation_y=table[:, 15],
        line=table[:, 16].astype(np.int64))
    _check_unique(path, labels)
    return labels


def _check_ids(path: Path, line: int, values: np.ndarray, kind: str, fields: list[str]) -> None:
    frame, track = values[0], values[1]
    if frame != int(frame) or not 0 <= frame <= MAX_FRAME:
        raise InputError(f"{path}:{line}: frame must be an integer in [0, {MAX_FRAME}], got {fields[0]!r}")
    lowest = -1 if kind == "DontCare" else 0
    if track != int(track) or not lowest <= track <= MAX_FRAME:
        raise InputError(f"{path}:{line}: track id must be an integer in [{lowest}, {MAX_FRAME}] for {kind}, "
                         f"got {fields[1]!r}")


def _check_object(path: Path, line: int, values: np.ndarray) -> None:
    """An object's (not DontCare's) flags, box, size, location and yaw in range."""
    truncated, occluded, box = values[2], values[3], values[5:9]
    dims, loc, yaw = values[9:12], values[12:15], values[15]
    problem = ""
    if not 0.0 <= truncated <= 2.0 or occluded not in (0, 1, 2, 3):
        problem = f"truncated must lie in [0, 2] and occluded be 0-3, got {truncated:g}, {occluded:g}"
    elif np.any(np.abs(box) > MAX_PIXEL) or box[2] < box[0] or box[3] < box[1]:
        problem = f"box [x1 y1 x2 y2] must have x1 <= x2, y1 <= y2 within {MAX_PIXEL:g} px, got {box.tolist()}"
    elif np.any(dims <= 0.0) or np.any(dims > MAX_DIMENSION_M):
        problem = f"dimensions h w l must lie in (0, {MAX_DIMENSION_M:g}] m, got {dims.tolist()}"
    elif np.any(np.abs(loc) > MAX_LOCATION_M):
        problem = f"location must lie within {MAX_LOCATION_M:g} m of the camera, got {loc.tolist()}"
    elif abs(yaw) > 2.0 * np.pi:
        problem = f"rotation_y must lie in [-2 pi, 2 pi], got {yaw:g}"
    if problem:
        raise InputError(f"{path}:{line}: {problem}")


def _check_unique(path: Path, labels: KittiLabels) -> None:
    """No (frame, track id) twice among the tracked objects (a duplicate would be scored twice)."""
    tracked = labels.track_id >= 0
    if not tracked.any():
        return
    keys = labels.frame[tracked] * (MAX_FRAME + 2) + labels.track_id[tracked]
    order = np.argsort(keys, kind="stable")
    same = np.flatnonzero(np.diff(keys[order]) == 0)
    if len(same):
        lines = labels.line[tracked][order]
        first, again = lines[same[0]], lines[same[0] + 1]
        raise InputError(f"{path}:{again}: frame {labels.frame[tracked][order][same[0]]}, track "
                         f"{labels.track_id[tracked][order][same[0]]} is labelled twice (first on line {first})")


def read_camera_trajectory(path: str | Path) -> np.ndarray:
    """ORB-SLAM3 ``CameraTrajectory.txt``: (F, 4, 4) ``T_world_from_cam`` per frame (line i = frame i).

    The world frame is the camera frame at frame 0 (x right, y down, z forward, metres).
    """
    path = Path(path)
    poses = []
    for line, text in read_lines(path):
        values = numbers(path, line, text.split(), "pose")
        if values.size != 12:
            raise InputError(f"{path}:{line}: a pose line has 12 numbers (row-major 3x4 [R | t]), got {values.size}")
        pose = np.eye(4)
        pose[:3] = values.reshape(3, 4)
        pose[:3, :3] = checked_rotation(path, line, pose[:3, :3])
        if np.any(np.abs(pose[:3, 3]) > MAX_TRANSLATION_M):
            raise InputError(f"{path}:{line}: translation beyond {MAX_TRANSLATION_M:g} m: {pose[:3, 3].tolist()}")
        poses.append(pose)
    if not poses:
        raise InputError(f"{path}: no poses")
    return np.stack(poses)


def checked_rotation(path: Path, line: int, r: np.ndarray) -> np.ndarray:
    """``r`` (3, 3) made exactly orthonormal when it is a rotation to :data:`ROTATION_TOLERANCE`;
    else an InputError naming file and line."""
    if not np.allclose(r @ r.T, np.eye(3), rtol=0.0, atol=ROTATION_TOLERANCE) or np.linalg.det(r) <= 0:
        raise InputError(f"{path}:{line}: the 3x3 part is not a rotation (orthonormal to {ROTATION_TOLERANCE:g}, "
                         "determinant +1)")
    u, _, vt = np.linalg.svd(r)
    return u @ vt


@dataclass(frozen=True)
class TrackingSequence:
    """One KITTI tracking sequence on disk: calibration, labels, optional poses, image frames present."""

    name: str
    calib: KittiCalib
    labels: KittiLabels
    poses: np.ndarray | None  # (F, 4, 4) T_world_from_cam, or None without ORB-SLAM3 poses
    image_dir: Path
    frames: tuple[int, ...]  # frame indices whose image exists, ascending

    def image_path(self, frame: int) -> Path:
        """Path of the image_02 PNG of ``frame``."""
        return self.image_dir / f"{frame:06d}.png"


def read_tracking_sequence(training: str | Path, name: str) -> TrackingSequence:
    """Read sequence ``name`` (e.g. ``"0016"``) under a KITTI tracking ``training/`` folder."""
    training = Path(training)
    image_dir = training / "image_02" / name
    if not image_dir.is_dir():
        raise InputError(f"{image_dir}: no image folder for KITTI tracking sequence {name}")
    frames = []
    for p in sorted(image_dir.glob("*.png")):
        if not p.stem.isdigit():
            raise InputError(f"{p}: KITTI image names are the frame number (000012.png)")
        frames.append(int(p.stem))
    pose_file = training / "ego_poses_orbslam3" / name / "CameraTrajectory.txt"
    poses = read_camera_trajectory(pose_file) if pose_file.is_file() else None
    if poses is not None and frames and frames[-1] >= len(poses):
        raise InputError(f"{pose_file}: {len(poses)} poses, but image frame {frames[-1]} exists")
    return TrackingSequence(name, read_calib(training / "calib" / f"{name}.txt"),
                            read_labels(training / "label_02" / f"{name}.txt"), poses, image_dir, tuple(frames))


def tracking_sequence_names(training: str | Path) -> list[str]:
    """Names of the sequences with an image folder under ``training/image_02``."""
    root = Path(training) / "image_02"
    return sorted(p.name for p in root.iterdir() if p.is_dir()) if root.is_dir() else []
