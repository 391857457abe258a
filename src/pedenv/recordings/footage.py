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

``fov_deg`` (the horizontal field of view, degrees; square pixels, principal point at the
centre) may stand for the intrinsics. A file written by ``pedenv calibrate`` carries
``estimated: true`` and the estimate's 1-sigma ``uncertainty``; loading it warns. A file with
the size and intrinsics (or ``fov_deg``) but no ``cam_to_vehicle`` is read by
:func:`load_intrinsics`: the mounting is then estimated (:mod:`pedenv.calibration`); on a
vehicle its ``camera_position: [x, y]`` (metres, :func:`load_camera_position`) says where the
camera sits in the vehicle frame of the ego poses, which the people and the road cannot show.

A ``static`` camera (an infrastructure camera, a parked vehicle) needs no ego poses: its
vehicle frame stays where it is (the world frame), with ``cam_to_vehicle`` placing the
camera over the ground (z = 0).

Unknown keys are refused and values are bounded to sane ranges
(:mod:`pedenv.recordings.calibration_fields`). Ego poses: :mod:`pedenv.recordings.ego_poses`.
"""

from __future__ import annotations

import csv
import os
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.errors import InputError
from pedenv.geometry import quaternion_to_rotation
from pedenv.images import image_size, read_image_rgb
from pedenv.paths import check_path
from pedenv.recordings.calibration_fields import FOV_RANGE_DEG, MAX_MOUNT_DISTANCE_M, check_keys, check_ranges
from pedenv.recordings.ego_poses import (  # noqa: F401 - the recordings' API in one place
    MAX_PLAUSIBLE_EGO_SPEED_MPS,
    EgoTrajectory,
    load_ego_poses,
    slerp,
)
from pedenv.records import MOUNTS, Camera, EgoPose, Frame
from pedenv.structured_text import load_yaml
from pedenv.video_files import video_capture

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp")


def _field(data: dict[str, Any], key: str, path: Path) -> Any:
    node = data
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            raise InputError(f"{path}: calibration field {key!r} is missing")
        node = node[part]
    return node


def _numbers(value: object, key: str, path: Path, shape: tuple[int, ...]) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{path}: calibration field {key!r} must be numbers, got {value!r}") from None
    if array.shape != shape or not np.all(np.isfinite(array)):
        raise InputError(f"{path}: calibration field {key!r} must be finite numbers of shape {shape}, got {value!r}")
    return array


def _intrinsics(data: dict[str, Any], path: Path, width: float, height: float) -> np.ndarray | None:
    """The (3, 3) camera matrix of a calibration mapping: ``intrinsics``, ``fx fy cx cy`` or
    ``fov_deg`` (square pixels, principal point at the centre); None when it gives none."""
    if "intrinsics" in data:
        k = _numbers(data["intrinsics"], "intrinsics", path, (3, 3))
        if not np.array_equal(k[2], [0.0, 0.0, 1.0]):
            raise InputError(f"{path}: calibration field 'intrinsics' must have the last row [0, 0, 1], got "
                             f"{k[2].tolist()} (a scaled matrix would scale every distance)")
        return k
    if "fov_deg" in data and "fx" not in data:
        fov = float(_numbers(data["fov_deg"], "fov_deg", path, ()))
        if not FOV_RANGE_DEG[0] <= fov <= FOV_RANGE_DEG[1]:
            raise InputError(f"{path}: calibration field 'fov_deg' must be in [{FOV_RANGE_DEG[0]:g}, "
                             f"{FOV_RANGE_DEG[1]:g}] degrees, got {fov:g}")
        f = width / (2.0 * np.tan(np.radians(fov) / 2.0))
        return np.array([[f, 0.0, width / 2.0], [0.0, f, height / 2.0], [0.0, 0.0, 1.0]])
    if not any(key in data for key in ("fx", "fy", "cx", "cy")):
        return None
    fx, fy, cx, cy = (float(_numbers(_field(data, f, path), f, path, ())) for f in ("fx", "fy", "cx", "cy"))
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def load_intrinsics(path: str | Path) -> tuple[int, int, np.ndarray | None]:
    """(width, height, (3, 3) camera matrix or None) of a calibration YAML that may lack the
    mounting (``cam_to_vehicle``) and the intrinsics: what a camera estimated from people starts from."""
    path = Path(path)
    data = load_yaml(path, "the calibration")
    if not isinstance(data, dict):
        raise InputError(f"{path}: calibration must be a YAML mapping of fields")
    check_keys(data, path)
    width, height = (_numbers(_field(data, f, path), f, path, ()) for f in ("width", "height"))
    if width != int(width) or height != int(height):
        raise InputError(f"{path}: calibration fields 'width' and 'height' must be whole pixels, got {width}, {height}")
    k = _intrinsics(data, path, float(width), float(height))
    if k is not None:
        check_ranges(path, k, float(width), float(height), np.zeros(3))
    return int(width), int(height), k


def load_camera_position(path: str | Path, static: bool = False) -> tuple[float, float]:
    """``camera_position`` (x forward, y left, metres) of a calibration YAML without ``cam_to_vehicle``:
    where the camera sits in the vehicle frame of the ego poses; (0, 0) when the file gives none (the
    vehicle origin then lies on the road under the camera). InputError for a static camera (``static``),
    whose ground frame lies under it by definition."""
    path = Path(path)
    data = load_yaml(path, "the calibration")
    if not isinstance(data, dict) or "camera_position" not in data:
        return 0.0, 0.0
    if static or data.get("mount") == "static":
        raise InputError(f"{path}: calibration field 'camera_position' places a vehicle camera on its vehicle; "
                         "a static camera's world lies on the ground under it")
    x, y = _numbers(data["camera_position"], "camera_position", path, (2,))
    if np.hypot(x, y) > MAX_MOUNT_DISTANCE_M:
        raise InputError(f"{path}: calibration field 'camera_position' must be within {MAX_MOUNT_DISTANCE_M:g} m of "
                         f"the vehicle origin, got [{x:g}, {y:g}]")
    return float(x), float(y)


def has_mounting(path: str | Path) -> bool:
    """Whether a calibration YAML places the camera (has ``cam_to_vehicle``); a file that cannot
    be read says True, so that loading it gives its own error."""
    try:
        data = load_yaml(Path(path), "the calibration")
    except InputError:
        return True
    return not isinstance(data, dict) or "cam_to_vehicle" in data


def load_calibration(path: str | Path) -> Camera:
    """The :class:`Camera` described by a calibration YAML file (format in the module doc)."""
    path = Path(path)
    data = load_yaml(path, "the calibration")  # size, nesting and alias limits
    if not isinstance(data, dict):
        raise InputError(f"{path}: calibration must be a YAML mapping of fields")
    check_keys(data, path)
    width, height = (_numbers(_field(data, f, path), f, path, ()) for f in ("width", "height"))
    k = _intrinsics(data, path, float(width), float(height))
    if k is None:
        raise InputError(f"{path}: calibration field 'intrinsics' is missing (or fx, fy, cx, cy, or fov_deg)")
    if data.get("estimated") is True:
        warnings.warn(f"{path}: this calibration was estimated from the people seen (estimated: true), not "
                      "measured; its uncertainty field says how well", stacklevel=2)
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
    check_ranges(path, k, float(width), float(height), t[:3, 3], static=mount == "static")
    try:
        return Camera(k, int(width), int(height), t, mount)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None


def folder_frames(folder: Path, fps: float | None, start_time: float) -> list[tuple[Path, float]]:
    """The folder's images in name order, each with its timestamp: ``start_time + i / fps`` with
    ``fps``, else from the folder's ``timestamps.csv`` (filename,timestamp)."""
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

    images: (path, timestamp in seconds) per frame in order, or empty for a video.
    video: the video file, or None. start_time: seconds of a video's first frame.
    trajectory: the ego poses, or None for a static camera (every frame's ego pose is the
    identity: the vehicle frame is the world frame).
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
            ego = self._check_frame(path, index, timestamp, (image.shape[1], image.shape[0]))
            yield Frame(index, timestamp, self.camera, ego, image=image,
                        image_path=None if self.video else Path(path), scene=self.name)

    def check(self) -> None:
        """Check every frame before anything runs, without decoding an image: each image's size
        (from its header) is the calibrated one and each frame's timestamp has an ego pose; a
        video opens and its frame size is the calibrated one. InputError naming the first bad one.
        """
        if self.video is not None:
            with video_capture(self.video) as cap:
                import cv2

                size = (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
            self._check_frame(f"{self.video}#0", 0, self.start_time, size)
            return
        for index, (path, timestamp) in enumerate(self.images):
            self._check_frame(path, index, timestamp, image_size(path))

    def _check_frame(self, path: str | Path, index: int, timestamp: float,
                     size: tuple[int, int] | None = None) -> EgoPose:
        """The ego pose of frame ``index`` (the identity without a trajectory: a static camera), its size checked."""
        ego = EgoPose(np.zeros(3), np.eye(3)) if self.trajectory is None else self.trajectory.at(timestamp)
        if ego is None:
            assert self.trajectory is not None
            span = self.trajectory.timestamps
            raise InputError(f"{path}: frame {index} at {timestamp:.6f} s has no ego pose: "
                             f"{self.trajectory.source} covers {span[0]:.6f} s to {span[-1]:.6f} s")
        if size is not None and size != (self.camera.width, self.camera.height):
            raise InputError(f"{path}: frame {index} is {size[0]}x{size[1]} pixels, "
                             f"the calibration says {self.camera.width}x{self.camera.height}")
        return ego

    def __len__(self) -> int:
        if self.video is None:
            return len(self.images)
        import cv2

        with video_capture(self.video) as cap:
            return max(int(cap.get(cv2.CAP_PROP_FRAME_COUNT)), 0)


def _video_frames(video: Path, fps: float | None, start_time: float) -> Iterator[tuple[int, float, str, np.ndarray]]:
    """(index, timestamp in seconds, ``<video>#<index>``, (H, W, 3) uint8 RGB) per frame of ``video``."""
    import cv2

    index = 0
    with video_capture(video) as cap:
        rate = fps or cap.get(cv2.CAP_PROP_FPS)
        while True:
            ok, bgr = cap.read()
            if not ok:
                break
            offset = index / rate if rate and rate > 0 else cap.get(cv2.CAP_PROP_POS_MSEC) / 1e3
            yield index, start_time + offset, f"{video}#{index}", cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
            index += 1
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
    camera = load_calibration(check_path(calibration, "calibration"))
    if static and not camera.static:
        camera = Camera(camera.intrinsics, camera.width, camera.height, camera.cam_to_vehicle, "static")
    if ego_poses is None and not camera.static:
        raise InputError(f"{calibration}: a vehicle-mounted camera needs ego poses (--ego-poses); "
                         "a fixed camera runs without them with --static or 'mount: static' in the calibration")
    trajectory = None if ego_poses is None else load_ego_poses(check_path(ego_poses, "ego poses"))
    first = 0.0 if trajectory is None else float(trajectory.timestamps[0])
    start = float(first if start_time is None else start_time)
    if video is not None:
        video = check_path(video, "video")
        if not video.is_file():
            raise InputError(f"{video}: video file not found")
        return Recording(name or _text(video.stem), camera, trajectory, video=video, fps=fps, start_time=start)
    assert images is not None  # exactly one of images and video (checked above)
    folder = check_path(images, "image folder")
    if not folder.is_dir():
        raise InputError(f"{folder}: image folder not found")
    frames = tuple(folder_frames(folder, fps, start))
    return Recording(name or _text(folder.resolve().name), camera, trajectory, frames)


def _text(name: str) -> str:
    """A file name as UTF-8 text for the recording's name (drawn, logged, plotted): bytes that
    are not UTF-8 become ``\\xff`` escapes."""
    return os.fsencode(name).decode("utf-8", "backslashreplace")
