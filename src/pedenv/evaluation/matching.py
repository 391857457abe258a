"""The paper's evaluation protocol (Sec. IV-B of Holzbock et al., ITSC 2023).

A predicted pedestrian is matched to the ground-truth pedestrian nearest in world x-y
among those whose 2D box overlaps the prediction's box (IoU > 0). Several predictions
may match the same ground truth, as in the paper.

That rule suits the paper's relative error, not the covariances: it picks whichever truth
lies nearest, which beside a neighbour is often not the person the estimate describes, and
a covariance long in range and thin sideways then scores a sideways miss of a metre.
Coverage and NEES are measured on :func:`match_one_to_one`, the pairing the CLEAR MOT
metrics use (each prediction with at most one person, box IoU at least 0.5).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from pedenv.boxes import iou_matrix


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


def match_one_to_one(pred_boxes: np.ndarray, gt_boxes: np.ndarray, min_iou: float = 0.5) -> np.ndarray:
    """Index (N,) of each prediction's ground truth in the one-to-one assignment of largest
    summed box IoU (Hungarian), -1 where unassigned or below ``min_iou``. Boxes (N, 4), (M, 4) px."""
    out = np.full(len(pred_boxes), -1, np.int64)
    if len(pred_boxes) == 0 or len(gt_boxes) == 0:
        return out
    iou = iou_matrix(pred_boxes, gt_boxes)
    rows, cols = linear_sum_assignment(-iou)
    good = iou[rows, cols] >= min_iou
    out[rows[good]] = cols[good]
    return out


def position_errors(pred_xy: np.ndarray, gt_xy: np.ndarray, ego_xy: np.ndarray,
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Absolute error (metres) and relative error (percent of the ego-to-truth distance).

    pred_xy, gt_xy: (K, 2) matched pairs, world x-y; ego_xy: (2,) the ego vehicle's position.
    Returns ``(abs_error (K,), rel_error_pct (K,), distance (K,))``.
    """
    abs_err = np.linalg.norm(pred_xy - gt_xy, axis=1)
    dist = np.linalg.norm(gt_xy - ego_xy, axis=1)
    return abs_err, 100.0 * abs_err / np.maximum(dist, 1e-6), dist
