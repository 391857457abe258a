"""Association of detections to tracks in the image (paper Sec. III-B): GIoU + Hungarian."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from pedenv.boxes import giou_matrix


def associate(detection_boxes: np.ndarray, track_boxes: np.ndarray, threshold: float = -0.3,
              max_height_ratio: float = 0.0, allowed: np.ndarray | None = None,
              extra_cost: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Assign detections to tracks as the paper does.

    Detections overlapping no track (GIoU <= ``threshold`` with all) start new tracks and
    tracks overlapping no detection count a miss; both are left out of the assignment.
    The rest are assigned by the Hungarian algorithm on the negative GIoU; an assigned
    pair that does not overlap is split again.

    detection_boxes: (N, 4), track_boxes: (T, 4) float, pixels.
    max_height_ratio: when > 0, pairs whose box heights differ by more than this factor
        do not overlap whatever their GIoU (beyond the paper; 0 keeps the paper's rule).
    allowed: optional (N, T) bool, beyond the paper: pairs marked False do not overlap
        (e.g. outside a gate around the track's predicted ground position).
    extra_cost: optional (N, T) float added to the negative GIoU of overlapping pairs.
    Returns ``(matches (M, 2) [detection, track], unmatched_tracks (U,),
    unmatched_detections (V,))`` as int64 arrays; empty input gives empty outputs.
    """
    n, t = len(detection_boxes), len(track_boxes)
    if n == 0 or t == 0:
        return np.zeros((0, 2), np.int64), np.arange(t, dtype=np.int64), np.arange(n, dtype=np.int64)
    giou = giou_matrix(detection_boxes, track_boxes)
    overlap = giou > threshold
    if max_height_ratio > 0:
        hd = np.maximum(detection_boxes[:, 3] - detection_boxes[:, 1], 1e-6)[:, None]
        ht = np.maximum(track_boxes[:, 3] - track_boxes[:, 1], 1e-6)[None, :]
        overlap &= np.maximum(hd / ht, ht / hd) <= max_height_ratio
    if allowed is not None:
        overlap &= allowed
    cost, apart = (-giou, 10.0) if extra_cost is None else (extra_cost - giou, 10.0 + np.abs(extra_cost).max())
    # Pairs that do not overlap cost more than any overlapping pair, so the assignment
    # among overlapping rows and columns is the paper's; such pairs are split below.
    rows, cols = linear_sum_assignment(np.where(overlap, cost, apart))
    good = overlap[rows, cols]
    matches = np.column_stack([rows[good], cols[good]]).astype(np.int64)
    det_free = np.ones(n, bool)
    det_free[matches[:, 0]] = False
    trk_free = np.ones(t, bool)
    trk_free[matches[:, 1]] = False
    return matches, np.flatnonzero(trk_free), np.flatnonzero(det_free)
