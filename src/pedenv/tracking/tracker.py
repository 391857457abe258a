"""The thin image-plane tracker (paper Sec. III-B).

Each frame it associates the detections with the tracks of the :class:`TrackTable`,
decides the next table (matched, kept and new tracks) and carries every per-track
column there at once (:meth:`TrackTable.carry`), the Kalman filter's and the position
method's included.

Beyond the paper, each switched on by a :class:`~pedenv.config.TrackingConfig` value (the
``fused`` preset turns them on; :mod:`pedenv.tracking.recall`): a second association
stage for low-score detections (ByteTrack), a gate and cost from each track's Kalman
prediction projected into the image, and a memory of lost tracks that gives a person
their old id back after an occlusion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.config import TrackingConfig
from pedenv.tracking.association import associate
from pedenv.tracking.prediction import box_displacement, predict_boxes
from pedenv.tracking.projection import CameraView
from pedenv.tracking.recall import camera_disagrees, ground_terms, recall_remembered, split_by_score
from pedenv.tracking.table import TrackTable

#: Weight of the newest displacement in a track's image velocity (exponential smoothing).
MOTION_SMOOTHING = 0.5
#: What a low-band detection (``tracking.low_score_threshold``) adds to the association cost
#: (GIoU lies in [-1, 1]): a sure detection wins a track over a weak one that overlaps it up to
#: 0.5 GIoU better; a weak one still takes a track no sure detection overlaps. Set with the
#: two-band association on KITTI 0016 (frame 7), not tuned further.
LOW_SCORE_COST = 0.5


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

    detection_rows: (N,) row of each detection in the new track table; -1 for a low-score
        detection that continued no track (it is left out of the frame's pedestrians).
    previous_rows: (T,) for each row of the new table, its row in the previous table,
        or -1 for a track started in this frame.
    dropped_ids: ids of the tracks removed in this frame (not those only lost and
        remembered: they are dropped when their memory runs out).
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
        #: whether the last frame's ground gate agreed with the image (:func:`camera_disagrees`)
        self.camera_trusted = True

    def __len__(self) -> int:
        return len(self.table)

    ids = property(lambda self: self.table.tracks.ids)
    boxes = property(lambda self: self.table.tracks.boxes)
    misses = property(lambda self: self.table.tracks.misses)
    hits = property(lambda self: self.table.tracks.hits)
    velocities = property(lambda self: self.table.tracks.velocities)

    def update(self, boxes: np.ndarray, u_shift: float = 0.0, scores: np.ndarray | None = None,
               view: CameraView | None = None) -> TrackerStep:
        """Associate one frame's detections with the tracks and move the table on.

        boxes: (N, 4) float, pixels of the current frame.
        u_shift: pixels to move the tracks' stored u coordinates by before association
            (the ego-yaw compensation of Eq. 1; 0 when it is off).
        scores: (N,) person scores in [0, 1]; needed by the two-stage association
            (``tracking.low_score_threshold`` > 0), else unused.
        view: the frame's camera and road; needed by the ground gate and the memory
            (``tracking.ground_gate``, ``tracking.memory_s``), which are off without it.
            The table's Kalman columns must hold the prediction at this frame's time.
        """
        cfg, tr = self.config, self.table.tracks
        boxes = np.asarray(boxes, np.float64).reshape(-1, 4)
        if len(tr.ids):  # where the tracks are expected now (kept tracks too): the detector's prediction
            tr.boxes = predict_boxes(tr.boxes, tr.velocities, u_shift, cfg.predict_motion)
        memory = view is not None and cfg.memory_s > 0
        if cfg.low_score_threshold <= 0 and (view is None or cfg.ground_gate <= 0) and not memory:
            # the paper's association, without the steps beyond it (the hot path of `paper`)
            m, free, fresh = associate(boxes, tr.boxes, cfg.giou_threshold, cfg.max_height_ratio)
            pairs, remembered = [m], np.zeros(0, np.int64)
        else:
            pairs, free, fresh, remembered = self._associate_beyond(boxes, scores, view)
        if view is not None and memory and self.camera_trusted and len(fresh) and len(remembered) + len(free):
            # the remembered tracks and the live ones the image left without a detection
            candidates = np.concatenate([free, remembered])
            m = recall_remembered(view, boxes[fresh], self.table.filter, candidates)
            pairs.append(np.column_stack([fresh[m[:, 0]], candidates[m[:, 1]]]))
            fresh = np.delete(fresh, m[:, 0])
            free = free[~np.isin(free, candidates[m[:, 1]])]
        matches = np.concatenate(pairs).astype(np.int64)
        kept, dropped = self._without_detection(free, remembered, matches, view if memory else None)
        n_match, n_kept, n_new = len(matches), len(kept), len(fresh)
        motion = None
        if cfg.predict_motion:  # the matched tracks' displacement since the last frame's box (none after a loss)
            previous_box = tr.boxes[matches[:, 1]] - box_displacement(tr.velocities[matches[:, 1]])
            motion = np.where(tr.lost[matches[:, 1]][:, None], 0.0, boxes[matches[:, 0]] - previous_box)

        previous_rows = np.concatenate([matches[:, 1], kept, np.full(n_new, -1, np.int64)])
        detection_rows = np.full(len(boxes), -1, np.int64)
        detection_rows[matches[:, 0]] = np.arange(n_match)
        detection_rows[fresh] = np.arange(n_match + n_kept, n_match + n_kept + n_new)
        self.table.carry(previous_rows)
        self._write_rows(boxes[matches[:, 0]], boxes[fresh], n_kept, motion, view)
        return TrackerStep(detection_rows, previous_rows, dropped)

    def _without_detection(self, missed: np.ndarray, remembered: np.ndarray, matches: np.ndarray,
                           view: CameraView | None) -> tuple[np.ndarray, np.ndarray]:
        """The rows kept without a detection and the ids dropped.

        missed: live rows without a detection; remembered: lost rows; matches: (M, 2)
        (detection, row). A live track is kept while under ``max_misses``; with the memory
        (``view`` given) a track past it, and a lost one not matched, is remembered for
        ``memory_s`` seconds since it was last seen. Returns ``(kept rows, dropped ids)``.
        """
        cfg, tr = self.config, self.table.tracks
        alive = tr.misses[missed] + 1 < cfg.max_misses
        if view is None:
            return missed[alive], tr.ids[missed[~alive]]
        keep_lost = np.zeros(len(tr.ids), bool)
        keep_lost[missed[~alive]] = True
        still = remembered[~np.isin(remembered, matches[:, 1])]
        keep_lost[still[view.timestamp - tr.last_seen[still] <= cfg.memory_s]] = True
        gone = np.setdiff1d(np.arange(len(tr.ids)), np.concatenate([matches[:, 1], missed[alive]]))
        return np.concatenate([missed[alive], np.flatnonzero(keep_lost)]), tr.ids[gone[~keep_lost[gone]]]

    def _write_rows(self, matched_boxes: np.ndarray, new_boxes: np.ndarray, n_kept: int, motion: np.ndarray | None,
                    view: CameraView | None) -> None:
        """Fill the carried table's rows: matched (their ``matched_boxes`` (M, 4)), kept
        (``n_kept``, one more miss) and new (``new_boxes`` (F, 4), fresh ids). motion: (M, 4)
        pixels, the matched tracks' displacement (``predict_motion``); view: for the time seen."""
        cfg, tr = self.config, self.table.tracks
        n_match, n_new = len(matched_boxes), len(new_boxes)
        matched, kept, new = slice(0, n_match), slice(n_match, n_match + n_kept), slice(n_match + n_kept, None)
        tr.ids[new] = self.id_counter.take(n_new)
        tr.boxes[matched], tr.boxes[new] = matched_boxes, new_boxes
        tr.hits[matched] += 1
        tr.hits[new] = 1
        tr.misses[matched] = 0
        tr.misses[kept] += 1
        tr.lost[matched] = False
        tr.lost[kept] = tr.misses[kept] >= cfg.max_misses
        if view is not None:
            tr.last_seen[matched] = tr.last_seen[new] = view.timestamp
        if motion is not None:
            tr.velocities[matched] = MOTION_SMOOTHING * motion + (1.0 - MOTION_SMOOTHING) * tr.velocities[matched]

    def _associate_beyond(self, boxes: np.ndarray, scores: np.ndarray | None,
                          view: CameraView | None) -> tuple[list[np.ndarray], np.ndarray, np.ndarray, np.ndarray]:
        """The association of the fused preset: the low-score band in one assignment at its
        cost, the ground gate, lost rows left out. Returns ``(pairs, free live tracks, fresh
        detections, lost rows)``; a weak detection is never fresh."""
        cfg, tr = self.config, self.table.tracks
        first, second = split_by_score(scores, len(boxes), cfg)
        stage = np.concatenate([first, second])  # one assignment; the low band pays its cost
        live = np.flatnonzero(~tr.lost)
        allowed, extra = ground_terms(boxes, self.table.filter, view, cfg)
        self.camera_trusted = allowed is None or not camera_disagrees(allowed[first], boxes[first], tr.boxes, live)
        if not self.camera_trusted:  # a wrong calibration: the gate abstains, the boxes decide
            allowed, extra = None, None
        sub = np.ix_(stage, live)
        extra = None if extra is None else extra[sub]
        if len(second):
            band = np.repeat([0.0, LOW_SCORE_COST], [len(first), len(second)])[:, None]
            extra = np.broadcast_to((0.0 if extra is None else extra) + band, (len(stage), len(live)))
        m, free_rows, unmatched = associate(boxes[stage], tr.boxes[live], cfg.giou_threshold, cfg.max_height_ratio,
                                            None if allowed is None else allowed[sub], extra)
        pairs = [np.column_stack([stage[m[:, 0]], live[m[:, 1]]])]
        return pairs, live[free_rows], stage[unmatched[unmatched < len(first)]], np.flatnonzero(tr.lost)
