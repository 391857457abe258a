"""The detection stage: the pose network spent as the run's detection settings say.

:func:`create_detector` is the one place that picks the mode: ``onnx`` becomes a
:class:`Detector` over the network (:class:`~pedenv.pose.onnx_backend.OnnxPose`) in mode
``fast``, ``far`` (either with the re-detection of missed tracks when ``redetect.enabled``) or
``stream``; another backend (``ground-truth``, ``detector-model``, ``ultralytics``) is returned as
the pose registry makes it. Every detector is called ``detector(frame, tracks)``: the tracks the
model predicts for the frame are an input, handed in by the pipeline (:class:`pedenv.Pipeline`);
no detector holds the model.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.detection.config import EDGE_MARGIN_PX, DetectionConfig, RedetectConfig
from pedenv.detection.geometry import CameraGeometry
from pedenv.detection.levels import plan_passes
from pedenv.detection.passes import detect_levels
from pedenv.detection.redetect import Redetection
from pedenv.detection.stream import StreamState
from pedenv.detection.tiling import Pass
from pedenv.errors import InputError
from pedenv.pose.base import PoseBackend, create_pose_backend
from pedenv.pose.onnx_backend import OnnxPose
from pedenv.pose.postprocess import frame_image
from pedenv.records import Detections, Frame, PredictedTracks


class Detector:
    """The ``onnx`` pose network in a detection mode.

    network: the network (its passes' score threshold, NMS and max persons are its own).
    config: the mode and its settings (:class:`DetectionConfig`); None: one pass at the
        network's input size.
    redetect: the re-detection of missed tracks (``far``, ``fast``, one pass; on when
        ``redetect.enabled``) and the track search's matching (all modes, ``stream`` included);
        None: its defaults, re-detection off.
    """

    name = "onnx"

    def __init__(self, network: OnnxPose, config: DetectionConfig | None = None, *,
                 redetect: RedetectConfig | None = None) -> None:
        self.network, self.config = network, config
        match = redetect if redetect is not None else RedetectConfig()
        #: The passes' decoding; the cut margin at inner edges is the config's (none for one pass).
        self.decoding = replace(network.decoding, edge_margin_px=EDGE_MARGIN_PX if config is not None else 0.0)
        self.stream = (StreamState(network, config, self.decoding, match)
                       if config is not None and config.mode == "stream" else None)
        self.redetection = Redetection(match) if self.stream is None and match.enabled else None
        #: The passes the last frame ran, and how their rows were chosen.
        self.last_passes: list[Pass] = []
        self.last_note = ""

    @property
    def provider(self) -> str:
        """The onnxruntime provider that runs the network."""
        return self.network.provider

    def __call__(self, frame: Frame, tracks: PredictedTracks | None = None) -> Detections:
        """The persons in ``frame`` (px of its image); ``tracks``: where the model expects its live
        tracks in this frame (searched for by ``stream`` and by the re-detection), None: none."""
        image, geometry = frame_image(frame), CameraGeometry.from_frame(frame)  # the camera, once per frame
        if self.stream is not None:
            return self.detect_frame(image, geometry, frame.timestamp, tracks)
        dets = self.detect(image, geometry)
        if self.redetection is not None and tracks is not None:
            size = (int(frame.camera.height), int(frame.camera.width))
            dets = self.redetection(self.network, image, size, dets, tracks, self.decoding)
        return dets

    def detect(self, image_rgb: np.ndarray, geometry: CameraGeometry | None = None) -> Detections:
        """One image on its own, ``image_rgb`` (H, W, 3) uint8 RGB; px of that image. geometry: the
        camera for the ground band (None: no calibration, the rows fitted to the people found).
        ``stream`` on one image runs as ``far`` (the whole band), the cascade included."""
        net = self.network
        if self.config is None:
            self.last_passes, self.last_note = [Pass((0, 0, image_rgb.shape[1], image_rgb.shape[0]),
                                                     net.input_size, "full")], "one pass"
            return net.detect(image_rgb)
        dets, self.last_passes, self.last_note = detect_levels(
            net.infer_many, image_rgb, self.config, geometry, fixed_input=None if net.dynamic else net.input_size,
            decoding=self.decoding, base_input=net.requested_input)
        return dets

    def detect_frame(self, image_rgb: np.ndarray, geometry: CameraGeometry | None, timestamp: float,
                     tracks: PredictedTracks | None = None) -> Detections:
        """``stream``: ``image_rgb`` (H, W, 3) uint8 RGB as the next frame of the stream, at
        ``timestamp`` s, with the tracks predicted for it (:meth:`StreamState.detect_frame`)."""
        if self.stream is None:
            raise InputError("detect_frame needs the detection mode stream")
        dets = self.stream.detect_frame(image_rgb, geometry, timestamp, tracks)
        self.last_passes, self.last_note = self.stream.last_passes, self.stream.last_note
        return dets

    def restart(self) -> None:
        """Forget the stream (``stream``): the next frame is a first frame (a cold start)."""
        if self.stream is not None:
            self.stream.restart()

    def plan(self, width: int, height: int, geometry: CameraGeometry | None = None) -> tuple[list[Pass], str]:
        """The passes run on a ``width`` x ``height`` image before any detection, and how they were
        chosen (levels whose rows wait for a fit to the people found are only named in the note)."""
        if self.config is None:
            raise InputError(f"{self.network.model_path}: no detection mode set (one pass at "
                             f"{self.network.input_size}): nothing to plan")
        passes, note = plan_passes(width, height, self.config, geometry)
        if self.network.requested_input is not None:
            passes[0] = Pass(passes[0].region, self.network.requested_input, "full")
        return passes, note

    def describe(self) -> dict:
        """What to save next to results: the network, the detection settings, and what the
        re-detection and the stream did."""
        net = self.network.describe()
        out = {**{k: v for k, v in net.items() if k not in ("score_threshold", "iou_threshold")},
               "detection": None if self.config is None else self.config.to_dict(),
               "score_threshold": net["score_threshold"], "iou_threshold": net["iou_threshold"]}
        if self.redetection is not None:
            out["redetect"] = self.redetection.to_dict()
        if self.stream is not None:
            out["stream"] = self.stream.accounts.to_dict()
        return out


def create_detector(name: str = "onnx", *, detection: str | DetectionConfig | None = None,
                    redetect: RedetectConfig | None = None,
                    **options: Any) -> PoseBackend:  # options: the backend's keywords
    """The detector ``name`` names, in the mode ``detection`` names (the one place that picks it).

    ``onnx``: a :class:`Detector` over :class:`~pedenv.pose.onnx_backend.OnnxPose` (``options``:
    its keywords: ``model_path``, ``input_size``, ``device``, ``score_threshold``, ...);
    ``detection`` ``fast``, ``far``, ``stream`` or a :class:`DetectionConfig`; None: ``far``,
    or one pass when ``input_size`` is given. ``redetect``: the run's section (``Config.redetect``:
    the re-detection and the track search's matching). Another backend: as
    :func:`pedenv.pose.create_pose_backend` makes it (``options`` its keywords).
    """
    if name != "onnx":
        return create_pose_backend(name, **options)
    if detection is None and options.get("input_size") is None:
        detection = "far"
    if isinstance(detection, str):
        detection = DetectionConfig.named(detection)
    elif detection is not None and not isinstance(detection, DetectionConfig):
        raise InputError(f"detection must be 'fast', 'far', 'stream' or a DetectionConfig, got {detection!r}")
    return Detector(OnnxPose(**options), detection, redetect=redetect)


def backend_options(backend: str, model: str | Path | None = None, input_size: int | str | Sequence[int] | None = None,
                    detection: str | DetectionConfig | None = None, score_threshold: float | None = None,
                    device: str = "auto", redetect: RedetectConfig | None = None) -> dict:
    """Keyword options for :func:`create_detector` ``(backend, ...)`` from a model file, input size,
    detection mode (``fast``, ``far`` or ``stream``, onnx only) and device (``auto``, ``cpu`` or ``cuda``:
    :mod:`pedenv.pose.providers`; ultralytics runs on the CPU, ``cuda`` is refused for it).

    ``onnx``: ``model`` is an ONNX file (None: the cached one for ``input_size``, else the
    dynamic one); ``ultralytics``: ``model`` is the .pt weights. Other backends take no options.
    score_threshold: the network's person score threshold (onnx, ultralytics); None keeps
    the backend's own (0.25). The tracker's low-score band needs it lowered
    (``TrackingConfig.pose_score_threshold``). ``detection`` may be a ``DetectionConfig`` and
    ``redetect`` a ``RedetectConfig`` (onnx; a run's ``Config.detection`` and ``Config.redetect``:
    the track search is built from the run's saved settings).
    """
    scores = {} if score_threshold is None else {"score_threshold": score_threshold}
    if backend == "onnx":
        return {"model_path": model, "input_size": input_size, "detection": detection, "device": device, **scores,
                **({} if redetect is None else {"redetect": redetect})}
    if device not in ("auto", "cpu"):
        raise InputError(f"device {device!r} applies to the onnx pose backend; {backend} runs on the CPU")
    if backend == "ultralytics":
        return {"weights": model, "input_size": input_size or 640, **scores}
    return {}
