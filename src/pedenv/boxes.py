"""Axis-aligned image boxes: IoU, containment, generalized IoU, greedy matching and non-maximum suppression.

Every box is ``[u_min, v_min, u_max, v_max]`` in pixels (any one unit works, the results
are ratios). All functions are vectorized over the boxes.
"""

from __future__ import annotations

import numpy as np

#: Areas (pixels^2) are divided by at least this, so zero-area boxes give no NaN.
_MIN_AREA = 1e-12


def _overlaps(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, ...]:
    """Signed overlap widths and heights (N, M) and the sizes of a (N, 1) and b (M,).

    The overlap is negative along an axis where the boxes are apart.
    """
    a, b = np.asarray(a, float), np.asarray(b, float)
    ax0, ay0, ax1, ay1 = (c[:, None] for c in a.T)
    bx0, by0, bx1, by1 = b.T
    iw = np.minimum(ax1, bx1) - np.maximum(ax0, bx0)
    ih = np.minimum(ay1, by1) - np.maximum(ay0, by0)
    return iw, ih, ax1 - ax0, ay1 - ay0, bx1 - bx0, by1 - by0


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Intersection over union between every box of ``a`` and every box of ``b``.

    a: (N, 4), b: (M, 4) float, pixels ``[u_min, v_min, u_max, v_max]``.
    Returns (N, M) in [0, 1]; 0 where the union has no area (zero-area boxes).
    """
    iw, ih, wa, ha, wb, hb = _overlaps(a, b)
    inter = np.maximum(iw, 0.0) * np.maximum(ih, 0.0)
    union = wa * ha + wb * hb - inter
    return inter / np.maximum(union, _MIN_AREA)


def intersection_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, M) intersection areas of boxes a (N, 4) and b (M, 4), pixels^2 (0 where apart)."""
    iw, ih, *_ = _overlaps(np.asarray(a, float).reshape(-1, 4), np.asarray(b, float).reshape(-1, 4))
    return np.maximum(iw, 0.0) * np.maximum(ih, 0.0)


def box_areas(boxes: np.ndarray) -> np.ndarray:
    """(N,) areas of boxes (N, 4), pixels^2, at least the smallest area divided by (no zeros)."""
    boxes = np.asarray(boxes, float).reshape(-1, 4)
    return np.maximum((boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1]), _MIN_AREA)


def containment_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, M) share of each box of ``a`` that lies inside each box of ``b``: intersection over
    the area of ``a``, in [0, 1]. a: (N, 4), b: (M, 4) pixels."""
    return intersection_matrix(a, b) / box_areas(a)[:, None]


def greedy_match(iou: np.ndarray, scores: np.ndarray, threshold: float = 0.5) -> list[tuple[int, int]]:
    """(detection, ground truth) pairs: detections by falling score take their best free box
    with IoU >= ``threshold`` (as detection benchmarks count). iou: (N, M); scores: (N,)."""
    pairs, taken = [], np.zeros(iou.shape[1], bool)
    for d in np.argsort(-np.asarray(scores), kind="stable"):
        if iou.shape[1] == 0:
            break
        cand = np.where(taken, -1.0, iou[d])
        g = int(np.argmax(cand))
        if cand[g] >= threshold:
            taken[g] = True
            pairs.append((int(d), g))
    return pairs


def giou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Generalized IoU (Rezatofighi et al. 2019) between every box of ``a`` and of ``b``.

    a: (N, 4), b: (M, 4) float, pixels ``[u_min, v_min, u_max, v_max]``.
    Returns (N, M) in [-1, 1]: the IoU minus the share of the smallest enclosing box
    (the hull) that neither box covers. Boxes far apart tend to -1. Zero-area boxes do
    not divide by zero: two of them give -1 (no IoU, a hull of no area).
    """
    iw, ih, wa, ha, wb, hb = _overlaps(a, b)
    # the hull's sides follow from the signed overlaps: w_hull = w_a + w_b - w_overlap
    hull = (wa + wb - iw) * (ha + hb - ih)
    inter = np.maximum(iw, 0.0) * np.maximum(ih, 0.0)
    union = wa * ha + wb * hb - inter
    # IoU - (hull - union) / hull
    return inter / np.maximum(union, _MIN_AREA) + union / np.maximum(hull, _MIN_AREA) - 1.0


def nms(boxes: np.ndarray, scores: np.ndarray, iou_threshold: float, max_detections: int = 300) -> np.ndarray:
    """Greedy non-maximum suppression.

    boxes: (N, 4) float, pixels ``[u_min, v_min, u_max, v_max]``; scores: (N,).
    A box is dropped when its IoU with a higher-scoring kept box is above
    ``iou_threshold``; equal scores keep their input order. Returns the kept indices
    (K,) int64, best score first, at most ``max_detections``.
    """
    boxes = np.asarray(boxes, float)
    order = np.argsort(-np.asarray(scores), kind="stable")
    keep: list[int] = []
    while order.size and len(keep) < max_detections:
        best, rest = order[0], order[1:]
        keep.append(best)
        order = rest[iou_matrix(boxes[best][None], boxes[rest])[0] <= iou_threshold]
    return np.asarray(keep, dtype=np.int64)
