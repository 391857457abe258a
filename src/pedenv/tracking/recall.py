"""Identities that hold: the tracker's steps beyond the paper, as pure functions.

* :func:`split_by_score`: ByteTrack's two stages; sure detections first, then the
  low-score ones, which may only continue a track.
* :func:`ground_terms`: a gate and a cost from each track's Kalman-predicted ground
  position projected into the image (two people side by side keep their ids).
* :func:`recall_remembered`: a lost (or just missed) track's predicted ground position
  against a new detection's foot point, so a person back from an occlusion gets their id.

Each is off in the paper's configuration (see :class:`~pedenv.config.TrackingConfig`).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from pedenv.boxes import iou_matrix
from pedenv.config import TrackingConfig
from pedenv.config_tracking import START_SCORE_THRESHOLD
from pedenv.tracking.projection import CameraView, pixel_distances
from pedenv.tracking.table import FilterColumns

#: Mean of a chi-square distance with 2 degrees of freedom: the cost of a track whose
#: filter holds no state yet, so it is neither favoured nor penalized against the others.
EXPECTED_DISTANCE_2DOF = 2.0
#: Weight of the projected-prediction distance over the ground gate in the association cost
#: (on the scale of the negative GIoU, [-1, 1]): at the gate it costs as much as boxes that
#: just touch. Not tuned; 1 keeps the box overlap and the prediction on one footing.
GROUND_COST_WEIGHT = 1.0
#: The memory's re-identification gate: the 99 % quantile of a chi-square distance with 2
#: degrees of freedom (``scipy.stats.chi2.ppf(0.99, 2)`` = 9.21).
MEMORY_GATE = 9.21
#: The ground gate and the memory trust the camera only while its projections agree with the
#: image: in a frame where more than this share of the unambiguous box matches (a track and a
#: detection each other's best, IoU >= 0.5; at least 3 of them) fall outside the ground gate,
#: both abstain and the boxes decide. A wrong or guessed calibration otherwise splits every
#: track (MOT17 with a guessed camera: 244 id switches in 39 frames). With a true camera about
#: one match in seven lies outside the 86 % gate by chance, so more than a third is already a
#: sign; at 0.5 a recording whose projections disagreed with the image in 2 of 4 matches kept
#: the gate, and a low-score sliver took a person's id. The seeded synthetic figures and the
#: real KITTI and MOT17 runs are the same at 0.34 and 0.5.
CAMERA_CHECK = 0.34


def split_by_score(scores: np.ndarray | None, count: int, config: TrackingConfig) -> tuple[np.ndarray, np.ndarray]:
    """Detections of the first and of the second association stage, as index arrays.

    scores: (count,) person scores, or None (every detection is sure). With
    ``config.low_score_threshold`` at 0 (the paper) every detection is in the first stage;
    else the first stage holds those scoring at least :data:`START_SCORE_THRESHOLD`, the second
    those at least ``low_score_threshold``, and the rest take part in neither.
    """
    every = np.arange(count, dtype=np.int64)
    if config.low_score_threshold <= 0 or scores is None:
        return every, every[:0]
    scores = np.asarray(scores, np.float64).reshape(count)
    sure = scores >= START_SCORE_THRESHOLD
    return every[sure], every[~sure & (scores >= config.low_score_threshold)]


def predicted_ground(filters: FilterColumns,
                     rows: np.ndarray | slice = slice(None)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kalman-predicted ground positions (R, 2), their covariance (R, 2, 2) (world, metres)
    and whether each filter holds a state (R,) for table ``rows``."""
    x, P = filters.x[rows], filters.P[rows]
    return x[:, [0, 2]], P[:, [0, 2]][:, :, [0, 2]], filters.started[rows]


def ground_terms(boxes: np.ndarray, filters: FilterColumns, view: CameraView | None,
                 config: TrackingConfig) -> tuple[np.ndarray, np.ndarray] | tuple[None, None]:
    """The ground gate's ``(allowed (N, T) bool, extra_cost (N, T))`` for detections
    ``boxes`` (N, 4) pixels and every track row, or ``(None, None)`` when it is off
    (``config.ground_gate`` = 0 or no view). Tracks whose filter holds no state, or whose
    prediction is not surely in front of the camera (its projection means nothing there,
    :func:`~pedenv.tracking.projection.project_ground`), pass the gate with the expected
    cost: the gate abstains and the boxes decide."""
    if view is None or config.ground_gate <= 0 or not len(boxes) or not len(filters.x):
        return None, None
    xy, cov, started = predicted_ground(filters)
    d2 = pixel_distances(view, boxes, xy, cov)
    started = started & np.isfinite(d2).all(axis=0)
    allowed = (d2 <= config.ground_gate) | ~started[None]
    d2 = np.where(started[None], np.minimum(d2, config.ground_gate), EXPECTED_DISTANCE_2DOF)
    return allowed, GROUND_COST_WEIGHT * d2 / config.ground_gate


def camera_disagrees(allowed: np.ndarray, detection_boxes: np.ndarray, track_boxes: np.ndarray,
                     rows: np.ndarray, max_share: float = CAMERA_CHECK) -> bool:
    """Whether the camera's projections contradict the image in this frame: more than
    ``max_share`` (:data:`CAMERA_CHECK`; 1 never) of the unambiguous box matches (detection and live track
    ``rows`` each other's best, IoU >= 0.5; at least 3) lie outside the ground gate
    ``allowed`` (N, T over every row). A wrong calibration, not people, is then the cause."""
    if max_share >= 1.0 or not len(detection_boxes) or not len(rows):
        return False
    iou = iou_matrix(detection_boxes, track_boxes[rows])
    best_track, best_detection = iou.argmax(axis=1), iou.argmax(axis=0)
    d = np.flatnonzero((best_detection[best_track] == np.arange(len(iou))) & (iou.max(axis=1) >= 0.5))
    if len(d) < 3:
        return False
    outside = ~allowed[d, rows[best_track[d]]]
    return bool(outside.mean() > max_share)


def recall_remembered(view: CameraView, boxes: np.ndarray, filters: FilterColumns, rows: np.ndarray,
                      gate: float = MEMORY_GATE) -> np.ndarray:
    """Give remembered tracks their people back.

    boxes: (N, 4) pixels, detections no live track took in the image. rows: (R,) table
    rows of the candidate tracks (remembered ones, and live ones missed in this frame).
    Each track's predicted ground position is compared with each detection's foot point
    (squared Mahalanobis distance, :func:`~pedenv.tracking.projection.pixel_distances`,
    equal to the one on the ground under the linearization); pairs within ``gate`` are
    assigned by the Hungarian algorithm on that distance.
    Returns matches (M, 2) ``[detection index into boxes, index into rows]`` int64.
    """
    xy, cov, started = predicted_ground(filters, rows)
    d2 = pixel_distances(view, boxes, xy, cov)
    allowed = started[None] & (d2 <= gate)
    if not allowed.any():
        return np.zeros((0, 2), np.int64)
    det, trk = linear_sum_assignment(np.where(allowed, d2, 2.0 * gate + 1.0))
    good = allowed[det, trk]
    return np.column_stack([det[good], trk[good]]).astype(np.int64)
