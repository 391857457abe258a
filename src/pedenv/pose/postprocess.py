"""Pure numpy pre- and post-processing around a YOLO-pose network.

Pre-processing fits an image into the network input by a letterbox (scale, keeping the
aspect ratio, then pad with grey 114). Post-processing decodes the raw output
``(1, 56, N)`` (per anchor: box centre, width, height, person score, then 17 keypoints as
u, v, confidence; px of the input), keeps the persons above a score
threshold, suppresses overlapping boxes (NMS) and maps everything back to image pixels.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from pedenv.boxes import nms
from pedenv.errors import InputError
from pedenv.images import read_image_rgb
from pedenv.records import Detections, Frame
from pedenv.skeleton import NUM_KEYPOINTS
from pedenv.validation import check_count, check_number

#: Grey value of the letterbox padding the YOLO networks were trained with.
PAD_VALUE = 114
#: Rows of the raw output: 4 box + 1 score + 17 x (x, y, visibility).
OUTPUT_ROWS = 5 + 3 * NUM_KEYPOINTS
#: The network on the independent inputs of one step: (1, 3, h, w) float32 tensors in (sizes may
#: differ), their (1, 56, N) outputs out, in order
#: (:meth:`~pedenv.pose.onnx_backend.OnnxPose.infer_many`: batched, side by side or one by one).
InferMany = Callable[[list[np.ndarray]], list[np.ndarray]]


def parse_input_size(size: int | np.integer | str | Sequence[int]) -> tuple[int, int]:
    """``640``, ``"640"``, ``"384x640"`` or ``(384, 640)`` -> ``(height, width)`` in pixels.

    Both sides must be positive multiples of 32 (the network's stride).
    """
    if isinstance(size, str):
        parts = size.lower().replace(" ", "").split("x")
        try:
            values = [int(p) for p in parts]
        except ValueError:
            raise InputError(f"input size must look like 640 or 384x640 (height x width), got {size!r}") from None
    elif isinstance(size, (int, np.integer)) and not isinstance(size, bool):
        values = [int(size)]
    else:
        try:
            values = [int(v) for v in size]  # type: ignore[union-attr]  # a bool: the TypeError below
        except TypeError:
            raise InputError(f"input size must be an int or (height, width), got {size!r}") from None
    if len(values) == 1:
        values = values * 2
    if len(values) != 2 or any(v <= 0 or v % 32 for v in values):
        raise InputError(f"input size must be one or two positive multiples of 32 (height x width), got {size!r}")
    return values[0], values[1]


@dataclass(frozen=True)
class Letterbox:
    """How an image of ``image_size`` was placed into the network input of ``input_size``.

    input pixel = image pixel * scale + (pad_left, pad_top); sizes are ``(height, width)``.
    """

    scale: float
    pad_left: int
    pad_top: int
    image_size: tuple[int, int]
    input_size: tuple[int, int]

    @classmethod
    def fit(cls, image_size: tuple[int, int], input_size: tuple[int, int]) -> Letterbox:
        """The letterbox for an image of (height, width) into an input of (height, width)."""
        h, w = image_size
        in_h, in_w = input_size
        scale = min(in_h / h, in_w / w)
        new_w, new_h = max(round(w * scale), 1), max(round(h * scale), 1)
        # Centred padding; an odd leftover pixel goes to the right / bottom.
        return cls(scale, round((in_w - new_w) / 2 - 0.1), round((in_h - new_h) / 2 - 0.1), (h, w), (in_h, in_w))

    @property
    def resized_size(self) -> tuple[int, int]:
        """(height, width) of the image after scaling, before padding."""
        h, w = self.image_size
        return max(round(h * self.scale), 1), max(round(w * self.scale), 1)

    def to_image(self, points: np.ndarray) -> np.ndarray:
        """Input pixels -> image pixels. points: (..., 2) float ``(x, y)``; clipped to the image."""
        out = (points - np.array([self.pad_left, self.pad_top], float)) / self.scale
        h, w = self.image_size
        return np.clip(out, 0.0, [w, h])




def frame_image(frame: Frame) -> np.ndarray:
    """The frame's (H, W, 3) uint8 RGB image: ``frame.image``, else read from ``frame.image_path``."""
    if frame.image is not None:
        image = np.asarray(frame.image)
        if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise InputError(f"frame {frame.index}: image must be (H, W, 3) uint8 RGB, got {image.shape} {image.dtype}")
        return image
    if frame.image_path is None:
        raise InputError(f"frame {frame.index} of {frame.scene or 'the sequence'}: no image for the pose backend")
    return read_image_rgb(frame.image_path)


def letterbox(image: np.ndarray, input_size: tuple[int, int],
              pad_value: int = PAD_VALUE) -> tuple[np.ndarray, Letterbox]:
    """Scale ``image`` (H, W, 3) uint8 into ``input_size`` (height, width), padding with ``pad_value``.

    Returns ``(padded (in_h, in_w, 3) uint8, Letterbox)``.
    """
    box = Letterbox.fit((image.shape[0], image.shape[1]), input_size)
    new_h, new_w = box.resized_size
    if (new_h, new_w) != image.shape[:2]:
        image = cv2.resize(image, (new_w, new_h), interpolation=cv2.INTER_LINEAR)
    in_h, in_w = input_size
    padded = cv2.copyMakeBorder(image, box.pad_top, in_h - new_h - box.pad_top, box.pad_left,
                                in_w - new_w - box.pad_left, cv2.BORDER_CONSTANT, value=(pad_value,) * 3)
    return padded, box


#: The most persons one network input may report (``max_detections``' upper bound).
MAX_DETECTIONS = 10000


@dataclass(frozen=True)
class DecodeSettings:
    """How a pass's raw output is decoded (options of the ``onnx`` and ``ultralytics`` backends).

    score_threshold: persons scoring at or below this are dropped (0..1; 0.25). Raising it
        keeps fewer, surer persons.
    iou_threshold: a box overlapping a higher-scoring one by more than this IoU is
        suppressed (0..1; 0.7). Lowering it merges nearby persons more readily.
    max_detections: at most this many persons per input (1..10000; 300).
    edge_margin_px: a person within this many input px of an inner tile edge counts as cut (0..64;
        :data:`pedenv.detection.config.EDGE_MARGIN_PX` in the detection modes).
    """

    score_threshold: float = 0.25
    iou_threshold: float = 0.7
    max_detections: int = 300
    edge_margin_px: float = 16.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "score_threshold", float(check_number("score_threshold", self.score_threshold, 0, 1)))
        object.__setattr__(self, "iou_threshold", float(check_number("iou_threshold", self.iou_threshold, 0, 1)))
        check_count("max_detections", self.max_detections, 1, MAX_DETECTIONS)
        check_number("edge_margin_px", self.edge_margin_px, 0, 64)


def to_input_tensor(padded: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 RGB -> (1, 3, H, W) float32 in [0, 1], the network's input.

    One channel at a time into a fresh array, then one in-place scale: the same float32 values as
    ``padded.transpose(2, 0, 1).astype(np.float32) * np.float32(1 / 255)``
    (:func:`to_input_tensor_plain`) at about half its cost (docs/preprocessing.md).
    """
    height, width = padded.shape[:2]
    tensor = np.empty((1, 3, height, width), np.float32)
    for c, channel in enumerate(cv2.split(padded)):
        tensor[0, c] = channel
    tensor *= np.float32(1.0 / 255.0)
    return tensor


def to_input_tensor_plain(padded: np.ndarray) -> np.ndarray:
    """:func:`to_input_tensor` written plainly (transpose, convert, scale): the reference its tests
    compare with."""
    chw = np.ascontiguousarray(padded.transpose(2, 0, 1), dtype=np.float32)
    chw *= np.float32(1.0 / 255.0)
    return chw[None]


def decode(output: np.ndarray, box: Letterbox, score_threshold: float = 0.25, iou_threshold: float = 0.7,
           max_detections: int = 300) -> Detections:
    """Raw YOLO-pose output (1, 56, N) -> :class:`Detections` in the original image's pixels."""
    pred = output[0]
    scores = pred[4]
    candidates = np.flatnonzero(scores > score_threshold)
    if candidates.size == 0:
        return Detections.empty()
    pred = pred[:, candidates].T.astype(np.float64)  # (K, 56)
    cx, cy, w, h = pred[:, 0], pred[:, 1], pred[:, 2], pred[:, 3]
    boxes = np.stack([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2], axis=1)
    keep = nms(boxes, pred[:, 4], iou_threshold, max_detections)
    pred, boxes = pred[keep], boxes[keep]
    kpts = pred[:, 5:].reshape(-1, NUM_KEYPOINTS, 3)
    image_boxes = box.to_image(boxes.reshape(-1, 2, 2)).reshape(-1, 4)
    return Detections(box.to_image(kpts[..., :2]), kpts[..., 2], image_boxes, pred[:, 4])
