"""Person boxes linked from image to image into tracks, so one person's images count as one person.

A greedy overlap linker (each box joins the track whose last box, moved on by the track's
box motion per image, it overlaps most, above :data:`MIN_IOU`, among the tracks seen in the
last :data:`MAX_GAP` images): the fit needs only
which images show the same person, not a tracker's motion model, and a static camera's people
move little from one frame to the next.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from pedenv.boxes import iou_matrix
from pedenv.calibration.observations import Observations, observations_of
from pedenv.records import Detections

#: Least intersection over union for a box to continue a track of the image before.
MIN_IOU = 0.3
#: A track missed in up to this many images in a row (a dropped detection, a person filtered
#: out as bending or cut off) is continued: a person split into many short tracks would count
#: as many people, and the fit's uncertainty, clustered per track, would come out too small.
MAX_GAP = 3
#: Share of a track's previous box motion kept when a new box continues it (the rest is the new
#: step): a walker's box moves steadily while its edges jitter with the gait and the detector.
VELOCITY_SMOOTHING = 0.5


class BoxLinker:
    """Track ids for each image's boxes, in order (ids from 0, never reused)."""

    def __init__(self) -> None:
        self.previous = np.zeros((0, 4))
        self.previous_ids = np.zeros(0, int)
        self.previous_age = np.zeros(0, int)  # images since each track's last box
        self.velocity = np.zeros((0, 4))  # each track's box motion per image, pixels
        self.next_id = 0

    def __call__(self, boxes: np.ndarray) -> np.ndarray:
        """boxes: (N, 4) pixels [u_min, v_min, u_max, v_max] -> (N,) int track ids."""
        boxes = np.asarray(boxes, float).reshape(-1, 4)
        ids, velocity = np.full(len(boxes), -1), np.zeros((len(boxes), 4))
        if len(boxes) and len(self.previous):
            steps = (self.previous_age + 1)[:, None]
            overlap = iou_matrix(boxes, self.previous + self.velocity * steps)  # each track's box moved on
            for flat in np.argsort(-overlap, axis=None):
                i, j = np.unravel_index(flat, overlap.shape)
                if overlap[i, j] < MIN_IOU:
                    break
                if ids[i] < 0 and self.previous_ids[j] not in ids:
                    ids[i] = self.previous_ids[j]
                    velocity[i] = VELOCITY_SMOOTHING * self.velocity[j] + (1.0 - VELOCITY_SMOOTHING) * (
                        boxes[i] - self.previous[j]) / steps[j]
        fresh = ids < 0
        ids[fresh] = self.next_id + np.arange(int(fresh.sum()))
        self.next_id += int(fresh.sum())
        kept = ~np.isin(self.previous_ids, ids) & (self.previous_age < MAX_GAP)
        self.previous = np.concatenate([boxes, self.previous[kept]])
        self.previous_ids = np.concatenate([ids, self.previous_ids[kept]])
        self.previous_age = np.concatenate([np.zeros(len(ids), int), self.previous_age[kept] + 1])
        self.velocity = np.concatenate([velocity, self.velocity[kept]])
        return ids


def linked_observations(detections: Iterable[Detections]) -> Observations:
    """The upright people of consecutive images' detections (image ``i`` the ``i``-th), their boxes
    linked into tracks by one :class:`BoxLinker`."""
    linker = BoxLinker()
    return Observations.concat([observations_of(det, index, linker(det.boxes))
                                for index, det in enumerate(detections)])
