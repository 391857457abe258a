"""The track search: which predicted tracks to look for in a crop, and which person found there is
the track. One search, used by the re-detection of ``far``/``fast`` (:mod:`pedenv.detection.redetect`)
and by ``stream`` (:class:`TrackFinder`, which also remembers where each track was last detected);
both match with the run's ``redetect.match_distance`` and ``redetect.match_height_ratio``.
"""

from __future__ import annotations

import numpy as np

from pedenv.boxes import iou_matrix
from pedenv.detection.config import MATCH_HEIGHT_RATIO, PLAUSIBLE_KEYPOINT_CONF, SURE_SCORE, RedetectConfig
from pedenv.records import Detections

#: A predicted box shorter than this (pixels, after clipping to the image) is not searched: a person
#: that small is below what the network finds even zoomed (geometry: 8 px is a quarter of its stride).
MIN_BOX_HEIGHT_PX = 8.0
#: A predicted box with less than this share of its area inside the image is not searched (leaving it).
MIN_VISIBLE_SHARE = 0.5
#: A remembered box overlapping another track's predicted box by this IoU (and not its own) is that track's.
SAME_BOX_IOU = 0.95


def searchable(predicted: np.ndarray, hits: np.ndarray, found: np.ndarray, image_size: tuple[int, int], *,
               min_hits: int, min_height_px: float, missed_iou: float) -> np.ndarray:
    """(T,) bool: the tracks worth searching for in a crop (here and in the ``stream`` mode).

    predicted: (T, 4) px, the tracks' expected boxes; hits: (T,) detections so far; found: (N, 4)
    px, the boxes detected in the frame; image_size: (height, width) px. A track is searchable
    when at least :data:`MIN_VISIBLE_SHARE` of its box lies inside the image and at least
    ``min_height_px`` of its height, it has at least ``min_hits`` hits, and no found box overlaps
    it by more than ``missed_iou``.
    """
    h, w = image_size
    clipped = np.clip(predicted, 0.0, [w, h, w, h])
    area = np.prod(np.clip(predicted[:, 2:] - predicted[:, :2], 1e-9, None), axis=1)
    inside = np.prod(np.clip(clipped[:, 2:] - clipped[:, :2], 0.0, None), axis=1)
    usable = (inside / area >= MIN_VISIBLE_SHARE) & (clipped[:, 3] - clipped[:, 1] >= min_height_px)
    usable &= np.asarray(hits) >= min_hits
    if len(found):
        usable &= iou_matrix(predicted, np.asarray(found, float).reshape(-1, 4)).max(axis=1) <= missed_iou
    return usable


def nearest_person(box: np.ndarray, boxes: np.ndarray, whole: np.ndarray, config: RedetectConfig) -> np.ndarray:
    """Index array (0 or 1 entries) of the box of ``boxes`` (M, 4) px nearest the predicted
    ``box`` (4,) px: among the ``whole`` (M,) ones, centre within ``match_distance`` predicted
    heights and height within ``match_height_ratio`` of the predicted one."""
    height = max(float(box[3] - box[1]), 1.0)
    heights = np.maximum(boxes[:, 3] - boxes[:, 1], 1e-9)
    distance = np.linalg.norm(0.5 * (boxes[:, :2] + boxes[:, 2:] - box[:2] - box[2:]), axis=1) / height
    ratio = np.maximum(heights / height, height / heights)
    ok = whole & (distance <= config.match_distance) & (ratio <= MATCH_HEIGHT_RATIO)
    return np.flatnonzero(ok)[np.argsort(distance[ok])[:1]]


def nearest_track(box: np.ndarray, predicted: np.ndarray) -> int:
    """Row of the predicted box (T, 4) px whose centre lies nearest the centre of ``box`` (4,) px,
    in heights of each predicted box."""
    heights = np.maximum(predicted[:, 3] - predicted[:, 1], 1.0)
    distance = np.linalg.norm(0.5 * (predicted[:, :2] + predicted[:, 2:] - box[:2] - box[2:]), axis=1) / heights
    return int(np.argmin(distance))


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
    (within :class:`~pedenv.detection.config.RedetectConfig`'s ``match_distance`` and
    ``match_height_ratio``) and nearer the search box than any other track's.
    """

    def __init__(self, match: RedetectConfig) -> None:
        self.match = match
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
            # sure, or a plausible skeleton: a person, not a pole (the far levels' own check)
            sure = (found.scores >= SURE_SCORE) | (found.confidences.mean(axis=1) >= PLAUSIBLE_KEYPOINT_CONF)
            pick = found.take(nearest_person(searched[row], found.boxes, ~cut & sure, self.match))
            if not len(pick):
                pick = found.take(nearest_person(last[row], found.boxes, ~cut & sure, self.match))
            if len(pick) and nearest_track(pick.boxes[0], searched) == row:
                kept.append(pick)
        return Detections.concat(kept)


