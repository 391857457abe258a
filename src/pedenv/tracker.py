"""The thin image-plane tracker (paper Sec. III-B): the only place tracking state lives.

Tracks are kept as rows of a few arrays (ids, last boxes, last keypoints, misses,
hits) so that a frame costs a handful of vectorized operations, not a Python loop
per pedestrian. After each update, ``TrackerStep.previous_rows`` tells how the new
rows map to the old ones, so per-track state kept elsewhere (the world position,
the Kalman filter) can be carried along with :func:`carry_rows`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.association import associate
from pedenv.config import TrackingConfig
from pedenv.egomotion import shift_u


#: Weight of the newest displacement in a track's image velocity (exponential smoothing).
MOTION_SMOOTHING = 0.5


class IdCounter:
    """Hands out track ids 1, 2, 3, ... ; ``reset()`` starts again at ``start``."""

    def __init__(self, start: int = 1) -> None:
        self.start = int(start)
        self._next = self.start

    def take(self, count: int) -> np.ndarray:
        """The next ``count`` ids as an int64 array."""
        ids = np.arange(self._next, self._next + count, dtype=np.int64)
        self._next += count
        return ids

    def reset(self) -> None:
        self._next = self.start


@dataclass(frozen=True)
class TrackerStep:
    """What one tracker update did.

    detection_rows: (N,) row of each detection in the new track table.
    previous_rows: (T,) for each row of the new table, its row in the previous table,
        or -1 for a track started in this frame.
    dropped_ids: ids of the tracks removed in this frame.
    """

    detection_rows: np.ndarray
    previous_rows: np.ndarray
    dropped_ids: np.ndarray


def carry_rows(array: np.ndarray, previous_rows: np.ndarray, fill=0) -> np.ndarray:
    """Re-order per-track ``array`` (T_old, ...) to the new table; new rows get ``fill``."""
    padded = np.concatenate([array, np.full((1,) + array.shape[1:], fill, dtype=array.dtype)])
    return padded[previous_rows]  # row -1 is the fill row


class Tracker:
    """GIoU + Hungarian tracker over boxes and skeletons in the image.

    Attributes (one row per live track): ``ids (T,)``, ``boxes (T, 4)`` and
    ``keypoints (T, 17, 2)`` in pixels of the latest frame (ego-yaw compensated),
    ``misses (T,)`` consecutive frames without a detection, ``hits (T,)`` detections so far,
    ``velocities (T, 4)`` pixels per frame of the box edges (used with ``predict_motion``).
    """

    def __init__(self, config: TrackingConfig | None = None, ids: IdCounter | None = None) -> None:
        self.config = config or TrackingConfig()
        self.id_counter = ids or IdCounter()
        self.reset()

    def reset(self) -> None:
        """Forget every track and restart the ids."""
        self.ids = np.zeros(0, np.int64)
        self.boxes = np.zeros((0, 4))
        self.keypoints = np.zeros((0, 17, 2))
        self.misses = np.zeros(0, np.int64)
        self.hits = np.zeros(0, np.int64)
        self.velocities = np.zeros((0, 4))
        self.id_counter.reset()

    def __len__(self) -> int:
        return len(self.ids)

    def update(self, boxes: np.ndarray, keypoints: np.ndarray, u_shift: float = 0.0) -> TrackerStep:
        """Associate one frame's detections with the tracks and update the table.

        boxes: (N, 4), keypoints: (N, 17, 2) float, pixels of the current frame.
        u_shift: pixels to move the tracks' stored u coordinates by before association
            (the ego-yaw compensation of Eq. 1; 0 when it is off).
        """
        if u_shift and len(self.ids):
            self.boxes = shift_u(self.boxes, u_shift)
            self.keypoints = shift_u(self.keypoints, u_shift)
        if self.config.predict_motion and len(self.ids):
            self.boxes = self.boxes + self.velocities  # constant velocity in the image (kept tracks too)
        matches, lost, fresh = associate(boxes, self.boxes, self.config.giou_threshold, self.config.max_height_ratio)
        misses = self.misses[lost] + 1
        alive = misses < self.config.max_misses
        kept = lost[alive]
        n_match, n_kept, n_new = len(matches), len(kept), len(fresh)

        previous_rows = np.concatenate([matches[:, 1], kept, np.full(n_new, -1, np.int64)])
        detection_rows = np.empty(len(boxes), np.int64)
        detection_rows[matches[:, 0]] = np.arange(n_match)
        detection_rows[fresh] = np.arange(n_match + n_kept, n_match + n_kept + n_new)

        new_ids = self.id_counter.take(n_new)
        ids = np.concatenate([self.ids[matches[:, 1]], self.ids[kept], new_ids])
        out_boxes = np.concatenate([boxes[matches[:, 0]], self.boxes[kept], boxes[fresh]])
        out_kp = np.concatenate([keypoints[matches[:, 0]], self.keypoints[kept], keypoints[fresh]])
        hits = np.concatenate([self.hits[matches[:, 1]] + 1, self.hits[kept], np.ones(n_new, np.int64)])
        if self.config.predict_motion:
            seen = self.velocities[matches[:, 1]]
            moved = boxes[matches[:, 0]] - (self.boxes[matches[:, 1]] - seen)  # since the last frame's box
            self.velocities = np.concatenate([
                MOTION_SMOOTHING * moved + (1.0 - MOTION_SMOOTHING) * seen, self.velocities[kept], np.zeros((n_new, 4))])
        else:
            self.velocities = np.zeros((len(ids), 4))
        step = TrackerStep(detection_rows, previous_rows, self.ids[lost[~alive]])
        self.ids, self.boxes, self.keypoints, self.hits = ids, out_boxes, out_kp, hits
        self.misses = np.concatenate([np.zeros(n_match, np.int64), misses[alive], np.zeros(n_new, np.int64)])
        return step
