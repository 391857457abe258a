"""The cascade for small people: low-scoring persons verified at a higher zoom, in packed crops.

A small, far person often scores below the network's threshold in a pass where they are
40-80 px tall. Such candidates (scores ``min_score`` up to the threshold, boxes of the
sizes the cascade is for, not a duplicate of a person already kept) are cropped, zoomed
about x3 and packed several to one network input (:mod:`pedenv.detection.packing`); a candidate
is kept only when the zoomed pass finds a whole, plausible skeleton at the same place, and
the zoomed detection (sharper keypoints) replaces it. Settings: :class:`CascadeConfig`.
"""

from __future__ import annotations

import numpy as np

from pedenv.boxes import containment_matrix, iou_matrix
from pedenv.detection.config import (
    CASCADE_MARGIN,
    CASCADE_MATCH_IOU,
    CASCADE_MAX_HEIGHT_PX,
    CASCADE_MAX_ZOOM,
    CASCADE_MIN_HEIGHT_PX,
    CASCADE_MIN_SCORE,
    CASCADE_PERSON_PX,
    CASCADE_PLAUSIBLE_KEYPOINT_CONF,
    CASCADE_VERIFY_SCORE,
    CascadeConfig,
)
from pedenv.detection.merge import merge_detections
from pedenv.detection.packing import Placement, crop_around, pack, run_packed
from pedenv.detection.tiling import Pass
from pedenv.pose.postprocess import DecodeSettings, InferMany
from pedenv.records import Detections

#: A candidate overlapping a kept person by more than this IoU, or lying this much inside one, is that person.
DUPLICATE_IOU = 0.3
DUPLICATE_CONTAINMENT = 0.6


def candidates(low: Detections, kept: Detections) -> Detections:
    """The persons of ``low`` (image px, scoring below the threshold) worth verifying, best first:
    box ``min_height_px``..``max_height_px`` tall, no duplicate of a person in ``kept`` (image px),
    duplicates among themselves merged."""
    if not len(low):
        return low
    heights = low.boxes[:, 3] - low.boxes[:, 1]
    low = low.take((heights >= CASCADE_MIN_HEIGHT_PX) & (heights <= CASCADE_MAX_HEIGHT_PX)
                   & (low.scores >= CASCADE_MIN_SCORE))
    if len(low) and len(kept):
        iou = iou_matrix(low.boxes, kept.boxes).max(axis=1)
        inside = containment_matrix(low.boxes, kept.boxes).max(axis=1)
        low = low.take((iou <= DUPLICATE_IOU) & (inside <= DUPLICATE_CONTAINMENT))
    if len(low) > 1:
        low = merge_detections([(low, np.zeros(len(low), bool))])
    return low.take(np.argsort(-low.scores, kind="stable"))


def accept(candidate_box: np.ndarray, found: Detections, cut: np.ndarray) -> np.ndarray:
    """Index array (0 or 1 entries) of the person of ``found`` (image px) that verifies the
    candidate ``candidate_box`` (4,) px: whole (not ``cut``), scoring at least ``verify_score``,
    plausible keypoints, overlapping the candidate by IoU >= ``match_iou``; the best overlap."""
    if not len(found):
        return np.zeros(0, np.int64)
    iou = iou_matrix(np.asarray(candidate_box, float)[None], found.boxes)[0]
    ok = (~cut) & (found.scores >= CASCADE_VERIFY_SCORE) & (iou >= CASCADE_MATCH_IOU)
    ok &= found.confidences.mean(axis=1) >= CASCADE_PLAUSIBLE_KEYPOINT_CONF
    return np.flatnonzero(ok)[np.argsort(-iou[ok])[:1]]


def candidate_placements(cands: Detections, image_size: tuple[int, int], packed_size: tuple[int, int]) -> list:
    """One crop per candidate (image px boxes ``cands.boxes``), zoomed to ``person_px``."""
    return [crop_around(b, image_size, CASCADE_PERSON_PX, CASCADE_MARGIN, CASCADE_MAX_ZOOM, packed_size)
            for b in cands.boxes]


def verify(infer: InferMany, image: np.ndarray, cands: Detections, config: CascadeConfig,
           packed_size: tuple[int, int], settings: DecodeSettings) -> tuple[Detections, list[Pass]]:
    """The candidates (image px) that the zoomed pass confirms, as found there (image px), and the
    passes run (at most ``config.max_units`` packed inputs over ``image`` (H, W, 3) uint8 RGB)."""
    if not len(cands):
        return Detections.empty(), []
    image_size = (image.shape[0], image.shape[1])
    crops = candidate_placements(cands, image_size, packed_size)
    placements = pack(crops, packed_size, max_inputs=config.max_units)
    rows = [p.item for p in placements]
    results, passes = run_packed(infer, image, placements, packed_size, settings)
    return confirmed(cands, rows, placements, results), passes


def confirmed(cands: Detections, rows: list[int], placements: list[Placement],
              results: list[tuple[Detections, np.ndarray]]) -> Detections:
    """The zoomed persons confirming candidates ``cands.take(rows)``, one per placement at most."""
    kept = []
    for row, _, (found, cut) in zip(rows, placements, results):
        kept.append(found.take(accept(cands.boxes[row], found, cut)))
    return Detections.concat(kept)
