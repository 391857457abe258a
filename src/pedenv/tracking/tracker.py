"""The thin image-plane tracker (paper Sec. III-B).

Each frame it associates the detections with the tracks of the :class:`TrackTable`,
decides the next table (matched, kept and new tracks) and carries every per-track
column there at once (:meth:`TrackTable.carry`), the Kalman filter's and the position
method's included.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.tracking.association import associate
from pedenv.config import TrackingConfig
from pedenv.tracking.egomotion import shift_u
from pedenv.tracking.table import TrackTable


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


class Tracker:
    """GIoU + Hungarian tracker over boxes in the image.

    Its state is ``table.tracks`` (see :class:`~pedenv.tracking.table.TrackColumns`); the
    properties ``ids``, ``boxes``, ``misses``, ``hits`` and ``velocities`` read it.
    """

    def __init__(self, config: TrackingConfig | None = None, ids: IdCounter | None = None,
                 table: TrackTable | None = None) -> None:
        self.config = config or TrackingConfig()
        self.id_counter = ids or IdCounter()
        self.table = table if table is not None else TrackTable()
        self.reset()

    def reset(self) -> None:
        """Forget every track (every column of the table) and restart the ids."""
        self.table.clear()
        self.id_counter.reset()

    def __len__(self) -> int:
        return len(self.table)

    ids = property(lambda self: self.table.tracks.ids)
    boxes = property(lambda self: self.table.tracks.boxes)
    misses = property(lambda self: self.table.tracks.misses)
    hits = property(lambda self: self.table.tracks.hits)
    velocities = property(lambda self: self.table.tracks.velocities)

    def update(self, boxes: np.ndarray, u_shift: float = 0.0) -> TrackerStep:
        """Associate one frame's detections with the tracks and move the table on.

        boxes: (N, 4) float, pixels of the current frame.
        u_shift: pixels to move the tracks' stored u coordinates by before association
            (the ego-yaw compensation of Eq. 1; 0 when it is off).
        """
        cfg, tr = self.config, self.table.tracks
        if u_shift and len(tr.ids):
            tr.boxes = shift_u(tr.boxes, u_shift)
        if cfg.predict_motion and len(tr.ids):
            tr.boxes = tr.boxes + tr.velocities  # constant velocity in the image (kept tracks too)
        matches, lost, fresh = associate(boxes, tr.boxes, cfg.giou_threshold, cfg.max_height_ratio)
        alive = tr.misses[lost] + 1 < cfg.max_misses
        kept = lost[alive]
        n_match, n_kept, n_new = len(matches), len(kept), len(fresh)
        dropped = tr.ids[lost[~alive]]
        previous_box = tr.boxes[matches[:, 1]] - tr.velocities[matches[:, 1]]  # the last frame's box

        previous_rows = np.concatenate([matches[:, 1], kept, np.full(n_new, -1, np.int64)])
        detection_rows = np.empty(len(boxes), np.int64)
        detection_rows[matches[:, 0]] = np.arange(n_match)
        detection_rows[fresh] = np.arange(n_match + n_kept, n_match + n_kept + n_new)
        self.table.carry(previous_rows)

        matched, new = slice(0, n_match), slice(n_match + n_kept, None)
        tr.ids[new] = self.id_counter.take(n_new)
        tr.boxes[matched], tr.boxes[new] = boxes[matches[:, 0]], boxes[fresh]
        tr.hits[matched] += 1
        tr.hits[new] = 1
        tr.misses[matched] = 0
        tr.misses[n_match:n_match + n_kept] += 1
        if cfg.predict_motion:
            moved = boxes[matches[:, 0]] - previous_box
            tr.velocities[matched] = MOTION_SMOOTHING * moved + (1.0 - MOTION_SMOOTHING) * tr.velocities[matched]
        return TrackerStep(detection_rows, previous_rows, dropped)
