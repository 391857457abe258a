"""The pose backend Protocol and the registry that creates the networks by name."""

from __future__ import annotations

import importlib
from typing import Any, Protocol, runtime_checkable

from pedenv.errors import InputError
from pedenv.records import Detections, Frame, PredictedTracks


@runtime_checkable
class PoseBackend(Protocol):
    """Turns one frame into 2D skeletons.

    ``name`` is saved with the results. ``__call__`` reads what it needs from the frame
    (its image, or its ground truth for the ``ground-truth`` backend) and returns
    :class:`~pedenv.records.Detections` in the frame's pixel coordinates. ``tracks``: where
    the model expects its live tracks in this frame (:class:`~pedenv.records.PredictedTracks`),
    handed in by the pipeline; a backend that cannot use them ignores them.
    """

    name: str

    def __call__(self, frame: Frame, tracks: PredictedTracks | None = None) -> Detections: ...


#: Backend name -> "module:class"; modules are imported only when the backend is created.
POSE_BACKENDS: dict[str, str] = {
    "ground-truth": "pedenv.pose.ground_truth:GroundTruthPose",
    "detector-model": "pedenv.synthetic.detector:DetectorModel",
    "onnx": "pedenv.pose.onnx_backend:OnnxPose",
    "ultralytics": "pedenv.pose.ultralytics_backend:UltralyticsPose",
}


def create_pose_backend(name: str, **options: Any) -> PoseBackend:  # options: the backend class's keywords
    """Create the backend registered as ``name`` with its keyword ``options``.

    ``detector-model:<profile>`` (e.g. ``detector-model:yolo11n-pose-single``) is the
    detector model with that named profile. ``onnx`` is the network alone, one pass per
    frame; the detection modes that spend it (``fast``, ``far``, ``stream``) are
    :func:`pedenv.detection.create_detector`'s. Raises InputError naming the valid backends
    for an unknown name.
    """
    if name.startswith("detector-model:"):
        name, options = "detector-model", {"profile": name.split(":", 1)[1], **options}
    if name not in POSE_BACKENDS:
        raise InputError(f"unknown pose backend {name!r}; valid: {', '.join(POSE_BACKENDS)}")
    module, cls = POSE_BACKENDS[name].split(":")
    return getattr(importlib.import_module(module), cls)(**options)
