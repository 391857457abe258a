"""The per-frame pipeline: predict the tracks, detect with those tracks, update the model.

    from pedenv import Config, Pipeline
    pipeline = Pipeline(Config())          # the onnx network in ``stream`` mode, as ``pedenv run``
    for frame in recording.frames():       # pedenv.recordings.footage.load_recording
        state = pipeline.step(frame)

Each stage hands its data forward: the model predicts where its live tracks will be in the frame
(:meth:`~pedenv.model.PedestrianEnvironmentModel.predict_tracks`), the detector is given those
tracks with the frame (``detector(frame, tracks)``: ``stream`` and the re-detection look for the
tracks the whole-frame pass missed), the model takes the frame with its detections. No stage holds
another. ``pedenv run`` runs this same pipeline (:func:`pedenv.apps.run.run_recording`), so the
library and the command line write the same ``environment.jsonl``.
"""

from __future__ import annotations

import time
from dataclasses import replace

from pedenv.config import Config
from pedenv.detection import backend_options, create_detector
from pedenv.model import PedestrianEnvironmentModel
from pedenv.pose.base import PoseBackend
from pedenv.records import Frame
from pedenv.state import EnvironmentState


class Pipeline:
    """The environment model fed by a detector, one frame at a time.

    config: the run's settings (default ``Config()``, the fused method).
    detector: anything called ``detector(frame, tracks)`` that returns the frame's
        :class:`~pedenv.records.Detections` (:func:`pedenv.detection.create_detector`); None: the
        ``onnx`` network in ``stream`` mode with the config's detection and track-search settings,
        as ``pedenv run`` runs without ``--detection`` (``config.detection.mode`` is then set to
        ``stream`` in :attr:`config`, which is what to save with the results).

    ``detection_s`` and ``model_s`` add up the seconds spent detecting and in the model's update,
    over ``frames`` frames.
    """

    def __init__(self, config: Config | None = None, detector: PoseBackend | None = None) -> None:
        config = config if config is not None else Config()
        if detector is None:
            config = config.replace(detection={"mode": "stream"})
            detector = create_detector("onnx", **backend_options(
                "onnx", detection=config.detection, score_threshold=config.tracking.pose_score_threshold,
                redetect=config.redetect))
        self.config, self.detector = config, detector
        self.model = PedestrianEnvironmentModel(config)
        self.detection_s = self.model_s = 0.0
        self.frames = 0

    def step(self, frame: Frame) -> EnvironmentState:
        """The environment model at ``frame``'s timestamp, after the frame is added (timestamps must increase)."""
        return self.process(frame)[0]

    def process(self, frame: Frame) -> tuple[EnvironmentState, Frame]:
        """:meth:`step`, and ``frame`` with the detections the model was given (for overlays and outputs)."""
        start = time.perf_counter()
        tracks = self.model.predict_tracks(frame)
        frame = replace(frame, detections=self.detector(frame, tracks))
        middle = time.perf_counter()
        state = self.model.update(frame)
        self.detection_s += middle - start
        self.model_s += time.perf_counter() - middle
        self.frames += 1
        return state, frame
