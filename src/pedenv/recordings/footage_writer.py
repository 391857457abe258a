"""Write a KITTI tracking or MOT17 sequence as a ``pedenv run`` recording (:mod:`pedenv.recordings.footage`).

Each writer makes, in an output folder: ``calibration.yaml``, ``ego_poses.csv``
(``timestamp,x,y,z,qw,qx,qy,qz``, vehicle -> world) and ``images/`` holding a symbolic link
per image present plus ``timestamps.csv`` (``filename,timestamp``), so frames with gaps
between them keep their true times. Then::

    pedenv run --calibration OUT/calibration.yaml --ego-poses OUT/ego_poses.csv --images OUT/images --output RUN

KITTI (:func:`write_kitti_recording`): image_02's intrinsics (``P2``), the camera mounted as
in :mod:`pedenv.datasets.kitti` (cam0 ``camera_height_m`` above the road, cam2 6 cm to its
left), ego poses from the ORB-SLAM3 trajectory (every frame of it, so the gaps interpolate),
or a standing ego without one; 10 Hz timestamps from the frame numbers.
MOT17 (:func:`write_mot17_recording`): **no calibration exists**. The camera written is a
guess, labelled as such in the YAML: focal length ``focal_px`` (default: the image width, about
53 deg across), principal point at the image centre, level unless ``pitch_down_deg`` says
otherwise, ``camera_height_m`` above the road. The ego stands still (identity poses): right
for the static sequences, wrong for MOT17-05/10/11/13 (moving cameras). Timestamps from ``frameRate``.
MOT17 with UCMCTrack's estimated camera (:func:`write_mot17_static_recording`): that camera,
``mount: static``, no ego poses.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import yaml

from pedenv.datasets import kitti_files as kitti
from pedenv.datasets import mot17
from pedenv.datasets.kitti import CAMERA_TO_VEHICLE_AXES, FRAME_RATE_HZ, cam0_to_vehicle
from pedenv.datasets.ucmctrack import read_camera_parameters, static_camera
from pedenv.errors import InputError
from pedenv.geometry import rotation_to_quaternion

POSE_HEADER = ("timestamp", "x", "y", "z", "qw", "qx", "qy", "qz")


def _prepare(out: Path) -> Path:
    out = Path(out)
    images = out / "images"
    if images.exists() and any(images.iterdir()):
        raise InputError(f"{images}: folder is not empty; choose a new output folder")
    images.mkdir(parents=True, exist_ok=True)
    return images


def _write_calibration(path: Path, K: np.ndarray, width: int, height: int, cam_to_vehicle: np.ndarray,
                       note: str, mount: str = "vehicle") -> None:
    data: dict = {"width": int(width), "height": int(height), "intrinsics": np.asarray(K, float).tolist(),
                  "cam_to_vehicle": {"rotation": np.asarray(cam_to_vehicle[:3, :3], float).tolist(),
                                     "translation": np.asarray(cam_to_vehicle[:3, 3], float).tolist()}}
    if mount != "vehicle":  # files of vehicle cameras stay as they were
        data["mount"] = mount
    path.write_text(f"# {note}\n" + yaml.safe_dump(data, sort_keys=False))


def _write_poses(path: Path, timestamps: np.ndarray, vehicle_to_world: np.ndarray) -> None:
    """timestamps (F,) s; vehicle_to_world (F, 4, 4)."""
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(POSE_HEADER)
        for t, pose in zip(timestamps, vehicle_to_world):
            q = rotation_to_quaternion(pose[:3, :3])
            w.writerow([f"{t:.9f}", *(f"{v:.6f}" for v in pose[:3, 3]), *(f"{v:.9f}" for v in q)])


def _link_images(images: Path, frames: list[tuple[Path, float]]) -> None:
    with (images / "timestamps.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["filename", "timestamp"])
        for source, t in frames:
            (images / source.name).symlink_to(source.resolve())
            w.writerow([source.name, f"{t:.9f}"])


def write_kitti_recording(training: str | Path, sequence: str, out: str | Path,
                          camera_height_m: float = 1.65) -> Path:
    """Write KITTI tracking ``sequence`` (under ``training/``) as a recording in ``out``; returns ``out``.

    The world is the vehicle frame at frame 0 (as ``pedenv evaluate --dataset kitti``).
    """
    out = Path(out)
    seq = kitti.read_tracking_sequence(training, sequence)
    if not seq.frames:
        raise InputError(f"{seq.image_dir}: no images")
    images = _prepare(out)
    from pedenv.images import read_image_rgb

    first = read_image_rgb(seq.image_path(seq.frames[0]))
    to_vehicle = cam0_to_vehicle(camera_height_m)
    cam2 = np.eye(4)
    cam2[:3, 3] = seq.calib.cam2_position
    _write_calibration(out / "calibration.yaml", seq.calib.K, first.shape[1], first.shape[0], to_vehicle @ cam2,
                       f"KITTI tracking {sequence}: image_02 (P2), cam0 {camera_height_m} m above the road")
    if seq.poses is not None:
        cam0 = seq.poses  # one per frame of the sequence, images present or not
        stamps = np.arange(len(cam0)) / FRAME_RATE_HZ
    else:
        stamps = np.array([seq.frames[0], seq.frames[-1] + 1]) / FRAME_RATE_HZ
        cam0 = np.repeat(np.eye(4)[None], 2, axis=0)
    vehicle = to_vehicle[None] @ cam0 @ np.linalg.inv(to_vehicle)[None]
    _write_poses(out / "ego_poses.csv", stamps, vehicle)
    _link_images(images, [(seq.image_path(f), f / FRAME_RATE_HZ) for f in seq.frames])
    return out


def write_mot17_recording(folder: str | Path, out: str | Path, camera_height_m: float = 1.5,
                          focal_px: float | None = None, pitch_down_deg: float = 0.0) -> Path:
    """Write the MOT17 sequence in ``folder`` as a recording in ``out`` with a **guessed** camera
    (module doc), tilted down by ``pitch_down_deg`` (-89..89; a camera looking down more than
    ``DetectionConfig.max_pitch_down_deg`` gets the whole image tiled by ``far``); returns ``out``."""
    out = Path(out)
    seq = mot17.read_sequence(folder)
    if not seq.frames:
        raise InputError(f"{folder}: no images")
    if not 0.1 <= camera_height_m <= 100.0:
        raise InputError(f"camera_height_m must be in [0.1, 100], got {camera_height_m!r}")
    if not -89.0 <= pitch_down_deg <= 89.0:
        raise InputError(f"pitch_down_deg must be in [-89, 89], got {pitch_down_deg!r}")
    info = seq.info
    f = float(focal_px) if focal_px is not None else float(info.width)
    if not f > 0:
        raise InputError(f"focal_px must be > 0, got {focal_px!r}")
    images = _prepare(out)
    K = np.array([[f, 0.0, info.width / 2.0], [0.0, f, info.height / 2.0], [0.0, 0.0, 1.0]])
    mount = np.eye(4)
    a = np.radians(pitch_down_deg)
    pitch = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])  # about y (left)
    mount[:3, :3] = pitch @ CAMERA_TO_VEHICLE_AXES
    mount[2, 3] = camera_height_m
    _write_calibration(out / "calibration.yaml", K, info.width, info.height, mount,
                       f"{info.name}: GUESSED camera (MOT17 has no calibration): focal {f:g} px, principal point "
                       f"at the centre, pitched down {pitch_down_deg:g} deg, {camera_height_m} m above the road")
    stamps = np.array([seq.frames[0] - 1, seq.frames[-1]], float) / info.frame_rate
    _write_poses(out / "ego_poses.csv", stamps, np.repeat(np.eye(4)[None], 2, axis=0))
    _link_images(images, [(seq.image_path(n), (n - 1) / info.frame_rate) for n in seq.frames])
    return out


def write_mot17_static_recording(folder: str | Path, cam_para: str | Path, out: str | Path) -> Path:
    """Write the MOT17 sequence in ``folder`` as a static-camera recording in ``out`` with the
    camera estimated in UCMCTrack's ``cam_para`` file (:mod:`pedenv.datasets.ucmctrack`):
    ``calibration.yaml`` with ``mount: static`` and ``images/``, no ego poses; returns ``out``.
    Then ``pedenv run --calibration OUT/calibration.yaml --images OUT/images --output RUN``."""
    out = Path(out)
    seq = mot17.read_sequence(folder)
    if not seq.frames:
        raise InputError(f"{folder}: no images")
    info = seq.info
    cam = static_camera(read_camera_parameters(cam_para), info.width, info.height)
    images = _prepare(out)
    _write_calibration(out / "calibration.yaml", cam.intrinsics, info.width, info.height, cam.cam_to_vehicle,
                       f"{info.name}: camera estimated by UCMCTrack ({Path(cam_para).name}, MIT licence), static",
                       mount="static")
    _link_images(images, [(seq.image_path(n), (n - 1) / info.frame_rate) for n in seq.frames])
    return out
