"""Person-detection recall and precision on real images (KITTI, MOT17, nuScenes samples).

Matching: per image, greedy by detection score, each detection takes the unmatched
ground-truth box with the highest IoU if that IoU >= the sample's threshold (0.5; nuScenes
0.3, since its boxes are projected 3D boxes, looser than a person's visible extent).
Ground truth is *required* (counts for recall) or *optional* (MOT17 visibility < 0.5,
KITTI Person_sitting): a detection matching an optional box is neither a hit nor a false
positive, and neither is one lying at least ``OCCLUDED_INSIDE`` inside an optional box no
detection matched (the visible part of a mostly occluded person, whose IoU with the amodal
box stays below the threshold; counted apart as ``occluded_parts``, so the strict precision
that counts them as false can be given too). A detection lying at least half inside an
ignore region (KITTI DontCare and Cyclist; MOT17 classes 2, 7, 8, 12) is no false positive. nuScenes images count for
recall only (its README: annotations do not cover every visible person).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from pedenv.boxes import containment_matrix, greedy_match, iou_matrix
from pedenv.datasets import kitti_files as kitti
from pedenv.datasets import mot17, nuscenes_cameras
from pedenv.detection.geometry import CameraGeometry
from pedenv.errors import InputError

#: Person height bins, pixels: (label, low, high).
HEIGHT_BINS = (("<50", 0.0, 50.0), ("50-100", 50.0, 100.0), ("100-200", 100.0, 200.0), (">=200", 200.0, np.inf))
#: The bins of the issue's goals, pixels.
GOAL_BINS = (("<40", 0.0, 40.0), ("40-80", 40.0, 80.0), (">=80", 80.0, np.inf))
#: Distance bins, metres (where 3D ground truth exists).
DISTANCE_BINS = (("0-15", 0.0, 15.0), ("15-30", 15.0, 30.0), ("30-50", 30.0, 50.0), (">50", 50.0, np.inf))
KITTI_CAMERA_HEIGHT_M = 1.65
#: KITTI tracking's frame rate, Hz (the samples' timestamps: frame index / rate).
KITTI_RATE_HZ = 10.0
#: Fraction of a detection's box inside an unmatched optional (occluded) person's box that makes it that person.
OCCLUDED_INSIDE = 0.7


@dataclass(frozen=True)
class DetectionSample:
    """One real image with its persons.

    boxes: (M, 4) px ``[u_min, v_min, u_max, v_max]`` clipped to the image. heights: (M,) px
    (the dataset's own box height: MOT17 amodal). distances: (M,) metres or NaN.
    required: (M,) bool. ignore: (K, 4) px regions. geometry: camera for the far band, or None.
    sequence: name of the sequence whose consecutive frames the sample is one of ("" for a
    single image); timestamp: its time in that sequence, seconds (``stream`` detection).
    """

    dataset: str
    name: str
    image_path: Path
    boxes: np.ndarray
    heights: np.ndarray
    distances: np.ndarray
    required: np.ndarray
    ignore: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    count_false_positives: bool = True
    iou_threshold: float = 0.5
    geometry: CameraGeometry | None = None
    sequence: str = ""
    timestamp: float = 0.0


def kitti_samples(root: Path) -> list[DetectionSample]:
    """KITTI tracking (label_02) and object (label_2) samples under ``root`` (the ``kitti/`` folder)."""
    out = []
    tracking = root / "tracking_mini" / "training"
    for name in kitti.tracking_sequence_names(tracking):
        seq = kitti.read_tracking_sequence(tracking, name)
        for frame in seq.frames:
            sample = _kitti_sample(f"tracking {name}/{frame:06d}", seq.image_path(frame), seq.labels.in_frame(frame),
                                   seq.calib)
            out.append(replace(sample, sequence=f"kitti tracking {name}", timestamp=frame / KITTI_RATE_HZ))
    objects = root / "object_samples" / "training"
    for image in sorted((objects / "image_2").glob("*.png")):
        out.append(
            _kitti_sample(
                f"object {image.stem}",
                image,
                kitti.read_labels(objects / "label_2" / f"{image.stem}.txt"),
                kitti.read_calib(objects / "calib" / f"{image.stem}.txt"),
            )
        )
    return out


def _kitti_sample(name: str, image: Path, labels: kitti.KittiLabels, calib: kitti.KittiCalib) -> DetectionSample:
    people = labels.of_type("Pedestrian", "Person_sitting")
    geometry = CameraGeometry.level(calib.K, KITTI_CAMERA_HEIGHT_M)
    return DetectionSample(
        "kitti", name, image, people.boxes, people.boxes[:, 3] - people.boxes[:, 1],
        np.hypot(people.locations[:, 0], people.locations[:, 2]), people.types == "Pedestrian",
        labels.of_type("DontCare", "Cyclist").boxes, geometry=geometry)


def mot17_samples(root: Path) -> list[DetectionSample]:
    """One sample per image of every MOT17 sequence under ``root``; no calibration (whole image tiled)."""
    out = []
    for folder in mot17.sequence_folders(root):
        seq = mot17.read_sequence(folder)
        w, h = seq.info.width, seq.info.height
        for frame in seq.frames:
            gt = seq.pedestrians.in_frame(frame)
            out.append(DetectionSample(
                "mot17", f"{seq.info.name}/{frame:06d}", seq.image_path(frame), gt.clipped(w, h),
                gt.boxes[:, 3] - gt.boxes[:, 1], np.full(len(gt), np.nan), gt.consider & (gt.visibility >= 0.5),
                np.clip(seq.ignore_boxes(frame), 0, [w, h, w, h]), sequence=seq.info.name,
                timestamp=frame / seq.info.frame_rate))
    return out


def nuscenes_samples(root: Path) -> list[DetectionSample]:
    """One sample per camera JSON under ``root``; recall only."""
    out = []
    for cam in nuscenes_cameras.read_cameras(root):
        p = cam.pedestrians
        rotation = cam.cam_to_global[:3, :3]
        height = float(cam.cam_to_global[2, 3] - cam.ego_to_global[2, 3])
        out.append(DetectionSample(
            "nuscenes", cam.camera, cam.image_path, p.boxes, p.boxes[:, 3] - p.boxes[:, 1], p.distances_xy,
            np.ones(len(p), bool), count_false_positives=False, iou_threshold=0.3,
            geometry=CameraGeometry(cam.K, rotation, height)))
    return out


def load_samples(data_root: str | Path) -> list[DetectionSample]:
    """Every sample under ``data_root`` (holding ``kitti/``, ``mot17/``, ``nuscenes-0061/``; any may be absent)."""
    root = Path(data_root)
    if not root.is_dir():
        raise InputError(f"{root}: data root not found")
    out = []
    if (root / "kitti").is_dir():
        out += kitti_samples(root / "kitti")
    if (root / "mot17").is_dir():
        out += mot17_samples(root / "mot17")
    if (root / "nuscenes-0061").is_dir():
        out += nuscenes_samples(root / "nuscenes-0061")
    if not out:
        raise InputError(f"{root}: no kitti/, mot17/ or nuscenes-0061/ samples")
    return out


@dataclass(frozen=True)
class FrameMatch:
    """Outcome on one image: hit (M,) bool per ground truth; false_positives: count;
    occluded_parts: detections of the visible part of an optional person (no false positive)."""

    hit: np.ndarray
    false_positives: int
    detections: int
    occluded_parts: int = 0


def match_detections(sample: DetectionSample, boxes: np.ndarray, scores: np.ndarray) -> FrameMatch:
    """Match detections (N, 4) px with scores (N,) to the sample's ground truth (module doc)."""
    boxes = np.asarray(boxes, float).reshape(-1, 4)
    hit = np.zeros(len(sample.boxes), bool)
    taken = np.zeros(len(sample.boxes), bool)
    pairs = greedy_match(iou_matrix(boxes, sample.boxes), scores, sample.iou_threshold)
    matched = np.zeros(len(boxes), bool)
    for i, j in pairs:
        matched[i], taken[j], hit[j] = True, True, sample.required[j]
    order = np.argsort(-np.asarray(scores), kind="stable")
    unmatched = [i for i in order if not matched[i] and sample.count_false_positives
                 and not _inside_any(boxes[i], sample.ignore)]
    occluded = list(sample.boxes[~sample.required & ~taken])
    parts = 0
    for i in unmatched:  # each occluded person absorbs at most one detection
        inside = [k for k, box in enumerate(occluded) if _inside_any(boxes[i], box[None], OCCLUDED_INSIDE)]
        if inside:
            occluded.pop(inside[0])
            parts += 1
    return FrameMatch(hit & sample.required, len(unmatched) - parts, len(boxes), parts)


def _inside_any(box: np.ndarray, regions: np.ndarray, fraction: float = 0.5) -> bool:
    """Whether at least ``fraction`` of ``box`` (4,) lies inside one of ``regions`` (M, 4), pixels."""
    return bool(len(regions)) and bool((containment_matrix(box[None], regions) >= fraction).any())


def _bins(values: np.ndarray, hits: np.ndarray, bins: Iterable[tuple[str, float, float]]) -> list[dict]:
    rows = []
    for label, low, high in bins:
        inside = (values >= low) & (values < high)
        n, k = int(inside.sum()), int(hits[inside].sum())
        rows.append({"bin": label, "persons": n, "found": k, "recall": k / n if n else None})
    return rows


def summarize(samples: list[DetectionSample], matches: list[FrameMatch], ms: list[float]) -> dict:
    """Recall by height and distance bin, precision and ms per frame, overall and per dataset."""
    def block(idx: list[int]) -> dict:
        req = [samples[i].required for i in idx]
        heights = np.concatenate([samples[i].heights[r] for i, r in zip(idx, req)]) if idx else np.zeros(0)
        dist = np.concatenate([samples[i].distances[r] for i, r in zip(idx, req)]) if idx else np.zeros(0)
        hits = np.concatenate([matches[i].hit[r] for i, r in zip(idx, req)]) if idx else np.zeros(0, bool)
        counted = [i for i in idx if samples[i].count_false_positives]
        tp = sum(int(matches[i].hit.sum()) for i in counted)
        fp = sum(matches[i].false_positives for i in counted)
        parts = sum(matches[i].occluded_parts for i in counted)
        return {"images": len(idx), "persons": len(hits), "found": int(hits.sum()),
                "recall": float(hits.mean()) if len(hits) else None,
                "precision": tp / (tp + fp) if tp + fp else None, "true_positives": tp, "false_positives": fp,
                "occluded_parts": parts, "precision_strict": tp / (tp + fp + parts) if tp + fp + parts else None,
                "ms_per_frame": float(np.mean([ms[i] for i in idx])) if idx else None,
                "by_height": _bins(heights, hits, HEIGHT_BINS), "by_goal_height": _bins(heights, hits, GOAL_BINS),
                "by_distance": _bins(dist[np.isfinite(dist)], hits[np.isfinite(dist)], DISTANCE_BINS)}

    datasets = sorted({s.dataset for s in samples})
    out = {"all": block(list(range(len(samples))))}
    for d in datasets:
        out[d] = block([i for i, s in enumerate(samples) if s.dataset == d])
    return out
