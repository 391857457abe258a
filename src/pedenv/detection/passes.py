"""Run the pose network over the levels of the pyramid (whole frame, bands, tiles) and merge.

``infer([tensor (1, 3, h, w) float32, ...]) -> [(1, 56, N), ...]`` is the network on the
independent passes of a step (:data:`~pedenv.pose.postprocess.InferMany`); each pass crops its
region, letterboxes it into its input size, decodes, shifts back to image pixels and
marks the persons touching an inner tile edge as cut. A finer level keeps a person only
when they are not too tall for it (``max_person_px``: fragments of someone the coarser
levels see whole) and, below ``SURE_SCORE``, when the skeleton looks like a person
(mean keypoint confidence at least ``plausible_keypoint_conf``). Without a usable
calibration each level's rows come from a line fitted to the people found so far
(:mod:`pedenv.detection.levels`). :func:`merge_detections` merges everything.
"""

from __future__ import annotations

from dataclasses import replace
from functools import partial

import numpy as np

from pedenv.detection.cascade import candidates, verify
from pedenv.detection.config import (
    CASCADE_MIN_SCORE,
    EDGE_MARGIN_PX,
    FIT_MIN_PEOPLE,
    FIT_MIN_SCORE,
    MAX_PERSON_PX,
    PLAUSIBLE_KEYPOINT_CONF,
    SURE_SCORE,
    DetectionConfig,
)
from pedenv.detection.geometry import CameraGeometry
from pedenv.detection.levels import HeightLine, placing_geometry, plan_level, pyramid
from pedenv.detection.merge import merge_detections
from pedenv.detection.packing import cut_by_inner_edge
from pedenv.detection.tiling import Pass, full_pass
from pedenv.pose.postprocess import DecodeSettings, InferMany, Letterbox, decode, letterbox, to_input_tensor
from pedenv.records import Detections

#: The default decoding (frozen, shared).
DEFAULT_DECODING = DecodeSettings()


def spans_the_region(boxes: np.ndarray, region: tuple[int, int, int, int], image_size: tuple[int, int],
                     margin_px: float) -> np.ndarray:
    """(N,) bool: boxes cut by two opposite inner edges of ``region`` (top and bottom, or left
    and right): a part of something larger than the tile, whole only in a coarser pass."""
    x0, y0, x1, y1 = region
    h, w = image_size
    vertical = (y0 > 0) & (y1 < h) & (boxes[:, 1] <= y0 + margin_px) & (boxes[:, 3] >= y1 - margin_px)
    horizontal = (x0 > 0) & (x1 < w) & (boxes[:, 0] <= x0 + margin_px) & (boxes[:, 2] >= x1 - margin_px)
    return vertical | horizontal


def pass_input(image: np.ndarray, step: Pass, input_size: tuple[int, int]) -> tuple[np.ndarray, Letterbox]:
    """The network input of one pass over ``image`` (H, W, 3) uint8 RGB: its region letterboxed
    into ``input_size``, as a (1, 3, h, w) tensor, and where the region went."""
    x0, y0, x1, y1 = step.region
    padded, box = letterbox(image[y0:y1, x0:x1], input_size)
    return to_input_tensor(padded), box


def pass_detections(output: np.ndarray, box: Letterbox, step: Pass, score_threshold: float, iou_threshold: float,
                    max_detections: int) -> Detections:
    """The persons of one pass's network ``output``, in pixels of the whole image."""
    dets = decode(output, box, score_threshold, iou_threshold, max_detections)
    x0, y0 = step.region[:2]
    if not len(dets) or (x0, y0) == (0, 0):
        return dets
    shift = np.array([x0, y0], float)
    return Detections(dets.keypoints + shift, dets.confidences, dets.boxes + np.tile(shift, 2), dets.scores)


def run_passes(infer: InferMany, image: np.ndarray, steps: list[Pass], input_sizes: list[tuple[int, int]],
               score_threshold: float, iou_threshold: float, max_detections: int) -> list[Detections]:
    """Detections of independent passes (one network call for all: ``infer`` may batch them or run
    them side by side), in pixels of the whole ``image`` (H, W, 3) uint8 RGB, in order."""
    inputs = [pass_input(image, step, size) for step, size in zip(steps, input_sizes)]
    outputs = infer([tensor for tensor, _ in inputs]) if inputs else []
    return [pass_detections(out, box, step, score_threshold, iou_threshold, max_detections)
            for out, (_, box), step in zip(outputs, inputs, steps)]


def level_filter(dets: Detections, step: Pass) -> np.ndarray:
    """(N,) bool: the persons of a finer level's pass to keep (module doc); all for ``full``."""
    if step.kind == "full" or not len(dets):
        return np.ones(len(dets), bool)
    heights = (dets.boxes[:, 3] - dets.boxes[:, 1]) * step.scale
    plausible = (dets.scores >= SURE_SCORE) | (dets.confidences.mean(1) >= PLAUSIBLE_KEYPOINT_CONF)
    return (heights <= MAX_PERSON_PX) & plausible


#: Per pass: its persons (px of the image) and which of them an inner tile edge cuts, (N,) bool.
Parts = list[tuple[Detections, np.ndarray]]


def run_level(infer: InferMany, image: np.ndarray, passes: list[Pass],
              fixed_input: tuple[int, int] | None, settings: DecodeSettings,
              low: list[Detections] | None = None) -> Parts:
    """Run ``passes``, independent of each other (``settings``: score threshold, NMS, max persons);
    with ``low`` a list, persons scoring :data:`~pedenv.detection.config.CASCADE_MIN_SCORE` up to the
    threshold (whole, not too tall for the level) are appended to it for the cascade."""
    score_threshold, iou_threshold, max_detections = (settings.score_threshold, settings.iou_threshold,
                                                      settings.max_detections)
    parts = []
    image_size = (image.shape[0], image.shape[1])
    floor = min(CASCADE_MIN_SCORE, score_threshold) if low is not None else score_threshold
    sizes = [fixed_input or step.input_size for step in passes]
    for step, size, dets in zip(passes, sizes, run_passes(infer, image, passes, sizes, floor, iou_threshold,
                                                          max_detections)):
        scale = min(size[0] / (step.region[3] - step.region[1]), size[1] / (step.region[2] - step.region[0]))
        margin = EDGE_MARGIN_PX / scale
        if len(dets):
            dets = dets.take(~spans_the_region(dets.boxes, step.region, image_size, margin))
        if low is not None and len(dets):
            weak = dets.take(dets.scores <= score_threshold)
            tall = (weak.boxes[:, 3] - weak.boxes[:, 1]) * scale > MAX_PERSON_PX
            low.append(weak.take(~tall & ~cut_by_inner_edge(weak.boxes, step.region, image_size, margin)))
            dets = dets.take(dets.scores > score_threshold)
        if len(dets):
            dets = dets.take(level_filter(dets, step))
        parts.append((dets, cut_by_inner_edge(dets.boxes, step.region, image_size, margin)))
    return parts


def detect_levels(infer: InferMany, image: np.ndarray, config: DetectionConfig,
                  geometry: CameraGeometry | None = None, *, decoding: DecodeSettings = DEFAULT_DECODING,
                  fixed_input: tuple[int, int] | None = None, base_input: tuple[int, int] | None = None,
) -> tuple[Detections, list[Pass], str]:
    """The pyramid over ``image`` (H, W, 3) uint8 RGB, coarse to fine, merged.

    geometry: the camera for the bands (None: rows fitted to the people found).
    decoding: score threshold, NMS IoU and max persons of every pass (its cut margin is
        :data:`~pedenv.detection.config.EDGE_MARGIN_PX`).
    fixed_input: forces every pass's input size (a model with a fixed input).
    base_input: the whole-frame pass's input (height, width) instead of the config's.
    Returns the persons (px of ``image``), the passes run and a note per level.
    """
    height, width = image.shape[:2]
    first = full_pass(width, height, config)
    if base_input is not None:
        first = Pass(first.region, base_input, "full")
    low: list[Detections] | None = [] if config.cascade.enabled and config.mode != "fast" else None
    settings = replace(decoding, edge_margin_px=EDGE_MARGIN_PX)
    max_detections = settings.max_detections
    run = partial(run_level, infer, image, fixed_input=fixed_input, settings=settings, low=low)
    levels = pyramid(width, height, config)[1:]
    geometry = placing_geometry(geometry, width, height, config)  # the ground band, once per frame
    if geometry is not None:  # every level's rows known now: one network call for all
        planned = [plan_level(level, width, height, config, geometry, None) for level in levels]
        passes = [first, *(p for more, _ in planned for p in more)]
        parts, notes = run(passes), [note for _, note in planned]
        levels = []
    else:
        parts, passes, notes = run([first]), [first], []
    for i, level in enumerate(levels):
        whole = [d.take(~c & (d.scores >= FIT_MIN_SCORE)) for d, c in parts if len(d)]
        boxes = np.concatenate([d.boxes for d in whole]) if whole else np.zeros((0, 4))
        line = HeightLine.fit(boxes, FIT_MIN_PEOPLE, height)
        more, note = plan_level(level, width, height, config, geometry, line, finest=i == len(levels) - 1)
        notes.append(note)
        parts += run(more)
        passes += more
    dets = parts[0][0] if len(passes) == 1 else merge_detections(parts, max_detections)
    if low is not None:
        verified, more = verify(infer, image, candidates(Detections.concat(low), dets), config.cascade,
                                config.stream.packed_size, settings)
        if more:
            notes.append(f"cascade: {len(verified)} confirmed in {len(more)} packed inputs")
            passes += more
            dets = merge_detections([(dets, np.zeros(len(dets), bool)), (verified, np.zeros(len(verified), bool))],
                                    max_detections)
    return dets, passes, "; ".join(notes) or "one pass"

