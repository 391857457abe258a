"""The real samples with 3D ground truth, as frames, and the real network's cached detections.

KITTI tracking 0016 (its labelled frames), KITTI object 000000 and the five nuScenes cameras of
``../shared/samples/real``; the detections are the ``.npz`` cache that
``benchmarks/real_detections.py`` writes (one array per image and field, named ``KEY|FIELD``).
Used by ``benchmarks/fused_calibration.py``, ``benchmarks/fit_detector_model.py`` and
``benchmarks/behaviour.py``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pedenv.config import Config
from pedenv.datasets import kitti_files as kitti
from pedenv.datasets import nuscenes_cameras
from pedenv.errors import InputError
from pedenv.evaluation.detections import KITTI_CAMERA_HEIGHT_M
from pedenv.localization import configure, create_locator
from pedenv.localization.base import FrameGeometry
from pedenv.records import Camera, EgoPose, Frame, default_cam_to_vehicle


def load_detection_cache(path: Path) -> dict[str, dict[str, np.ndarray]]:
    """The cache of ``benchmarks/real_detections.py``: image key -> field -> array. Plain arrays
    only (``allow_pickle=False``): a cache holding an object array is refused, never run."""
    data = np.load(path, allow_pickle=False)
    out: dict[str, dict[str, np.ndarray]] = {}
    for name in data.files:
        key, field = name.split("|")
        out.setdefault(key, {})[field] = data[name]
    return out


def real_frames(samples: Path) -> list[tuple[str, Frame, np.ndarray, np.ndarray]]:
    """(key, frame without detections, GT boxes (M, 4) px, GT ground points (M, 2) world x-y m)."""
    out = []

    def kitti_frame(key: str, calib: kitti.KittiCalib, labels: kitti.KittiLabels, image_size: tuple[int, int],
                    index: int) -> None:
        ped = labels.of_type("Pedestrian")
        k = calib.K
        cam = Camera(k, *image_size, default_cam_to_vehicle(KITTI_CAMERA_HEIGHT_M))
        # vehicle frame (x forward, y left, z up) with cam2 at (0, 0, height); labels are in rectified cam0
        rel = ped.locations - calib.cam2_position
        ground = np.column_stack([rel[:, 2], -rel[:, 0]])
        frame = Frame(index, 0.1 * index, cam, EgoPose(np.zeros(3), np.eye(3)), scene=key)
        out.append((key, frame, ped.boxes, ground))

    training = samples / "kitti" / "tracking_mini" / "training"
    seq = kitti.read_tracking_sequence(training, "0016")
    for f in seq.frames:
        kitti_frame(f"kitti/0016/{f}", seq.calib, seq.labels.in_frame(f), (1224, 370), f)
    obj = samples / "kitti" / "object_samples" / "training"
    kitti_frame("kitti-object/000000", kitti.read_calib(obj / "calib" / "000000.txt"),
                kitti.read_labels(obj / "label_2" / "000000.txt"), (1224, 370), 0)
    for cam in nuscenes_cameras.read_cameras(samples / "nuscenes-0061"):
        ego = EgoPose(cam.ego_to_global[:3, 3], cam.ego_to_global[:3, :3])
        frame = Frame(0, cam.timestamp_us * 1e-6, Camera(cam.K, cam.width, cam.height, cam.cam_to_ego), ego,
                      scene=f"nuscenes/{cam.camera}")
        ped = cam.pedestrians
        out.append((f"nuscenes/{cam.camera}", frame, ped.boxes, ped.ground_points_global[:, :2]))
    return out


def place(method: str, frame: Frame, config: Config) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (N, 2) and reported covariances (N, 2, 2) of the frame's detections by ``method``."""
    cfg = configure(config, method)
    locator = create_locator(cfg)
    geo = FrameGeometry.of(frame)
    assert frame.detections is not None, "place needs the frame's detections"
    n = len(frame.detections)
    if getattr(locator, "columns", None) is not None:
        locator.columns.carry(np.full(n, -1))  # a new track row for every detection
    m = locator.locate(geo, np.arange(n))
    cov = m.covariances + (m.bias_covariances if m.bias_covariances is not None else 0.0)
    return m.positions[:, :2], cov, m.sources


def sample_images(samples: Path) -> list[tuple[str, Path, Any]]:
    """(key, image path, camera geometry for the ``far`` band or None) of every real sample
    image: ``mot17/<SEQ>/<frame>``, ``kitti/<seq>/<frame>``, ``kitti-object/<id>``,
    ``nuscenes/<CAM>``. The geometry is the one ``pedenv evaluate-detections`` uses (KITTI:
    level camera 1.65 m up; nuScenes: the camera's pose; MOT17: none, the whole image is tiled)."""
    from pedenv.datasets import mot17
    from pedenv.detection.geometry import CameraGeometry

    out: list[tuple[str, Path, CameraGeometry | None]] = []
    for folder in mot17.sequence_folders(samples / "mot17"):
        mseq = mot17.read_sequence(folder)
        out += [(f"mot17/{folder.name}/{f}", mseq.image_path(f), None) for f in mseq.frames]
    training = samples / "kitti" / "tracking_mini" / "training"
    for name in kitti.tracking_sequence_names(training):
        seq = kitti.read_tracking_sequence(training, name)
        geometry = CameraGeometry.level(seq.calib.K, KITTI_CAMERA_HEIGHT_M)
        out += [(f"kitti/{name}/{f}", seq.image_path(f), geometry) for f in seq.frames]
    objects = samples / "kitti" / "object_samples" / "training"
    for p in sorted((objects / "image_2").glob("*.png")):
        calib = kitti.read_calib(objects / "calib" / f"{p.stem}.txt")
        out.append((f"kitti-object/{p.stem}", p, CameraGeometry.level(calib.K, KITTI_CAMERA_HEIGHT_M)))
    for cam in nuscenes_cameras.read_cameras(samples / "nuscenes-0061"):
        height = float(cam.cam_to_global[2, 3] - cam.ego_to_global[2, 3])
        out.append((f"nuscenes/{cam.camera}", cam.image_path, CameraGeometry(cam.K, cam.cam_to_global[:3, :3], height)))
    return out


def detect_samples(samples: Path, backend: Any, prefixes: tuple[str, ...] = ()) -> dict[str, np.ndarray]:
    """The arrays of a detection cache (:func:`load_detection_cache`): ``backend.detect(rgb, geometry)``
    (a ``fast`` or ``far`` pose backend) over every sample image whose key starts with one of
    ``prefixes`` (all without)."""
    import cv2

    arrays: dict[str, np.ndarray] = {}
    for key, path, geometry in sample_images(samples):
        if prefixes and not key.startswith(prefixes):
            continue
        bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if bgr is None:
            raise InputError(f"{path}: not a readable image")
        det = backend.detect(np.ascontiguousarray(bgr[..., ::-1]), geometry)
        for name in ("keypoints", "confidences", "boxes", "scores"):
            arrays[f"{key}|{name}"] = np.asarray(getattr(det, name), np.float32)
    return arrays
