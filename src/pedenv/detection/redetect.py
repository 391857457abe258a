"""Re-detection of missed tracks in high-resolution crops (``far`` and ``fast``, beyond the paper).

Given the tracks the model predicts for this frame (:class:`~pedenv.records.PredictedTracks`, handed
in by the pipeline), after the main detection: the tracks whose predicted box no detection overlaps
(:func:`missed_tracks`) are searched once each, the pose network on an upscaled crop around the
predicted box (:func:`crop_pass`); the one whole person there nearest the predicted box (and nearer
it than any other track's, :mod:`pedenv.detection.track_search`) is merged with the main detections
by the skeleton-aware NMS (:func:`pedenv.detection.merge.merge_detections`), so no person appears
twice. Settings: :class:`pedenv.detection.config.RedetectConfig` (the ``fused`` preset turns it on).
``stream`` searches its tracks itself, in packed inputs (:mod:`pedenv.detection.stream`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pedenv.detection.config import (
    REDETECT_CROP_MARGIN,
    REDETECT_CROP_SCALE,
    REDETECT_MAX_CROP_PX,
    REDETECT_MAX_INPUT_PX,
    REDETECT_MIN_CROP_PX,
    REDETECT_MIN_HITS,
    REDETECT_MISSED_IOU,
    STRIDE,
    RedetectConfig,
)
from pedenv.detection.merge import merge_detections
from pedenv.detection.packing import cut_by_inner_edge
from pedenv.detection.passes import run_passes
from pedenv.detection.tiling import Pass
from pedenv.detection.track_search import MIN_BOX_HEIGHT_PX, nearest_person, nearest_track, searchable
from pedenv.pose.onnx_backend import OnnxPose
from pedenv.pose.postprocess import DecodeSettings
from pedenv.records import Detections, PredictedTracks


def missed_tracks(predicted: np.ndarray, hits: np.ndarray, detections: np.ndarray, image_size: tuple[int, int],
                  config: RedetectConfig) -> np.ndarray:
    """Rows of the tracks to search for, most-seen first, at most ``config.max_crops``.

    predicted: (T, 4) px, the tracks' expected boxes; hits: (T,) detections so far;
    detections: (N, 4) px, the main pass's boxes; image_size: (height, width) px.
    A track is missed when no detection overlaps its predicted box by more than
    ``missed_iou``; tracks with fewer than ``min_hits`` hits, or whose box lies mostly
    outside the image or is tiny there, are not searched.
    """
    predicted = np.asarray(predicted, float).reshape(-1, 4)
    if not len(predicted) or config.max_crops == 0:
        return np.zeros(0, np.int64)
    usable = searchable(predicted, hits, detections, image_size, min_hits=REDETECT_MIN_HITS,
                        min_height_px=MIN_BOX_HEIGHT_PX, missed_iou=REDETECT_MISSED_IOU)
    rows = np.flatnonzero(usable)
    rows = rows[np.argsort(-np.asarray(hits)[rows], kind="stable")]
    return rows[: config.max_crops]


def crop_pass(box: np.ndarray, image_size: tuple[int, int]) -> Pass:
    """The network pass around one predicted ``box`` (4,) px in an image of ``image_size``
    (height, width): the box with :data:`~pedenv.detection.config.REDETECT_CROP_MARGIN` times its
    height on every side, each side clamped to ``[REDETECT_MIN_CROP_PX, REDETECT_MAX_CROP_PX]`` and
    to the image, moved inside the image; scaled by ``REDETECT_CROP_SCALE`` (lowered to fit
    ``REDETECT_MAX_INPUT_PX``) into a multiple-of-32 input."""
    h, w = image_size
    box = np.asarray(box, float)
    height = box[3] - box[1]
    sides = []
    for centre, extent, limit in ((0.5 * (box[0] + box[2]), box[2] - box[0], w),
                                  (0.5 * (box[1] + box[3]), height, h)):
        side = min(max(extent + 2.0 * REDETECT_CROP_MARGIN * height, REDETECT_MIN_CROP_PX), REDETECT_MAX_CROP_PX, limit)
        start = int(round(min(max(centre - 0.5 * side, 0.0), limit - side)))
        sides.append((start, start + int(round(side))))
    (x0, x1), (y0, y1) = sides
    scale = min(REDETECT_CROP_SCALE, REDETECT_MAX_INPUT_PX / max(x1 - x0, y1 - y0))
    size = tuple(max(STRIDE, int(math.ceil(n * scale / STRIDE - 1e-9)) * STRIDE) for n in (y1 - y0, x1 - x0))
    return Pass((x0, y0, x1, y1), (min(size[0], REDETECT_MAX_INPUT_PX), min(size[1], REDETECT_MAX_INPUT_PX)), "crop")


@dataclass
class Redetection:
    """The re-detection of one detector: its settings and counts (``frames`` seen, ``crops`` run,
    persons ``redetected``), saved in ``run.json``."""

    config: RedetectConfig
    frames: int = 0
    crops: int = 0
    redetected: int = 0

    def __call__(self, network: OnnxPose, image: np.ndarray, image_size: tuple[int, int], detections: Detections,
                 tracks: PredictedTracks, decoding: DecodeSettings) -> Detections:
        """``detections`` (the main pass on ``image`` (H, W, 3) uint8 RGB of a frame of
        ``image_size`` (height, width)) with the missed ``tracks``' re-detections merged in."""
        self.frames += 1
        predicted, hits = tracks.boxes, tracks.hits
        rows = missed_tracks(predicted, hits, detections.boxes, image_size, self.config)
        if not len(rows):
            return detections
        found = self._search(network, image, predicted[rows], decoding)
        # a person nearer another track's predicted box is that track's business (or a neighbour)
        found = [d for d, r in zip(found, rows) if len(d) and nearest_track(d.boxes[0], predicted) == r]
        self.crops += len(rows)
        if not found:
            return detections
        extra = Detections.concat(found)
        merged = merge_detections([(detections, np.zeros(len(detections), bool)),
                                   (extra, np.zeros(len(extra), bool))], max_detections=decoding.max_detections)
        self.redetected += len(merged) - len(detections)
        return merged

    def _search(self, network: OnnxPose, image: np.ndarray, boxes: np.ndarray,
                decoding: DecodeSettings) -> list[Detections]:
        """Per box of ``boxes`` (K, 4) px, the one whole person in the crop around it nearest to it,
        or none; the crops are independent passes (one network call: side by side on the CPU)."""
        image_size = (image.shape[0], image.shape[1])
        steps = [crop_pass(box, image_size) for box in boxes]
        sizes = [step.input_size if network.dynamic else network.input_size for step in steps]
        found = run_passes(network.infer_many, image, steps, sizes, decoding.score_threshold, decoding.iou_threshold,
                           decoding.max_detections)
        out = []
        for box, step, size, dets in zip(boxes, steps, sizes, found):
            if len(dets):
                scale = min(size[0] / (step.region[3] - step.region[1]), size[1] / (step.region[2] - step.region[0]))
                whole = ~cut_by_inner_edge(dets.boxes, step.region, image_size, decoding.edge_margin_px / scale)
                dets = dets.take(nearest_person(box, dets.boxes, whole, self.config))
            out.append(dets)
        return out

    def to_dict(self) -> dict:
        """The settings and the counts."""
        return {**{k: getattr(self.config, k) for k in self.config.__dataclass_fields__},
                "frames": self.frames, "crops": self.crops, "redetected": self.redetected}
