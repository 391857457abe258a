"""Merge the detections of several passes (whole frame, tiles) with a skeleton-aware NMS.

A person seen twice (in the whole-frame pass and a tile, or in two overlapping tiles) is
one person if the two boxes overlap much (IoU) or one box lies mostly inside the other and
their keypoints agree (object keypoint similarity, OKS). The keypoint test keeps two
people standing one behind the other apart although their boxes nest. Detections cut by
an inner tile edge rank after whole ones and are dropped when nested in a kept person
(their keypoints, squeezed into the visible part, need not agree), so a person cut by a
seam is kept from the tile or pass that holds them whole.
"""

from __future__ import annotations

import numpy as np

from pedenv.boxes import box_areas, intersection_matrix, iou_matrix
from pedenv.detection.config import MERGE_CONTAINMENT, MERGE_IOU, MERGE_KEYPOINT_MIN_CONF, MERGE_OKS
from pedenv.records import Detections

#: COCO keypoint sigmas (nose, eyes, ears, shoulders, elbows, wrists, hips, knees, ankles).
COCO_SIGMAS = np.array([0.026, 0.025, 0.025, 0.035, 0.035, 0.079, 0.079, 0.072, 0.072, 0.062, 0.062,
                        0.107, 0.107, 0.087, 0.087, 0.089, 0.089])


def _iou_and_containment(box: np.ndarray, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """IoU (M,) of ``box`` (4,) with ``boxes`` (M, 4), and their intersection over the smaller of
    the two areas (M,): 1 when one box lies inside the other."""
    inter = intersection_matrix(box[None], boxes)[0]
    smaller = np.minimum(box_areas(box[None])[0], box_areas(boxes))
    return iou_matrix(box[None], boxes)[0], inter / smaller


def keypoint_similarity(kp: np.ndarray, conf: np.ndarray, kps: np.ndarray, confs: np.ndarray, box: np.ndarray,
                        boxes: np.ndarray, min_conf: float) -> np.ndarray:
    """OKS of one skeleton with M others over the keypoints both see.

    kp: (17, 2) px, conf: (17,); kps: (M, 17, 2), confs: (M, 17); box/boxes: (4,)/(M, 4) px.
    The scale is the smaller of the two boxes' areas. Returns (M,) in [0, 1]; 0 where
    fewer than 3 keypoints are seen by both.
    """
    both = (conf[None] >= min_conf) & (confs >= min_conf)
    area = np.minimum((box[2] - box[0]) * (box[3] - box[1]), (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1]))
    d2 = ((kps - kp[None]) ** 2).sum(-1)
    e = d2 / (2.0 * np.maximum(area, 1.0)[:, None] * (2 * COCO_SIGMAS[None]) ** 2)
    n = both.sum(1)
    sim = np.where(both, np.exp(-e), 0.0).sum(1) / np.maximum(n, 1)
    return np.where(n >= 3, sim, 0.0)


def merge_detections(parts: list[tuple[Detections, np.ndarray]], max_detections: int = 300) -> Detections:
    """One :class:`Detections` from several passes' detections, duplicates removed.

    parts: ``(detections in image px, cut (N,) bool)`` per pass; ``cut`` marks persons touching
    an inner tile edge. Whole persons come first, then by score; a person is dropped when
    it duplicates one already kept (see the module doc).
    """
    parts = [(d, c) for d, c in parts if len(d)]
    if not parts:
        return Detections.empty()
    every = Detections.concat([d for d, _ in parts])
    kps, confs, boxes, scores = every.keypoints, every.confidences, every.boxes, every.scores
    cut = np.concatenate([np.asarray(c, bool) for _, c in parts])
    order = np.lexsort((-scores, cut))  # whole before cut, then best score first
    keep: list[int] = []
    for i in order:
        if len(keep) >= max_detections:
            break
        if keep:
            k = np.asarray(keep)
            iou, contained = _iou_and_containment(boxes[i], boxes[k])
            oks = keypoint_similarity(kps[i], confs[i], kps[k], confs[k], boxes[i], boxes[k],
                                      MERGE_KEYPOINT_MIN_CONF)
            # a cut person nested in a kept one is a fragment of them, whatever its keypoints say
            duplicate = (iou > MERGE_IOU) | ((contained > MERGE_CONTAINMENT) & ((oks > MERGE_OKS) | cut[i]))
            if duplicate.any():
                continue
        keep.append(int(i))
    keep_sorted = sorted(keep, key=lambda j: -scores[j])
    return Detections(kps[keep_sorted], confs[keep_sorted], boxes[keep_sorted], scores[keep_sorted])
