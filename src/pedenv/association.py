"""Association of detections to tracks in the image (paper Sec. III-B): GIoU + Hungarian."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

_EMPTY = np.zeros(0, dtype=np.int64)


def giou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Generalized IoU (Rezatofighi et al. 2019) between every box of ``a`` and of ``b``.

    a: (N, 4), b: (M, 4) float, pixels ``[u_min, v_min, u_max, v_max]``.
    Returns (N, M) in [-1, 1]: IoU minus the share of the enclosing box that neither covers.
    Degenerate (zero-area) boxes are handled: two identical points give 1.
    """
    a = a[:, None, :]
    b = b[None, :, :]
    area_a = (a[..., 2] - a[..., 0]) * (a[..., 3] - a[..., 1])
    area_b = (b[..., 2] - b[..., 0]) * (b[..., 3] - b[..., 1])
    iw = np.clip(np.minimum(a[..., 2], b[..., 2]) - np.maximum(a[..., 0], b[..., 0]), 0.0, None)
    ih = np.clip(np.minimum(a[..., 3], b[..., 3]) - np.maximum(a[..., 1], b[..., 1]), 0.0, None)
    inter = iw * ih
    union = area_a + area_b - inter
    hull = (np.maximum(a[..., 2], b[..., 2]) - np.minimum(a[..., 0], b[..., 0])) * (
        np.maximum(a[..., 3], b[..., 3]) - np.minimum(a[..., 1], b[..., 1]))
    with np.errstate(divide="ignore", invalid="ignore"):
        iou = np.where(union > 0, inter / union, 1.0)
        giou = iou - np.where(hull > 0, (hull - union) / hull, 0.0)
    return giou


def associate(detection_boxes: np.ndarray, track_boxes: np.ndarray, threshold: float = -0.3):
    """Assign detections to tracks as the paper does.

    Detections overlapping no track (GIoU <= ``threshold`` with all) start new tracks and
    tracks overlapping no detection count a miss; both are left out of the assignment.
    The rest are assigned by the Hungarian algorithm on the negative GIoU; an assigned
    pair that does not overlap is split again.

    detection_boxes: (N, 4), track_boxes: (T, 4) float, pixels.
    Returns ``(matches (M, 2) [detection, track], unmatched_tracks (U,),
    unmatched_detections (V,))`` as int64 arrays; empty input gives empty outputs.
    """
    n, t = len(detection_boxes), len(track_boxes)
    if n == 0 or t == 0:
        return np.zeros((0, 2), np.int64), np.arange(t, dtype=np.int64), np.arange(n, dtype=np.int64)
    giou = giou_matrix(detection_boxes, track_boxes)
    overlap = giou > threshold
    det_in = np.flatnonzero(overlap.any(axis=1))
    trk_in = np.flatnonzero(overlap.any(axis=0))
    if len(det_in) == 0:
        return np.zeros((0, 2), np.int64), np.arange(t, dtype=np.int64), np.arange(n, dtype=np.int64)
    sub = giou[np.ix_(det_in, trk_in)]
    rows, cols = linear_sum_assignment(-sub)
    good = sub[rows, cols] > threshold
    matches = np.stack([det_in[rows[good]], trk_in[cols[good]]], axis=1).astype(np.int64)
    det_free = np.ones(n, bool)
    det_free[matches[:, 0]] = False
    trk_free = np.ones(t, bool)
    trk_free[matches[:, 1]] = False
    return matches, np.flatnonzero(trk_free), np.flatnonzero(det_free)
