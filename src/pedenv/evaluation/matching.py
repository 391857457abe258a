"""The paper's evaluation protocol (Sec. IV-B; FORMATS.md "The paper's evaluation protocol").

A predicted pedestrian is matched to the ground-truth pedestrian nearest in world x-y
among those whose 2D box overlaps the prediction's box (IoU > 0). Several predictions
may match the same ground truth, as in the paper.
"""

from __future__ import annotations

import numpy as np


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU (N, M) between boxes a (N, 4) and b (M, 4), pixels ``[u_min, v_min, u_max, v_max]``."""
    a, b = a[:, None, :], b[None, :, :]
    iw = np.clip(np.minimum(a[..., 2], b[..., 2]) - np.maximum(a[..., 0], b[..., 0]), 0.0, None)
    ih = np.clip(np.minimum(a[..., 3], b[..., 3]) - np.maximum(a[..., 1], b[..., 1]), 0.0, None)
    inter = iw * ih
    union = ((a[..., 2] - a[..., 0]) * (a[..., 3] - a[..., 1]) + (b[..., 2] - b[..., 0]) * (b[..., 3] - b[..., 1])
             - inter)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(union > 0, inter / union, 0.0)


def match_to_ground_truth(pred_boxes: np.ndarray, pred_xy: np.ndarray, gt_boxes: np.ndarray,
                          gt_xy: np.ndarray) -> np.ndarray:
    """Index (N,) of each prediction's ground truth, -1 where no box overlaps.

    pred_boxes (N, 4), gt_boxes (M, 4): pixels. pred_xy (N, 2), gt_xy (M, 2): world x-y, metres.
    """
    if len(pred_boxes) == 0 or len(gt_boxes) == 0:
        return np.full(len(pred_boxes), -1, np.int64)
    overlap = iou_matrix(pred_boxes, gt_boxes) > 0
    dist = np.linalg.norm(pred_xy[:, None, :] - gt_xy[None, :, :], axis=2)
    dist = np.where(overlap, dist, np.inf)
    best = np.argmin(dist, axis=1)
    return np.where(overlap.any(axis=1), best, -1).astype(np.int64)


def position_errors(pred_xy: np.ndarray, gt_xy: np.ndarray, ego_xy: np.ndarray):
    """Absolute error (metres) and relative error (percent of the ego-to-truth distance).

    pred_xy, gt_xy: (K, 2) matched pairs, world x-y; ego_xy: (2,) the ego vehicle's position.
    Returns ``(abs_error (K,), rel_error_pct (K,), distance (K,))``.
    """
    abs_err = np.linalg.norm(pred_xy - gt_xy, axis=1)
    dist = np.linalg.norm(gt_xy - ego_xy, axis=1)
    return abs_err, 100.0 * abs_err / np.maximum(dist, 1e-6), dist
