"""Body orientation on the real samples: pedenv's skeleton cue against KITTI's and nuScenes' labelled yaw.

KITTI tracking 0016 (frames 2, 7, 12), KITTI object 000000 and the five nuScenes cameras: the
network's cached detections (``benchmarks/real_detections.py``; score above 0.25) matched to a
labelled pedestrian's box (IoU >= 0.5) are placed by the fused method (no history), and the
behaviour cue of that single frame (:mod:`pedenv.behaviour.orientation`, one update of a flat
heading filter) gives the yaw. Truth: KITTI's ``rotation_y`` (the box's length axis, the
body's facing), nuScenes' ``yaw_global``. Baselines: "always facing the camera" and the walking
direction alone (where the labels give one: nuScenes' velocity, KITTI's track 3 frames either
side; speed at least 0.3 m/s).

    PYTHONPATH=src python benchmarks/behaviour.py --detections det-far.npz   # the tables
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from pedenv.behaviour import heading_filter
from pedenv.behaviour.orientation import skeleton_cue, skeleton_likelihood
from pedenv.config import Config
from pedenv.datasets import kitti_files as kitti
from pedenv.datasets import nuscenes_cameras
from pedenv.evaluation.real_samples import KITTI_CAMERA_HEIGHT_M, load_detection_cache, place
from pedenv.geometry import pixel_rays, wrap_angle
from pedenv.records import Camera, Detections, EgoPose, Frame, default_cam_to_vehicle
from pedenv.synthetic.detector_fit import greedy_match, iou_matrix

SCORE, MIN_WALK_MPS = 0.25, 0.3


def _kitti_yaw(rotation_y: np.ndarray) -> np.ndarray:
    """KITTI ``rotation_y`` -> yaw in the level vehicle frame (x forward, y left): the box's length
    axis ``(cos ry, -sin ry)`` in camera (x, z) is ``(-sin ry, -cos ry)`` in vehicle (x, y)."""
    return np.arctan2(-np.cos(rotation_y), -np.sin(rotation_y))


def _kitti_walk(labels: kitti.KittiLabels, ped: kitti.KittiLabels, frame: int) -> np.ndarray:
    """(M,) walking direction (vehicle frame) of each of ``ped``'s tracks over frames +-3, NaN if unknown."""
    out = np.full(len(ped), np.nan)
    for i, tid in enumerate(ped.track_id):
        rows = {f: labels.locations[(labels.track_id == tid) & (labels.frame == f)] for f in (frame - 3, frame + 3)}
        if all(len(v) for v in rows.values()):
            d = rows[frame + 3][0] - rows[frame - 3][0]
            if np.hypot(d[0], d[2]) / 0.6 >= MIN_WALK_MPS:
                out[i] = np.arctan2(-d[0], d[2])
    return out


def real_samples(samples: Path) -> list[tuple[str, Frame, np.ndarray, np.ndarray, np.ndarray]]:
    """(key, frame without detections, GT boxes (M, 4) px, GT yaw (M,), GT walking direction (M,) or NaN)."""
    out = []

    def kitti_frame(key: str, calib: kitti.KittiCalib, labels: kitti.KittiLabels, index: int,
                    all_labels: kitti.KittiLabels | None = None) -> None:
        ped = labels.of_type("Pedestrian")
        cam = Camera(calib.K, 1224, 370, default_cam_to_vehicle(KITTI_CAMERA_HEIGHT_M))
        frame = Frame(index, 0.1 * index, cam, EgoPose(np.zeros(3), np.eye(3)), scene=key)
        walk = _kitti_walk(all_labels, ped, index) if all_labels is not None else np.full(len(ped), np.nan)
        out.append((key, frame, ped.boxes, _kitti_yaw(ped.rotation_y), walk))

    training = samples / "kitti" / "tracking_mini" / "training"
    seq = kitti.read_tracking_sequence(training, "0016")
    for f in seq.frames:
        kitti_frame(f"kitti/0016/{f}", seq.calib, seq.labels.in_frame(f), f, seq.labels.of_type("Pedestrian"))
    obj = samples / "kitti" / "object_samples" / "training"
    kitti_frame("kitti-object/000000", kitti.read_calib(obj / "calib" / "000000.txt"),
                kitti.read_labels(obj / "label_2" / "000000.txt"), 0)
    for cam in nuscenes_cameras.read_cameras(samples / "nuscenes-0061"):
        ego = EgoPose(cam.ego_to_global[:3, 3], cam.ego_to_global[:3, :3])
        frame = Frame(0, cam.timestamp_us * 1e-6, Camera(cam.K, cam.width, cam.height, cam.cam_to_ego), ego,
                      scene=f"nuscenes/{cam.camera}")
        ped = cam.pedestrians
        v = ped.velocities_xy
        walk = np.where(np.hypot(v[:, 0], v[:, 1]) >= MIN_WALK_MPS, np.arctan2(v[:, 1], v[:, 0]), np.nan)
        out.append((f"nuscenes/{cam.camera}", frame, ped.boxes, ped.yaws_global, walk))
    return out


def real_orientation(samples: Path, detections: Path, config: Config) -> list[dict]:
    """One row per matched pedestrian: errors (degrees) of pedenv and the baselines, distance, pixel height."""
    cache = load_detection_cache(detections)
    cfg = config.behaviour
    cells = heading_filter.cell_centres(cfg.orientation_bins)
    rows = []
    for key, frame, gt_boxes, gt_yaw, gt_walk in real_samples(samples):
        if key not in cache:
            continue
        keep = cache[key]["scores"] > SCORE
        fields = ("keypoints", "confidences", "boxes", "scores")
        det = Detections(*(cache[key][name][keep].astype(float) for name in fields))
        pairs = greedy_match(iou_matrix(det.boxes, gt_boxes), det.scores, 0.5) if len(det) else []
        if not pairs:
            continue
        frame = Frame(frame.index, frame.timestamp, frame.camera, frame.ego, detections=det, scene=frame.scene)
        xy, _, _ = place("fused", frame, config)
        origin = frame.cam_to_world[:3, 3]
        positions = np.column_stack([xy, np.full(len(xy), frame.ego.translation[2])])
        rays = pixel_rays(det.keypoints, frame.camera.intrinsics, frame.cam_to_world)
        cue = skeleton_cue(rays, det.confidences, positions, origin, float(frame.camera.intrinsics[0, 0]))
        p = heading_filter.update(heading_filter.uniform(len(det), len(cells)), skeleton_likelihood(cue, cells))
        yaw, std, available = heading_filter.summary(p, np.radians(cfg.available_std_deg))
        camera_yaw = np.arctan2(cue.toward[:, 1], cue.toward[:, 0])
        for d, g in pairs:
            err = _error_deg(gt_yaw[g])
            rows.append({"key": key, "distance_m": float(np.hypot(*(xy[d] - origin[:2]))),
                         "height_px": float(gt_boxes[g, 3] - gt_boxes[g, 1]), "pedenv": err(yaw[d]),
                         "available": int(available[d]), "std_deg": float(np.degrees(std[d])),
                         "facing_camera": err(camera_yaw[d]),
                         "walking": err(gt_walk[g]) if np.isfinite(gt_walk[g]) else None})
    return rows


def _error_deg(truth: float) -> Callable[[float], float]:
    """A function: estimated yaw (radians) -> absolute error against ``truth`` in degrees."""
    return lambda a: float(np.degrees(abs(wrap_angle(a - truth))))
