"""Several small crops packed into one network input (a packed input), and the persons found mapped back.

Ten far people cost one pass, not ten: each crop (a region around a predicted box or a
low-scoring candidate) is scaled so its person has the height the network sees best,
placed on shelves of a ``packed_size`` canvas (grey between the crops), and every person
the network finds in the canvas goes back to the crop holding its box centre, then to the
image's pixels: ``image = (input - offset) / scale + region origin``. A person touching an
edge of its crop that is not an image edge is marked cut (it may belong to a neighbour).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from pedenv.detection.config import STRIDE
from pedenv.detection.tiling import Pass, units
from pedenv.pose.postprocess import PAD_VALUE, DecodeSettings, InferMany, Letterbox, decode, to_input_tensor
from pedenv.records import Detections

#: Grey input px left between two crops of a packed input.
GAP_PX = 4


@dataclass(frozen=True)
class Crop:
    """An image region ``(x0, y0, x1, y1)`` px (end exclusive) and its ``scale`` (input px per image px);
    ``edge_px``: a person within this many input px of an inner edge of the crop is cut (None: the
    decoding's ``edge_margin_px``)."""

    region: tuple[int, int, int, int]
    scale: float
    edge_px: float | None = None

    @property
    def size(self) -> tuple[int, int]:
        """(height, width) in the packed input, input px."""
        x0, y0, x1, y1 = self.region
        return max(1, int(round((y1 - y0) * self.scale))), max(1, int(round((x1 - x0) * self.scale)))


@dataclass(frozen=True)
class Placement:
    """Crop number ``item`` of the packed list, placed in packed input number ``packed`` with its
    top-left corner at ``offset`` (x, y) input px."""

    crop: Crop
    packed: int
    offset: tuple[int, int]
    item: int


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


def crop_around(box: np.ndarray, image_size: tuple[int, int], person_px: float, margin: float, max_zoom: float,
                packed_size: tuple[int, int], also: np.ndarray | None = None) -> Crop:
    """The crop for a person's ``box`` (4,) px in an image of ``image_size`` (height, width):
    ``margin`` times the box height on every side, clipped to the image; scaled so the box is
    ``person_px`` tall (at most ``max_zoom``, and so the crop fits in ``packed_size``).
    ``also`` (4,) px: a second place the person may be (the crop covers both, with the same
    margin; the scale stays ``box``'s)."""
    h, w = image_size
    box = np.asarray(box, float)
    height = max(float(box[3] - box[1]), 1.0)
    span = box if also is None else np.concatenate([np.minimum(box[:2], also[:2]), np.maximum(box[2:], also[2:])])
    x0, y0 = max(0, int(math.floor(span[0] - margin * height))), max(0, int(math.floor(span[1] - margin * height)))
    x1, y1 = min(w, int(math.ceil(span[2] + margin * height))), min(h, int(math.ceil(span[3] + margin * height)))
    x1, y1 = max(x1, x0 + 1), max(y1, y0 + 1)
    fit = min((packed_size[0] - 2 * GAP_PX) / (y1 - y0), (packed_size[1] - 2 * GAP_PX) / (x1 - x0))
    return Crop((x0, y0, x1, y1), float(min(person_px / height, max_zoom, fit)))


def merge_crops(crops: list[Crop], max_scale_ratio: float,
                packed_size: tuple[int, int]) -> tuple[list[Crop], list[list[int]]]:
    """Neighbouring crops joined where that costs fewer input px (a crowd's crops overlap).

    Taken in the given (priority) order, a crop joins the first crop before it whose scale
    differs by at most ``max_scale_ratio`` when one crop over both regions, at the smaller of
    the two scales, fits in ``packed_size`` and has at most the input area of the two apart.
    Returns the crops and, per crop, the indices of ``crops`` it holds (its first one's priority).
    """
    merged: list[Crop] = []
    groups: list[list[int]] = []
    for i, crop in enumerate(crops):
        for k, other in enumerate(merged):
            joined = _joined(other, crop, max_scale_ratio, packed_size)
            if joined is not None:
                merged[k] = joined
                groups[k].append(i)
                break
        else:
            merged.append(crop)
            groups.append([i])
    return merged, groups


def _joined(a: Crop, b: Crop, max_scale_ratio: float, packed_size: tuple[int, int]) -> Crop | None:
    if max(a.scale, b.scale) > max_scale_ratio * min(a.scale, b.scale):
        return None
    (ax0, ay0, ax1, ay1), (bx0, by0, bx1, by1) = a.region, b.region
    joined = Crop((min(ax0, bx0), min(ay0, by0), max(ax1, bx1), max(ay1, by1)), min(a.scale, b.scale), a.edge_px)
    (h, w), (ah, aw), (bh, bw) = joined.size, a.size, b.size
    if h + 2 * GAP_PX > packed_size[0] or w + 2 * GAP_PX > packed_size[1] or h * w > ah * aw + bh * bw:
        return None
    return joined


def pack(crops: list[Crop], packed_size: tuple[int, int], max_inputs: int | None = None) -> list[Placement]:
    """Shelf packing in the given order (first fit): crops that do not fit in ``max_inputs``
    packed inputs are left out (the list is shorter). A crop larger than a packed input is left out."""
    height, width = packed_size
    shelves: list[list[list[int]]] = []  # per packed input: [top, shelf height, next x] per shelf
    placed = []
    for item, crop in enumerate(crops):
        ch, cw = crop.size
        if ch + 2 * GAP_PX > height or cw + 2 * GAP_PX > width:
            continue
        spot = _find_spot(shelves, ch, cw, height, width)
        if spot is None and (max_inputs is None or len(shelves) < max_inputs):
            shelves.append([[GAP_PX, ch, GAP_PX]])  # a new packed input, its first shelf
            spot = (len(shelves) - 1, 0)
        if spot is None:
            continue
        m, s = spot
        shelf = shelves[m][s]
        placed.append(Placement(crop, m, (shelf[2], shelf[0]), item))
        shelf[2] += cw + GAP_PX
    return placed


def pack_tallest_first(crops: list[Crop], packed_size: tuple[int, int],
                       max_inputs: int | None = None) -> list[Placement]:
    """Denser packing for ``stream``: the crops are taken in the given (priority) order, each kept
    when the kept ones still fit in ``max_inputs`` packed inputs packed tallest first (shelves of
    :func:`pack` then waste no rows under a short crop that opened them). ``Placement.item``
    indexes ``crops``; the placements come tallest first."""
    height, width = packed_size
    usable = [i for i, c in enumerate(crops) if c.size[0] + 2 * GAP_PX <= height and c.size[1] + 2 * GAP_PX <= width]
    if max_inputs is None:
        return _tallest_first(crops, usable, packed_size)
    kept: list[int] = []
    placed: list[Placement] = []
    for i in usable:
        trial = _tallest_first(crops, [*kept, i], packed_size)
        if len({p.packed for p in trial}) <= max_inputs:
            kept, placed = [*kept, i], trial
    return placed


def _tallest_first(crops: list[Crop], items: list[int], packed_size: tuple[int, int]) -> list[Placement]:
    order = sorted(items, key=lambda i: -crops[i].size[0])  # stable: equal heights keep their priority
    return [Placement(p.crop, p.packed, p.offset, order[p.item]) for p in pack([crops[i] for i in order], packed_size)]


def _find_spot(shelves: list[list[list[int]]], ch: int, cw: int, height: int, width: int) -> tuple[int, int] | None:
    for m, shelved in enumerate(shelves):
        for s, (_, shelf_h, x) in enumerate(shelved):
            if ch <= shelf_h and x + cw + GAP_PX <= width:
                return m, s
        top, shelf_h, _ = shelved[-1]
        if top + shelf_h + GAP_PX + ch + GAP_PX <= height and cw + 2 * GAP_PX <= width:
            shelved.append([top + shelf_h + GAP_PX, ch, GAP_PX])
            return m, len(shelved) - 1
    return None


def render(image: np.ndarray, placements: list[Placement], packed_size: tuple[int, int]) -> np.ndarray:
    """(H, W, 3) uint8 canvas of ``packed_size`` (at least the placements' extent) with the
    placements' crops of ``image`` (H, W, 3) uint8 RGB."""
    canvas = np.full((*packed_size, 3), PAD_VALUE, np.uint8)
    for p in placements:
        x0, y0, x1, y1 = p.crop.region
        ch, cw = p.crop.size
        ox, oy = p.offset
        canvas[oy:oy + ch, ox:ox + cw] = cv2.resize(image[y0:y1, x0:x1], (cw, ch), interpolation=cv2.INTER_LINEAR)
    return canvas


def unpack(dets: Detections, placements: list[Placement], image_size: tuple[int, int],
           edge_margin_px: float) -> list[tuple[Detections, np.ndarray]]:
    """Per placement: the persons of ``dets`` (packed input px) whose box centre lies in its crop,
    in image px, and (N,) bool: cut by an inner crop edge (within the crop's ``edge_px``, else
    ``edge_margin_px``, input px)."""
    centres = 0.5 * (dets.boxes[:, :2] + dets.boxes[:, 2:]) if len(dets) else np.zeros((0, 2))
    out = []
    for p in placements:
        ch, cw = p.crop.size
        ox, oy = p.offset
        inside = ((centres[:, 0] >= ox) & (centres[:, 0] < ox + cw) & (centres[:, 1] >= oy) & (centres[:, 1] < oy + ch))
        part = dets.take(inside)
        shift_in, shift_out = np.array([ox, oy], float), np.array(p.crop.region[:2], float)
        kps = (part.keypoints - shift_in) / p.crop.scale + shift_out
        boxes = (part.boxes - np.tile(shift_in, 2)) / p.crop.scale + np.tile(shift_out, 2)
        part = Detections(kps, part.confidences, boxes, part.scores)
        edge = edge_margin_px if p.crop.edge_px is None else p.crop.edge_px
        out.append((part, cut_by_inner_edge(part.boxes, p.crop.region, image_size, edge / p.crop.scale)))
    return out


def used_size(placements: list[Placement], packed_size: tuple[int, int]) -> tuple[int, int]:
    """(height, width) of the smallest input that holds ``placements``' crops (one packed input's) with
    the grey gap after them: multiples of the network's stride (32), at most ``packed_size``."""
    height = max(p.offset[1] + p.crop.size[0] for p in placements) + GAP_PX
    width = max(p.offset[0] + p.crop.size[1] for p in placements) + GAP_PX
    return (min(packed_size[0], STRIDE * math.ceil(height / STRIDE)),
            min(packed_size[1], STRIDE * math.ceil(width / STRIDE)))


def packed_units(placements: list[Placement], packed_size: tuple[int, int], trim: bool) -> float:
    """The mean network units of the packed inputs of ``placements``: each a whole ``packed_size`` (also
    without any placement), or with ``trim`` the room its crops use (:func:`used_size`)."""
    inputs = sorted({p.packed for p in placements})
    if not trim or not inputs:
        return units(packed_size)
    return sum(units(used_size([p for p in placements if p.packed == m], packed_size)) for m in inputs) / len(inputs)


def run_packed(infer: InferMany, image: np.ndarray, placements: list[Placement],
                packed_size: tuple[int, int], settings: DecodeSettings,
                trim: bool = False) -> tuple[list[tuple[Detections, np.ndarray]], list[Pass]]:
    """Run every packed input of ``placements`` over ``image`` (H, W, 3) uint8 RGB (one network call for
    all: ``infer`` may batch them or run them side by side); per placement (in order) its persons
    in image px and their cut flags, and the passes run (kind ``packed``). ``trim``: each packed input's
    input is cut to the room its crops use (:func:`used_size`; a model with a dynamic input):
    a packed input of three crops costs what they cover, not a whole packed input."""
    results: list[tuple[Detections, np.ndarray] | None] = [None] * len(placements)
    passes = []
    image_size = (image.shape[0], image.shape[1])
    inputs = sorted({p.packed for p in placements})
    rows = [[i for i, p in enumerate(placements) if p.packed == m] for m in inputs]
    groups = [[placements[i] for i in r] for r in rows]
    sizes = [used_size(group, packed_size) if trim else packed_size for group in groups]
    outputs = infer([to_input_tensor(render(image, group, size)) for group, size in zip(groups, sizes)])
    for members, group, size, output in zip(rows, groups, sizes, outputs):
        dets = decode(output, Letterbox(1.0, 0, 0, size, size), settings.score_threshold, settings.iou_threshold,
                      settings.max_detections)
        for i, part in zip(members, unpack(dets, group, image_size, settings.edge_margin_px)):
            results[i] = part
        regions = np.array([p.crop.region for p in group])
        bound = (int(regions[:, 0].min()), int(regions[:, 1].min()), int(regions[:, 2].max()), int(regions[:, 3].max()))
        passes.append(Pass(bound, size, "packed"))
    return [r for r in results if r is not None], passes
