"""The user's own recordings: calibration YAML + ego poses CSV + images or a video -> Frames.

Calibration (YAML; the rotation maps optical camera axes, x right / y down / z forward,
to the vehicle frame, x forward / y left / z up; translation in metres)::

    width: 1600
    height: 900
    intrinsics: [[1266.4, 0, 816.3], [0, 1266.4, 491.5], [0, 0, 1]]   # or fx, fy, cx, cy
    cam_to_vehicle:
      rotation: [0.5, -0.5, 0.5, -0.5]     # quaternion [w, x, y, z] or a 3x3 matrix
      translation: [1.70, 0.0, 1.51]
    mount: vehicle    # optional: vehicle (the default) or static (a camera fixed to the ground)

A ``static`` camera (an infrastructure camera, a parked vehicle) needs no ego poses: its
vehicle frame stays where it is (the world frame), with ``cam_to_vehicle`` placing the
camera over the ground (z = 0).

Ego poses (CSV, vehicle -> world, timestamps in seconds, rows sorted by time), either
``timestamp,x,y,z,qw,qx,qy,qz`` or ``timestamp,x,y,yaw`` (yaw in radians, z = 0).
Each frame gets the pose interpolated at its timestamp (linear position, slerp rotation).
"""

from __future__ import annotations

import csv
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from scipy.spatial.transform import Rotation, Slerp

from pedenv.errors import InputError, check_array, read_text
from pedenv.geometry import quaternion_to_rotation
from pedenv.images import read_image_rgb
from pedenv.records import MOUNTS, Camera, EgoPose, Frame

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp")
POSE_HEADERS = (("timestamp", "x", "y", "z", "qw", "qx", "qy", "qz"), ("timestamp", "x", "y", "yaw"))


def _field(data: dict, key: str, path: Path):
    node = data
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            raise InputError(f"{path}: calibration field {key!r} is missing")
        node = node[part]
    return node


def _numbers(value, key: str, path: Path, shape: tuple) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{path}: calibration field {key!r} must be numbers, got {value!r}") from None
    if array.shape != shape or not np.all(np.isfinite(array)):
        raise InputError(f"{path}: calibration field {key!r} must be finite numbers of shape {shape}, got {value!r}")
    return array


def load_calibration(path: str | Path) -> Camera:
    """The :class:`Camera` described by a calibration YAML file (format in the module doc)."""
    path = Path(path)
    text = read_text(path, "the calibration")
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InputError(f"{path}: not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: calibration must be a YAML mapping of fields")
    if "intrinsics" in data:
        k = _numbers(data["intrinsics"], "intrinsics", path, (3, 3))
        if not np.array_equal(k[2], [0.0, 0.0, 1.0]):
            raise InputError(f"{path}: calibration field 'intrinsics' must have the last row [0, 0, 1], got "
                             f"{k[2].tolist()} (a scaled matrix would scale every distance)")
    else:
        fx, fy, cx, cy = (float(_numbers(_field(data, f, path), f, path, ())) for f in ("fx", "fy", "cx", "cy"))
        k = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    width, height = (_numbers(_field(data, f, path), f, path, ()) for f in ("width", "height"))
    rot = np.asarray(_field(data, "cam_to_vehicle.rotation", path), dtype=object)
    if rot.shape == (4,):
        q = _numbers(rot.tolist(), "cam_to_vehicle.rotation", path, (4,))
        if np.linalg.norm(q) < 1e-9:
            raise InputError(f"{path}: calibration field 'cam_to_vehicle.rotation' is a zero quaternion")
        r = quaternion_to_rotation(q)
    else:
        r = _numbers(rot.tolist(), "cam_to_vehicle.rotation", path, (3, 3))
        if abs(np.linalg.det(r)) < 1e-9:
            raise InputError(f"{path}: calibration field 'cam_to_vehicle.rotation' is a singular matrix")
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = _numbers(_field(data, "cam_to_vehicle.translation", path), "cam_to_vehicle.translation", path, (3,))
    if width != int(width) or height != int(height):
        raise InputError(f"{path}: calibration fields 'width' and 'height' must be whole pixels, got {width}, {height}")
    mount = data.get("mount", "vehicle")
    if mount not in MOUNTS:
        raise InputError(f"{path}: calibration field 'mount' must be one of {', '.join(MOUNTS)}, got {mount!r}")
    try:
        return Camera(k, int(width), int(height), t, mount)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None


def slerp(q0: np.ndarray, q1: np.ndarray, fraction: float) -> np.ndarray:
    """Spherical interpolation between unit quaternions ``[w, x, y, z]`` (shortest arc).

    Returns the rotation ``fraction`` (0..1) of the way from ``q0`` to ``q1`` as a unit
    quaternion ``[w, x, y, z]`` with ``w >= 0`` (scipy's :class:`~scipy.spatial.transform.Slerp`).
    """
    ends = Rotation.from_quat(np.stack([q0, q1]), scalar_first=True)
    return Slerp([0.0, 1.0], ends)(fraction).as_quat(canonical=True, scalar_first=True)


@dataclass(frozen=True)
class EgoTrajectory:
    """Time-stamped ego poses of a recording.

    timestamps: (T,) seconds, strictly increasing. translations: (T, 3) world frame, metres.
    quaternions: (T, 4) unit ``[w, x, y, z]``, vehicle -> world. source: the file they came from.
    """

    timestamps: np.ndarray
    translations: np.ndarray
    quaternions: np.ndarray
    source: str = ""
    _rotations: Slerp | Rotation = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ts = check_array("ego timestamps", self.timestamps, (None,))
        if len(ts) == 0 or np.any(np.diff(ts) <= 0):
            raise InputError(f"{self.source or 'ego poses'}: timestamps must be non-empty and strictly increasing")
        object.__setattr__(self, "timestamps", ts)
        object.__setattr__(self, "translations", check_array("ego translations", self.translations, (len(ts), 3)))
        object.__setattr__(self, "quaternions", check_array("ego quaternions", self.quaternions, (len(ts), 4)))
        # one interpolator for the whole trajectory, built once (not two rotations per frame)
        rotations = Rotation.from_quat(self.quaternions, scalar_first=True)
        object.__setattr__(self, "_rotations", Slerp(ts, rotations) if len(ts) > 1 else rotations[0])

    def at(self, timestamp: float) -> EgoPose | None:
        """The pose interpolated at ``timestamp`` seconds; None outside the recorded span."""
        ts = self.timestamps
        if not ts[0] <= timestamp <= ts[-1]:
            return None
        if len(ts) == 1:
            return EgoPose(self.translations[0], self._rotations.as_matrix())
        i = int(np.clip(np.searchsorted(ts, timestamp, side="right") - 1, 0, len(ts) - 2))
        f = (timestamp - ts[i]) / (ts[i + 1] - ts[i])
        pos = (1.0 - f) * self.translations[i] + f * self.translations[i + 1]
        return EgoPose(pos, self._rotations(timestamp).as_matrix())


def load_ego_poses(path: str | Path) -> EgoTrajectory:
    """The ego poses of a CSV file (format in the module doc); rows must be sorted by time."""
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8-sig") as f:  # -sig: a byte-order mark is accepted
            rows = [r for r in csv.reader(f) if any(c.strip() for c in r)]
    except OSError as exc:
        raise InputError(f"{path}: cannot read the ego poses: {exc.strerror}") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{path}: the ego poses are not a UTF-8 CSV text file (a binary file?): {exc}") from None
    header = tuple(c.strip().lower() for c in rows[0]) if rows else ()
    if header not in POSE_HEADERS:
        raise InputError(f"{path}: ego poses header must be {' or '.join(','.join(h) for h in POSE_HEADERS)}, "
                         f"got {','.join(header) or 'an empty file'}")
    if len(rows) < 2:
        raise InputError(f"{path}: no ego pose rows after the header")
    values = np.empty((len(rows) - 1, len(header)))
    for n, row in enumerate(rows[1:]):
        try:
            if len(row) != len(header):
                raise ValueError
            values[n] = [float(c) for c in row]
        except ValueError:
            raise InputError(f"{path}: row {n + 1} (line {n + 2}) must hold {len(header)} numbers "
                             f"({','.join(header)}), got {','.join(row)}") from None
        if not np.all(np.isfinite(values[n])):
            raise InputError(f"{path}: row {n + 1} (line {n + 2}) contains NaN or inf")
        if n and values[n, 0] <= values[n - 1, 0]:
            raise InputError(f"{path}: rows must be sorted by time: row {n + 1} (line {n + 2}, timestamp "
                             f"{values[n, 0]:.6f} s) is not after row {n} ({values[n - 1, 0]:.6f} s)")
    ts = values[:, 0]
    if header == POSE_HEADERS[0]:
        trans, quats = values[:, 1:4], values[:, 4:8]
        norms = np.linalg.norm(quats, axis=1)
        if np.any(norms < 1e-9):
            raise InputError(f"{path}: row {int(np.argmax(norms < 1e-9)) + 1} has a zero quaternion")
        quats = quats / norms[:, None]
    else:
        trans = np.column_stack([values[:, 1:3], np.zeros(len(values))])
        quats = Rotation.from_euler("z", values[:, 3:4]).as_quat(canonical=True, scalar_first=True)
    _warn_implausible_speed(path, ts, trans)
    return EgoTrajectory(ts, trans, quats, str(path))


#: Ego speeds above this (m/s, about 300 km/h) between two pose rows are warned about:
#: a jump in the poses (a wrong row, a reset) makes every pedestrian seem to race.
MAX_PLAUSIBLE_EGO_SPEED_MPS = 85.0


def _warn_implausible_speed(path: Path, ts: np.ndarray, trans: np.ndarray) -> None:
    if len(ts) < 2:
        return
    speeds = np.linalg.norm(np.diff(trans, axis=0), axis=1) / np.diff(ts)
    fast = np.flatnonzero(speeds > MAX_PLAUSIBLE_EGO_SPEED_MPS)
    if len(fast):
        i = int(fast[0])
        warnings.warn(f"{path}: the ego moves at {speeds[i]:.0f} m/s between rows {i + 1} and {i + 2} (lines {i + 2}-"
                      f"{i + 3}), above the plausible {MAX_PLAUSIBLE_EGO_SPEED_MPS:g} m/s; {len(fast)} such step(s): "
                      f"check the poses (positions must be metres, timestamps seconds)", stacklevel=3)


def _folder_frames(folder: Path, fps: float | None, start_time: float) -> list[tuple[Path, float]]:
    images = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not images:
        raise InputError(f"{folder}: no images ({', '.join(IMAGE_SUFFIXES)}) in the folder")
    table = folder / "timestamps.csv"
    if fps is not None:
        return [(p, start_time + i / fps) for i, p in enumerate(images)]
    if not table.is_file():
        raise InputError(f"{folder}: no timestamps.csv (filename,timestamp) in the folder; give --fps instead")
    try:
        with table.open(newline="", encoding="utf-8-sig") as f:
            rows = [r for r in csv.reader(f) if r]
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{table}: not a UTF-8 CSV text file (a binary file?): {exc}") from None
    if not rows or [c.strip().lower() for c in rows[0]] != ["filename", "timestamp"]:
        raise InputError(f"{table}: header must be filename,timestamp")
    stamps = {}
    for n, row in enumerate(rows[1:], start=1):
        try:
            stamps[row[0].strip()] = float(row[1])
            if not np.isfinite(stamps[row[0].strip()]):
                raise ValueError
        except (IndexError, ValueError):
            raise InputError(f"{table}: row {n} must be filename,timestamp (seconds), got {','.join(row)}") from None
    missing = [p.name for p in images if p.name not in stamps]
    if missing:
        raise InputError(f"{table}: no timestamp for image {missing[0]}")
    return [(p, stamps[p.name]) for p in images]


@dataclass(frozen=True)
class Recording:
    """One recording: camera, ego trajectory and either an image folder or a video file.

    trajectory: the ego poses, or None for a static camera (every frame's ego pose is the
    identity: the vehicle frame is the world frame).
    images: (path, timestamp in seconds) per frame in order, or empty for a video.
    video: the video file, or None. start_time: seconds of a video's first frame.
    """

    name: str
    camera: Camera
    trajectory: EgoTrajectory | None
    images: tuple[tuple[Path, float], ...] = ()
    video: Path | None = None
    fps: float | None = None
    start_time: float = 0.0

    def frames(self) -> Iterator[Frame]:
        """The frames in order, images loaded (RGB) and ego poses interpolated.

        Raises :class:`InputError` at the first frame without an ego pose or with an image
        that is unreadable or not the calibrated size; the frames before it were yielded.
        """
        source = _video_frames(self.video, self.fps, self.start_time) if self.video else (
            (i, t, p, read_image_rgb(p)) for i, (p, t) in enumerate(self.images))
        for index, timestamp, path, image in source:
            ego = self._ego_at(index, timestamp, path)
            if image.shape[:2] != (self.camera.height, self.camera.width):
                raise InputError(f"{path}: frame {index} is {image.shape[1]}x{image.shape[0]} pixels, "
                                 f"the calibration says {self.camera.width}x{self.camera.height}")
            yield Frame(index, timestamp, self.camera, ego, image=image,
                        image_path=None if self.video else path, scene=self.name)

    def _ego_at(self, index: int, timestamp: float, path) -> EgoPose:
        """The ego pose of frame ``index``: the identity without a trajectory (a static camera)."""
        if self.trajectory is None:
            return EgoPose(np.zeros(3), np.eye(3))
        ego = self.trajectory.at(timestamp)
        if ego is None:
            span = self.trajectory.timestamps
            raise InputError(f"{path}: frame {index} at {timestamp:.6f} s has no ego pose: "
                             f"{self.trajectory.source} covers {span[0]:.6f} s to {span[-1]:.6f} s")
        return ego

    def __len__(self) -> int:
        if self.video is None:
            return len(self.images)
        import cv2

        cap = cv2.VideoCapture(str(self.video))
        count = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        cap.release()
        return max(count, 0)


def _video_frames(video: Path, fps: float | None, start_time: float):
    import cv2

    cap = cv2.VideoCapture(str(video))
    if not cap.isOpened():
        raise InputError(f"{video}: cannot open the video")
    rate = fps or cap.get(cv2.CAP_PROP_FPS)
    index = 0
    try:
        while True:
            ok, bgr = cap.read()
            if not ok:
                break
            offset = index / rate if rate and rate > 0 else cap.get(cv2.CAP_PROP_POS_MSEC) / 1e3
            yield index, start_time + offset, f"{video}#{index}", cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
            index += 1
    finally:
        cap.release()
    if index == 0:
        raise InputError(f"{video}: the video holds no readable frame")


def load_recording(*, calibration: str | Path, ego_poses: str | Path | None, images: str | Path | None = None,
                   video: str | Path | None = None, fps: float | None = None, start_time: float | None = None,
                   name: str | None = None, static: bool = False) -> Recording:
    """Read a recording: exactly one of ``images`` (a folder) or ``video`` (a file).

    Frame timestamps: ``images/timestamps.csv`` (filename,timestamp), else ``fps``; a
    video's come from ``fps`` or its own frame rate. With ``fps`` (and for a video) the first
    frame is at ``start_time``, by default the first ego pose's timestamp (0 without poses).
    ``static`` mounts the camera ``static`` whatever the calibration says; a static camera
    may come without ``ego_poses`` (its vehicle frame is then the world frame).
    """
    if (images is None) == (video is None):
        raise InputError("give exactly one of an image folder (--images) or a video (--video)")
    if fps is not None and not (np.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be a finite number > 0, got {fps}")
    camera = load_calibration(calibration)
    if static and not camera.static:
        camera = Camera(camera.intrinsics, camera.width, camera.height, camera.cam_to_vehicle, "static")
    if ego_poses is None and not camera.static:
        raise InputError(f"{calibration}: a vehicle-mounted camera needs ego poses (--ego-poses); "
                         "a fixed camera runs without them with --static or 'mount: static' in the calibration")
    trajectory = None if ego_poses is None else load_ego_poses(ego_poses)
    first = 0.0 if trajectory is None else float(trajectory.timestamps[0])
    start = float(first if start_time is None else start_time)
    if video is not None:
        video = Path(video)
        if not video.is_file():
            raise InputError(f"{video}: video file not found")
        return Recording(name or video.stem, camera, trajectory, video=video, fps=fps, start_time=start)
    assert images is not None  # exactly one of images and video (checked above)
    folder = Path(images)
    if not folder.is_dir():
        raise InputError(f"{folder}: image folder not found")
    return Recording(name or folder.resolve().name, camera, trajectory, tuple(_folder_frames(folder, fps, start)))
