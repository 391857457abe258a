"""Fitting the detector model to a real network: matching, height bins, the two fits and
the persistent per-person skeleton offsets.

Shared by ``benchmarks/fit_detector_model.py`` (which measures the network on real images)
and the tests that check a fitted profile reproduces those measurements.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import minimize
from scipy.stats import median_abs_deviation

from pedenv.boxes import greedy_match, iou_matrix

#: Person height bins (pixels, ground-truth box height): [low, high).
BINS: tuple[tuple[float, float], ...] = ((0.0, 50.0), (50.0, 100.0), (100.0, 200.0), (200.0, float("inf")))


def bin_index(heights_px: np.ndarray) -> np.ndarray:
    """(N,) int: the :data:`BINS` entry of each height (N,) pixels."""
    edges = np.array([b[1] for b in BINS[:-1]])
    return np.searchsorted(edges, np.asarray(heights_px, float), side="right")


def logistic(heights_px: np.ndarray, half_px: float, slope_px: float) -> np.ndarray:
    """Detection probability (N,) of the detector model's curve at heights (N,) pixels."""
    return 1.0 / (1.0 + np.exp(-(np.asarray(heights_px, float) - half_px) / slope_px))


def fit_detection_curve(heights_px: np.ndarray, detected: np.ndarray) -> tuple[float, float]:
    """Maximum-likelihood ``(half_detection_height_px, detection_slope_px)`` of the logistic
    curve from persons' heights (N,) pixels and whether each was detected (N,) bool."""
    h, y = np.asarray(heights_px, float), np.asarray(detected, bool)

    def nll(p: np.ndarray) -> float:
        q = np.clip(logistic(h, p[0], np.exp(p[1])), 1e-9, 1 - 1e-9)
        return -(np.log(q[y]).sum() + np.log(1 - q[~y]).sum())

    res = minimize(nll, [float(np.median(h)), np.log(20.0)], method="Nelder-Mead",
                   options={"xatol": 1e-3, "fatol": 1e-6, "maxiter": 2000})
    return float(res.x[0]), float(np.exp(res.x[1]))


def fit_noise_law(heights_px: np.ndarray, noise_px: np.ndarray) -> tuple[float, float]:
    """``(noise_px_small, noise_px_large)``: the power law ``noise = a * h^b`` through the
    median noise of each height bin (least squares in logs over the bins with at least 5
    persons, weighted by their counts), read at 30 and 300 px. heights_px, noise_px: (N,).

    Bin medians, not single persons: the per-person noise is skewed and its spread within a
    bin would tilt a fit over persons whose heights span only part of the range.
    """
    h, s = np.asarray(heights_px, float), np.asarray(noise_px, float)
    ok = (h > 0) & (s > 0) & np.isfinite(s)
    h, s = h[ok], s[ok]
    idx = bin_index(h)
    rows = [(np.median(h[idx == b]), np.median(s[idx == b]), (idx == b).sum()) for b in range(len(BINS))
            if (idx == b).sum() >= 5]
    if not rows:
        raise ValueError("fit_noise_law needs at least 5 persons in one height bin")
    mh, ms, n = map(np.array, zip(*rows))
    if len(rows) == 1:
        return float(ms[0]), float(ms[0])
    b, log_a = np.polyfit(np.log(mh), np.log(ms), 1, w=np.sqrt(n))
    return float(np.exp(log_a) * 30.0**b), float(np.exp(log_a) * 300.0**b)


def recall_by_bin(heights_px: np.ndarray, detected: np.ndarray) -> list[float | None]:
    """Share detected (None for an empty bin) per :data:`BINS` entry. heights_px, detected: (N,)."""
    idx, detected = bin_index(heights_px), np.asarray(detected, bool)
    return [float(detected[idx == b].mean()) if (idx == b).any() else None for b in range(len(BINS))]


def synthetic_recall(frames: Any, model: Any, span_over_box: float) -> tuple[np.ndarray, np.ndarray]:
    """Run the detector ``model`` on ``frames`` (with ground-truth skeletons) and match like the
    real benchmark (IoU >= 0.5, greedy by score). Returns ``(heights (N,) px, detected (N,) bool)``.

    The synthetic ground-truth boxes are the keypoints' hull; a real annotated box reaches from
    the head's top to the soles, so each person's height is given in that convention: keypoint
    extent / ``span_over_box`` (the measured ratio of the two on real images).
    """
    heights, detected = [], []
    for frame in frames:
        gt = frame.ground_truth
        if gt is None or len(gt) == 0:
            continue
        det = model(frame)
        pairs = greedy_match(iou_matrix(det.boxes, gt.boxes), det.scores, 0.5)
        got = np.zeros(len(gt), bool)
        got[[g for _, g in pairs]] = True
        heights.append(np.ptp(gt.keypoints[..., 1], axis=1) / span_over_box)
        detected.append(got)
    if not heights:
        return np.zeros(0), np.zeros(0, bool)
    return np.concatenate(heights), np.concatenate(detected)


# Persistent per-person skeleton offsets (benchmarks/person_offsets.py measures the real ones).
#: Ankles and hips (COCO-17 indices), the person score and keypoint confidence they are measured above.
ANKLES, HIPS = [15, 16], [11, 12]
SCORE, KP_CONF = 0.25, 0.3


def robust_std(x: np.ndarray) -> float:
    """1.4826 x the median absolute deviation: the std of a normal sample, robust to outliers."""
    return float(median_abs_deviation(x, scale="normal")) if len(x) else float("nan")


class Offsets:
    """Per-person lists of (foot, column, box height px) rows."""

    def __init__(self) -> None:
        self.rows: dict[tuple, list[tuple[float, float, float]]] = {}

    def add(self, key_of: Any, keypoints: np.ndarray, confidences: np.ndarray, scores: np.ndarray,
            boxes: np.ndarray, truth_boxes: np.ndarray, ground_uv: np.ndarray, counted: np.ndarray) -> None:
        """One image: detections (N, 17, 2) px, (N, 17), (N,), boxes (N, 4) px; truth boxes
        (M, 4) px, true ground points (M, 2) px, counted (M,) bool; ``key_of(g)`` names truth
        person g."""
        keep = np.asarray(scores) > SCORE
        kp, cf, sc = np.asarray(keypoints)[keep], np.asarray(confidences)[keep], np.asarray(scores)[keep]
        truth = np.asarray(truth_boxes, float).reshape(-1, 4)
        for d, g in greedy_match(iou_matrix(np.asarray(boxes)[keep], truth), sc, 0.5):
            if not counted[g] or (cf[d, ANKLES + HIPS] < KP_CONF).any():
                continue
            h = truth[g, 3] - truth[g, 1]
            foot = (kp[d, ANKLES, 1].mean() - ground_uv[g, 1]) / h
            column = (kp[d, ANKLES + HIPS, 0].mean() - ground_uv[g, 0]) / h
            self.rows.setdefault(key_of(g), []).append((float(foot), float(column), float(h)))

    def summary(self) -> dict:
        """Median offsets and their spread across persons (robust std), in box heights."""
        per = np.array([np.median(np.array(v), axis=0) for v in self.rows.values()]).reshape(-1, 3)
        within = [np.array(v)[:, :2] - np.median(np.array(v)[:, :2], axis=0) for v in self.rows.values() if len(v) > 1]
        w = np.concatenate(within) if within else np.zeros((0, 2))
        return {"persons": int(len(per)), "detections": int(sum(len(v) for v in self.rows.values())),
                "median_box_height_px": float(np.median(per[:, 2])) if len(per) else None,
                "foot_median": float(np.median(per[:, 0])), "foot_across_persons": robust_std(per[:, 0]),
                "column_median": float(np.median(per[:, 1])), "column_across_persons": robust_std(per[:, 1]),
                "foot_within_person": robust_std(w[:, 0]), "column_within_person": robust_std(w[:, 1])}


def synthetic_offsets(model: Any, scenes: Any) -> tuple[Offsets, float]:
    """Offsets of ``model``'s detections against the projected true positions on ``scenes``,
    and the median ratio of box height to keypoint extent of the persons measured."""
    from pedenv.geometry import invert_transform, project

    acc, ratios = Offsets(), []
    for scene in scenes:
        for frame in scene.frames:
            gt = frame.ground_truth
            if gt is None or not len(gt.ids):
                continue
            det = model(frame)
            uv, _ = project(gt.positions, frame.camera.intrinsics, invert_transform(frame.cam_to_world))
            acc.add(lambda g, s=scene.name, ids=gt.ids: (s, int(ids[g])), det.keypoints, det.confidences,
                    det.scores, det.boxes, gt.boxes, uv, np.ones(len(gt.ids), bool))
            ratios.append((gt.boxes[:, 3] - gt.boxes[:, 1]) / np.maximum(np.ptp(gt.keypoints[..., 1], axis=1), 1.0))
    return acc, float(np.median(np.concatenate(ratios)))


def fit_person_offset(real: dict, synthetic: dict, box_over_extent: float) -> dict[str, float]:
    """The detector model's per-person offsets (in keypoint extents) that bring the synthetic
    spread across persons up to the real one: ``sqrt(real**2 - synthetic**2)``, 0 where the
    synthetic spread is already as large."""
    def extra(key: str) -> float:
        return float(np.sqrt(max(real[key] ** 2 - synthetic[key] ** 2, 0.0)) * box_over_extent)

    return {"person_offset_u": extra("column_across_persons"), "person_offset_v": extra("foot_across_persons")}
