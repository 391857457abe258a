"""Re-detection of missed tracks in high-resolution crops (beyond the paper).

The apps run ``frame = replace(frame, detections=backend(frame)); state = model.update(frame)``.
:func:`with_redetection` wraps the backend: after the main detection it asks the model
where its live tracks are expected (:meth:`~pedenv.model.PedestrianEnvironmentModel.predicted_boxes`),
takes the tracks whose predicted box no detection overlaps (:func:`missed_tracks`), runs
the pose network once per such track on an upscaled crop around the predicted box
(:func:`crop_pass`), keeps the one whole person there nearest the predicted box (and nearer
it than any other track's), and merges them with the main detections by the skeleton-aware
NMS (:func:`pedenv.pose.merge.merge_detections`), so no person appears twice.
Settings: :class:`pedenv.pose.redetect_config.RedetectConfig` (the ``fused`` preset turns it on).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Protocol, cast

import numpy as np

from pedenv.boxes import iou_matrix
from pedenv.pose.merge import merge_detections
from pedenv.pose.multipass import cut_by_inner_edge, run_passes
from pedenv.pose.postprocess import frame_image
from pedenv.pose.redetect_config import RedetectConfig
from pedenv.pose.tiling import STRIDE, Pass
from pedenv.records import Detections, Frame

if TYPE_CHECKING:
    from pedenv.pose.base import PoseBackend
    from pedenv.pose.onnx_backend import OnnxPose

#: A predicted box shorter than this (pixels, after clipping to the image) is not searched.
MIN_BOX_HEIGHT_PX = 8.0
#: A predicted box with less than this share of its area inside the image is not searched.
MIN_VISIBLE_SHARE = 0.5


class TrackPredictor(Protocol):
    """What the re-detection needs of the model: its live tracks' boxes expected in a frame."""

    def predicted_boxes(self, frame: Frame) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


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
    usable = searchable(predicted, hits, detections, image_size, min_hits=config.min_hits,
                        min_height_px=MIN_BOX_HEIGHT_PX, missed_iou=config.missed_iou)
    rows = np.flatnonzero(usable)
    rows = rows[np.argsort(-np.asarray(hits)[rows], kind="stable")]
    return rows[: config.max_crops]


def nearest_person(box: np.ndarray, boxes: np.ndarray, whole: np.ndarray, config: RedetectConfig) -> np.ndarray:
    """Index array (0 or 1 entries) of the box of ``boxes`` (M, 4) px nearest the predicted
    ``box`` (4,) px: among the ``whole`` (M,) ones, centre within ``match_distance`` predicted
    heights and height within ``match_height_ratio`` of the predicted one."""
    height = max(float(box[3] - box[1]), 1.0)
    heights = np.maximum(boxes[:, 3] - boxes[:, 1], 1e-9)
    distance = np.linalg.norm(0.5 * (boxes[:, :2] + boxes[:, 2:] - box[:2] - box[2:]), axis=1) / height
    ratio = np.maximum(heights / height, height / heights)
    ok = whole & (distance <= config.match_distance) & (ratio <= config.match_height_ratio)
    return np.flatnonzero(ok)[np.argsort(distance[ok])[:1]]


def nearest_track(box: np.ndarray, predicted: np.ndarray) -> int:
    """Row of the predicted box (T, 4) px whose centre lies nearest the centre of ``box`` (4,) px,
    in heights of each predicted box."""
    heights = np.maximum(predicted[:, 3] - predicted[:, 1], 1.0)
    distance = np.linalg.norm(0.5 * (predicted[:, :2] + predicted[:, 2:] - box[:2] - box[2:]), axis=1) / heights
    return int(np.argmin(distance))


def crop_pass(box: np.ndarray, image_size: tuple[int, int], config: RedetectConfig) -> Pass:
    """The network pass around one predicted ``box`` (4,) px in an image of ``image_size``
    (height, width): the box with ``crop_margin`` times its height on every side, each side
    clamped to ``[min_crop_px, max_crop_px]`` and to the image, moved inside the image;
    scaled by ``crop_scale`` (lowered to fit ``max_input_px``) into a multiple-of-32 input."""
    h, w = image_size
    box = np.asarray(box, float)
    height = box[3] - box[1]
    sides = []
    for centre, extent, limit in ((0.5 * (box[0] + box[2]), box[2] - box[0], w),
                                  (0.5 * (box[1] + box[3]), height, h)):
        side = min(max(extent + 2.0 * config.crop_margin * height, config.min_crop_px), config.max_crop_px, limit)
        start = int(round(min(max(centre - 0.5 * side, 0.0), limit - side)))
        sides.append((start, start + int(round(side))))
    (x0, x1), (y0, y1) = sides
    scale = min(config.crop_scale, config.max_input_px / max(x1 - x0, y1 - y0))
    size = tuple(max(STRIDE, int(math.ceil(n * scale / STRIDE - 1e-9)) * STRIDE) for n in (y1 - y0, x1 - x0))
    return Pass((x0, y0, x1, y1), (min(size[0], config.max_input_px), min(size[1], config.max_input_px)), "crop")


class RedetectingPose:
    """A pose backend that re-detects the model's missed tracks after the main detection.

    backend: an :class:`~pedenv.pose.onnx_backend.OnnxPose` (its network runs the crops, at
        its score, NMS and edge-margin settings). model: anything with ``predicted_boxes``
        (the :class:`~pedenv.model.PedestrianEnvironmentModel` the frames go to next).
    ``crops`` and ``frames`` count the extra network passes and the frames seen.
    """

    def __init__(self, backend: OnnxPose, model: TrackPredictor, config: RedetectConfig) -> None:
        self.backend, self.model, self.config = backend, model, config
        self.name = backend.name
        self.crops = 0
        self.frames = 0
        self.redetected = 0

    def __call__(self, frame: Frame) -> Detections:
        return self.redetect(frame, self.backend(frame))

    def redetect(self, frame: Frame, detections: Detections) -> Detections:
        """``detections`` (the main pass on ``frame``) with the missed tracks' re-detections merged in."""
        self.frames += 1
        _, predicted, hits = self.model.predicted_boxes(frame)
        image_size = (int(frame.camera.height), int(frame.camera.width))
        rows = missed_tracks(predicted, hits, detections.boxes, image_size, self.config)
        if not len(rows):
            return detections
        image = frame_image(frame)
        image_size = (image.shape[0], image.shape[1])
        found = self._search(image, predicted[rows], image_size)
        # a person nearer another track's predicted box is that track's business (or a neighbour)
        found = [d for d, r in zip(found, rows) if len(d) and nearest_track(d.boxes[0], predicted) == r]
        self.crops += len(rows)
        if not found:
            return detections
        extra = Detections(*(np.concatenate([getattr(d, k) for d in found])
                             for k in ("keypoints", "confidences", "boxes", "scores")))
        merged = merge_detections([(detections, np.zeros(len(detections), bool)),
                                   (extra, np.zeros(len(extra), bool))], max_detections=self.backend.max_detections)
        self.redetected += len(merged) - len(detections)
        return merged

    def _search(self, image: np.ndarray, boxes: np.ndarray, image_size: tuple[int, int]) -> list[Detections]:
        """Per box of ``boxes`` (K, 4) px, the one whole person in the crop around it nearest to it,
        or none; the crops are independent passes (one network call: side by side on the CPU)."""
        b = self.backend
        steps = [crop_pass(box, image_size, self.config) for box in boxes]
        sizes = [step.input_size if b.dynamic else b.input_size for step in steps]
        found = run_passes(b.infer_many, image, steps, sizes, b.score_threshold, b.iou_threshold, b.max_detections)
        margin_px = b.detection.edge_margin_px if b.detection is not None else 0.0
        out = []
        for box, step, size, dets in zip(boxes, steps, sizes, found):
            if len(dets):
                scale = min(size[0] / (step.region[3] - step.region[1]), size[1] / (step.region[2] - step.region[0]))
                whole = ~cut_by_inner_edge(dets.boxes, step.region, image_size, margin_px / scale)
                dets = dets.take(nearest_person(box, dets.boxes, whole, self.config))
            out.append(dets)
        return out

    def describe(self) -> dict:
        """The wrapped backend's description with the re-detection settings and counts."""
        base = self.backend.describe() if hasattr(self.backend, "describe") else {"backend": self.name}
        return {**base, "redetect": {**{k: getattr(self.config, k) for k in self.config.__dataclass_fields__},
                                     "frames": self.frames, "crops": self.crops, "redetected": self.redetected}}


def with_redetection(backend: PoseBackend, model: TrackPredictor, config: RedetectConfig) -> PoseBackend:
    """``backend`` wrapped in a :class:`RedetectingPose` when ``config.enabled`` and the backend
    can run crops (the ``onnx`` backend); otherwise ``backend`` itself. A ``stream`` backend
    (:class:`~pedenv.pose.stream.StreamPose`) searches missed tracks itself, in packed crops:
    it is given the model and returned as it is."""
    if hasattr(backend, "attach_model"):
        backend.attach_model(model)
        return backend
    if not config.enabled or not hasattr(backend, "infer") or not hasattr(model, "predicted_boxes"):
        return backend
    return RedetectingPose(cast("OnnxPose", backend), model, config)  # only the onnx backend has infer
