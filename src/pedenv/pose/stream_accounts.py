"""What the ``stream`` detection remembers of tracks, and how it spent its budget (for ``run.json``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pedenv.boxes import iou_matrix
from pedenv.pose.cascade import concat
from pedenv.pose.redetect import nearest_person, nearest_track
from pedenv.pose.redetect_config import RedetectConfig
from pedenv.pose.schedule import FramePlan, units
from pedenv.records import Detections

#: A person found in a track's crop scoring below this needs a plausible skeleton (mean keypoint
#: confidence at least PLAUSIBLE_KEYPOINT_CONF): a person, not a pole.
SURE_SCORE = 0.5
PLAUSIBLE_KEYPOINT_CONF = 0.5
#: A remembered box overlapping another track's predicted box by this IoU (and not its own) is that track's.
SAME_BOX_IOU = 0.95


class TrackFinder:
    """When each track was last detected, where, and which person in its crop is the track.

    A track is searched around its **search box**: the box it was last detected with, moved by
    the prediction's centre shift since (the predicted box's size follows the tracker's edge
    velocities, which a detector's jitter distorts; the detected size does not); its crop covers
    the last detection too (the crop's ``also``). A shift over ``max_shift`` of its height, or a
    remembered box that is another track's predicted box (IoU >= :data:`SAME_BOX_IOU`) and not
    near its own, means the box is not that track's (stand-in tracks whose ids change between
    frames, a wrong association):
    the predicted box is searched as it is. A person found in a track's crop
    re-detects it when whole, sure or plausible, nearest the search box or the last detection
    (within :class:`~pedenv.pose.redetect_config.RedetectConfig`'s ``match_distance`` and
    ``match_height_ratio``) and nearer the search box than any other track's.
    """

    def __init__(self, match: RedetectConfig | None = None) -> None:
        self.match = match or RedetectConfig()
        self._seen: dict[int, float] = {}
        self._last: dict[int, np.ndarray] = {}

    def unseen_s(self, ids: np.ndarray, timestamp: float) -> np.ndarray:
        """(T,) seconds since each track of ``ids`` was last detected (0 for a new one, and for a
        person no track holds, id < 0)."""
        return np.array([timestamp - self._seen.setdefault(int(i), timestamp) if i >= 0 else 0.0 for i in ids], float)

    def search_boxes(self, ids: np.ndarray, predicted: np.ndarray, max_shift: float) -> tuple[np.ndarray, np.ndarray]:
        """``(search boxes, last detections)``, both (T, 4) px, for the tracks ``ids`` (T,) with
        their ``predicted`` boxes (T, 4) px; a track never detected here or id < 0 (a person no
        track holds): its predicted box for both.
        max_shift: the most centre shift from the last detection, in its heights, for it to count."""
        predicted = np.asarray(predicted, float).reshape(-1, 4)
        last = np.array([self._last.get(int(i), p) for i, p in zip(ids, predicted)], float).reshape(-1, 4)
        shift = 0.5 * (predicted[:, :2] + predicted[:, 2:] - last[:, :2] - last[:, 2:])
        heights = np.maximum(last[:, 3] - last[:, 1], 1.0)
        other = np.linalg.norm(shift, axis=1) > max_shift * heights
        if len(predicted):  # or it is another track's predicted box, apart from its own
            overlap = iou_matrix(last, predicted)
            other |= (np.diag(overlap) <= 0.0) & (overlap.max(axis=1) >= SAME_BOX_IOU)
        last[other] = predicted[other]
        shift[other] = 0.0
        return last + np.tile(shift, 2), last

    def update(self, ids: np.ndarray, searched: np.ndarray, boxes: np.ndarray, timestamp: float,
               iou: float) -> None:
        """Tracks whose search box (T, 4) px some detected box (N, 4) px overlaps by more than
        ``iou`` were seen, at the best-overlapping box."""
        self._last = {k: v for k, v in self._last.items() if k in set(np.asarray(ids).tolist())}
        if not len(ids) or not len(boxes):
            return
        overlap = iou_matrix(np.asarray(searched, float), np.asarray(boxes, float))
        for row in np.flatnonzero((overlap.max(axis=1) > iou) & (np.asarray(ids) >= 0)):
            self._seen[int(ids[row])] = timestamp
            self._last[int(ids[row])] = np.asarray(boxes[int(np.argmax(overlap[row]))], float).copy()

    def pick(self, searched: np.ndarray, last: np.ndarray, rows: list[int],
             results: list[tuple[Detections, np.ndarray]]) -> Detections:
        """Per searched track (``rows`` of the search boxes ``searched`` and last detections
        ``last``, (T, 4) px) the person of its crop's ``results`` (image px, cut flags) that is that track, if any."""
        kept = []
        for row, (found, cut) in zip(rows, results):
            if not len(found):
                continue
            sure = (found.scores >= SURE_SCORE) | (found.confidences.mean(axis=1) >= PLAUSIBLE_KEYPOINT_CONF)
            pick = found.take(nearest_person(searched[row], found.boxes, ~cut & sure, self.match))
            if not len(pick):
                pick = found.take(nearest_person(last[row], found.boxes, ~cut & sure, self.match))
            if len(pick) and nearest_track(pick.boxes[0], searched) == row:
                kept.append(pick)
        return concat(kept)


@dataclass
class StreamAccounts:
    """Counts over the frames a :class:`~pedenv.pose.stream.StreamPose` saw; units are 384x640 inputs."""

    frames: int = 0
    restarts: int = 0
    cold_starts: int = 0
    units: dict[str, float] = field(default_factory=lambda: {"whole_frame": 0.0, "band_tiles": 0.0, "packed": 0.0})
    warm_units: float = 0.0
    max_units: float = 0.0
    max_units_warm: float = 0.0
    frames_over_budget: int = 0
    frames_on_credit: int = 0
    credit_units: float = 0.0
    tracks_at_risk: int = 0
    tracks_found: int = 0
    cascade_confirmed: int = 0
    tile_visits: int = 0
    tiles_late: int = 0
    band_reserve_units: float = 0.0

    def add(self, ran: tuple, plan: FramePlan, cold: bool, counts: tuple[int, int, int], late: int) -> None:
        """One frame: ``ran`` (its whole-frame pass, band tiles, packed inputs), its plan, whether a
        cold start, ``counts`` (tracks searched, found in crops, cascade confirmations) and the
        tiles it left older than the scan period."""
        first, steps, passes = ran
        at_risk, found, verified = counts
        spent = [units(first.input_size), sum(units(s.input_size) for s in steps),
                 sum(units(p.input_size) for p in passes)]
        for key, value in zip(self.units, spent):
            self.units[key] += value
        total = sum(spent)
        self.frames += 1
        self.cold_starts += int(cold)
        self.max_units = max(self.max_units, total)
        if not cold:
            self.warm_units += total
            self.max_units_warm = max(self.max_units_warm, total)
        self.frames_over_budget += int(plan.over_budget and not cold)
        self.frames_on_credit += int(not cold and not plan.over_budget and total > plan.budget + 1e-9)
        self.tracks_at_risk += at_risk
        self.tracks_found += found
        self.cascade_confirmed += verified
        self.tile_visits += len(steps)
        self.tiles_late += late
        self.band_reserve_units = plan.reserve_units

    def to_dict(self) -> dict:
        n = max(self.frames, 1)
        return {"frames": self.frames, "restarts": self.restarts, "cold_starts": self.cold_starts,
                "units_per_frame": sum(self.units.values()) / n,
                "units_per_frame_by_use": {k: v / n for k, v in self.units.items()},
                "units_per_frame_after_cold_starts": self.warm_units / max(self.frames - self.cold_starts, 1),
                "max_units_per_frame": self.max_units, "max_units_per_frame_after_cold_start": self.max_units_warm,
                "frames_past_budget_for_a_due_tile": self.frames_over_budget,
                "frames_past_budget_on_credit": self.frames_on_credit, "credit_units_left": self.credit_units,
                "band_units_per_frame_needed": self.band_reserve_units,
                "tracks_at_risk_searched": self.tracks_at_risk, "tracks_found_in_crops": self.tracks_found,
                "cascade_confirmed": self.cascade_confirmed, "tile_visits": self.tile_visits,
                "tiles_older_than_scan_period": self.tiles_late}
