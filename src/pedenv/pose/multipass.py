"""Run the pose network over the planned passes (whole frame, tiles) and merge the persons.

``infer(tensor (1, 3, h, w) float32) -> (1, 56, N)`` is the network; each pass crops its
region, letterboxes it into its input size, decodes, shifts back to image pixels and
marks the persons touching an inner tile edge as cut; :func:`merge_detections` merges.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pedenv.pose.merge import MergeConfig, merge_detections
from pedenv.pose.postprocess import decode, letterbox, to_input_tensor
from pedenv.pose.tiling import Pass
from pedenv.records import Detections

#: The default merge settings (frozen, shared).
DEFAULT_MERGE = MergeConfig()


def cut_by_inner_edge(boxes: np.ndarray, region: tuple[int, int, int, int], image_size: tuple[int, int],
                      margin_px: float) -> np.ndarray:
    """(N,) bool: boxes (N, 4) px within ``margin_px`` of an edge of ``region`` that is not an image edge."""
    x0, y0, x1, y1 = region
    h, w = image_size
    cut = np.zeros(len(boxes), bool)
    if x0 > 0:
        cut |= boxes[:, 0] <= x0 + margin_px
    if y0 > 0:
        cut |= boxes[:, 1] <= y0 + margin_px
    if x1 < w:
        cut |= boxes[:, 2] >= x1 - margin_px
    if y1 < h:
        cut |= boxes[:, 3] >= y1 - margin_px
    return cut


def spans_the_region(boxes: np.ndarray, region: tuple[int, int, int, int], image_size: tuple[int, int],
                     margin_px: float) -> np.ndarray:
    """(N,) bool: boxes cut by two opposite inner edges of ``region`` (top and bottom, or left
    and right): a part of something larger than the tile, whole only in a coarser pass."""
    x0, y0, x1, y1 = region
    h, w = image_size
    vertical = (y0 > 0) & (y1 < h) & (boxes[:, 1] <= y0 + margin_px) & (boxes[:, 3] >= y1 - margin_px)
    horizontal = (x0 > 0) & (x1 < w) & (boxes[:, 0] <= x0 + margin_px) & (boxes[:, 2] >= x1 - margin_px)
    return vertical | horizontal


def run_pass(infer: Callable[[np.ndarray], np.ndarray], image: np.ndarray, step: Pass, input_size: tuple[int, int],
             score_threshold: float, iou_threshold: float, max_detections: int) -> Detections:
    """Detections of one pass, in pixels of the whole ``image`` (H, W, 3) uint8 RGB."""
    x0, y0, x1, y1 = step.region
    crop = image[y0:y1, x0:x1]
    padded, box = letterbox(crop, input_size)
    dets = decode(infer(to_input_tensor(padded)), box, score_threshold, iou_threshold, max_detections)
    if not len(dets) or (x0, y0) == (0, 0):
        return dets
    shift = np.array([x0, y0], float)
    return Detections(dets.keypoints + shift, dets.confidences, dets.boxes + np.tile(shift, 2), dets.scores)


def detect_multipass(infer: Callable[[np.ndarray], np.ndarray], image: np.ndarray, passes: list[Pass], *,
                     fixed_input: tuple[int, int] | None, score_threshold: float, iou_threshold: float,
                     max_detections: int, edge_margin_px: float, merge: MergeConfig = DEFAULT_MERGE) -> Detections:
    """All passes over ``image`` (H, W, 3) uint8 RGB, merged; ``fixed_input`` forces every pass's input size."""
    if len(passes) == 1:
        step = passes[0]
        return run_pass(infer, image, step, fixed_input or step.input_size, score_threshold, iou_threshold,
                        max_detections)
    parts = []
    for step in passes:
        size = fixed_input or step.input_size
        dets = run_pass(infer, image, step, size, score_threshold, iou_threshold, max_detections)
        scale = min(size[0] / (step.region[3] - step.region[1]), size[1] / (step.region[2] - step.region[0]))
        margin = edge_margin_px / scale
        image_size = (image.shape[0], image.shape[1])
        if len(dets):
            dets = dets.take(~spans_the_region(dets.boxes, step.region, image_size, margin))
        parts.append((dets, cut_by_inner_edge(dets.boxes, step.region, image_size, margin)))
    return merge_detections(parts, merge, max_detections)
