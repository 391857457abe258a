"""Identity figures on the real samples: KITTI tracking 0016 (3 frames, calibration, 3D
labels) and the MOT17 samples (2D: the tracker alone, image-only association).

    PYTHONPATH=src:tests python tests/tracking/real_identity.py

KITTI: the sequence's ego stands still (ORB-SLAM3 moves < 1 cm), so the vehicle frame is
the world; the camera is 1.65 m above the road (KITTI's setup), looking along its optical
axis. MOT17: the ONNX detections go straight into the tracker (no calibration: the ground
gate and the memory need one, so only the two-stage association and the image motion apply).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from pedenv.config import Config
from pedenv.datasets.kitti_files import read_tracking_sequence
from pedenv.datasets.mot17 import read_sequence, sequence_folders
from pedenv.evaluation.tracking_metrics import TrackingAccumulator
from pedenv.images import read_image_rgb
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Camera, EgoPose, Frame, GroundTruth
from pedenv.tracking.tracker import Tracker

from shared_paths import REAL_SAMPLES

KITTI_TRAINING = REAL_SAMPLES / "kitti" / "tracking_mini" / "training"
KITTI_CAMERA_HEIGHT_M = 1.65
KITTI_FRAME_RATE_HZ = 10.0


def kitti_frames(name: str = "0016") -> list[Frame]:
    """The sequence's frames with an image: camera, static ego, pedestrian ground truth."""
    seq = read_tracking_sequence(KITTI_TRAINING, name)
    cam_to_vehicle = np.array([[0.0, 0.0, 1.0, 0.0], [-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, KITTI_CAMERA_HEIGHT_M],
                               [0.0, 0.0, 0.0, 1.0]])
    frames = []
    for index in seq.frames:
        image = read_image_rgb(seq.image_path(index))
        camera = Camera(seq.calib.K, image.shape[1], image.shape[0], cam_to_vehicle)
        peds = seq.labels.in_frame(index).of_type("Pedestrian")
        loc = peds.locations
        positions = np.column_stack([loc[:, 2], -loc[:, 0], KITTI_CAMERA_HEIGHT_M - loc[:, 1]])
        gt = GroundTruth(peds.track_id, positions, peds.boxes)
        frames.append(Frame(index, index / KITTI_FRAME_RATE_HZ, camera, EgoPose.from_xy_yaw(0.0, 0.0, 0.0), None, gt,
                            image, seq.image_path(index), f"kitti-{name}"))
    return frames


def track_kitti(frames: list[Frame], config: Config, backend) -> tuple[list[dict[int, int]], dict]:
    """Per frame, ground-truth id -> track id (IoU >= 0.5, Hungarian), and the motmetrics summary."""
    model, acc, found = PedestrianEnvironmentModel(config), TrackingAccumulator(), []
    for frame in frames:
        frame = replace(frame, detections=backend(frame))
        peds = model.update(frame).pedestrians
        gt = frame.ground_truth
        acc.add(frame.scene, gt.ids, gt.boxes, peds.track_ids, peds.boxes)
        found.append(_assign(gt.ids, gt.boxes, peds.track_ids, peds.boxes))
    return found, _summary(acc)


def track_mot17(backend, config) -> dict:
    """The tracker alone over each MOT17 sample sequence's ONNX detections (image only)."""
    acc = TrackingAccumulator()
    for folder in sequence_folders(REAL_SAMPLES / "mot17"):
        seq = read_sequence(folder)
        tracker = Tracker(config.tracking)
        for index in seq.frames:
            det = backend.detect(read_image_rgb(seq.image_path(index)))
            step = tracker.update(det.boxes, scores=det.scores)
            keep = step.detection_rows >= 0
            gt = seq.pedestrians.in_frame(index)
            gt = gt.take(gt.consider)
            acc.add(folder.name, gt.ids, gt.boxes, tracker.ids[step.detection_rows[keep]], det.boxes[keep])
    return _summary(acc)


def _assign(gt_ids, gt_boxes, track_ids, boxes) -> dict[int, int]:
    from scipy.optimize import linear_sum_assignment

    from pedenv.evaluation.matching import iou_matrix

    if not len(gt_ids) or not len(track_ids):
        return {}
    iou = iou_matrix(gt_boxes, boxes)
    rows, cols = linear_sum_assignment(-iou)
    return {int(gt_ids[r]): int(track_ids[c]) for r, c in zip(rows, cols) if iou[r, c] >= 0.5}


def _summary(acc: TrackingAccumulator) -> dict:
    mh = acc._mm.metrics.create()
    df = mh.compute_many(list(acc.scenes.values()), names=list(acc.scenes),
                         metrics=["mota", "idf1", "num_switches", "num_matches"], generate_overall=True)
    row = df.loc["OVERALL"]
    return {"mota": float(row["mota"]), "idf1": float(row["idf1"]), "id_switches": int(row["num_switches"]),
            "matches": int(row["num_matches"])}


def main() -> None:
    from identity_scenes import fused_configs

    from pedenv.detection import create_detector

    configs = {"paper": Config(method="paper"), **fused_configs()}
    backends = {threshold: create_detector("onnx", score_threshold=threshold) for threshold in (0.25, 0.1)}
    frames = kitti_frames()
    print("KITTI tracking 0016, frames", [f.index for f in frames], "onnx backend (far)")
    for name, config in configs.items():
        threshold = config.tracking.low_score_threshold or 0.25
        found, summary = track_kitti(frames, config, backends[threshold])
        print(f"{name:7s} score>{threshold:.2f} {summary}")
        for frame, ids in zip(frames, found):
            print(f"    frame {frame.index}: gt id -> track id {dict(sorted(ids.items()))}")
    print("MOT17 samples (tracker alone, image only)")
    for name, config in configs.items():
        threshold = config.tracking.low_score_threshold or 0.25
        print(f"{name:7s} score>{threshold:.2f} {track_mot17(backends[threshold], config)}")


if __name__ == "__main__":
    main()
