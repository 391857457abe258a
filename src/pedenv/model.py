"""PedestrianEnvironmentModel: detections + ego pose in, environment state out, per frame.

    model = PedestrianEnvironmentModel(Config())
    for frame in frames:           # frames carry detections (see pedenv.detection)
        state = model.update(frame)

One frame, as the paper's Fig. 2: the tracker compensates the ego's yaw and associates
the skeletons with the tracks in the image (:mod:`pedenv.tracking`); the position method
measures each tracked skeleton's world position (:mod:`pedenv.localization`); a
constant-velocity Kalman filter smooths it on the ground plane (:mod:`pedenv.kalman`).
Every per-track row lives in one :class:`~pedenv.tracking.table.TrackTable`. The filter
predicts before the tracker associates, so the tracker may gate with the prediction.
"""

from __future__ import annotations

import dataclasses
import time
from functools import lru_cache

import numpy as np

from pedenv import kalman
from pedenv.behaviour.estimator import BehaviourEstimator
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.localization import FrameGeometry, Locator, create_locator
from pedenv.localization.bounds import bound_measurement, clamp_reported
from pedenv.records import Detections, Frame, PredictedTracks
from pedenv.stage_timer import StageTimer
from pedenv.state import EnvironmentState, Pedestrians
from pedenv.tracking.egomotion import yaw_change, yaw_shift_pixels
from pedenv.tracking.prediction import predict_boxes
from pedenv.tracking.projection import CameraView
from pedenv.tracking.table import TrackTable
from pedenv.tracking.tracker import Tracker


class PedestrianEnvironmentModel:
    """The paper's pedestrian environment model, one frame at a time.

    locator: a position method of your own (see :class:`~pedenv.localization.Locator`);
        by default the one ``config.method`` names.
    """

    def __init__(self, config: Config | None = None, locator: Locator | None = None) -> None:
        self.config = config or Config()
        self.locator = locator if locator is not None else create_locator(self.config)
        self.tracks = TrackTable(locator=self.locator.columns)
        self.tracker = Tracker(self.config.tracking, table=self.tracks)
        self.timer = StageTimer()
        self._transition = lru_cache(maxsize=64)(self._make_transition)
        self.behaviour = (BehaviourEstimator(self.config.behaviour, self.config.kalman.acceleration_std_mps2)
                          if self.config.behaviour.enabled else None)
        self.reset()

    def reset(self) -> None:
        """Forget all tracks (start of a new scene); the stage timer keeps counting."""
        self.tracker.reset()
        self._last: Frame | None = None
        if self.behaviour is not None:
            self.behaviour.reset()

    def update(self, frame: Frame) -> EnvironmentState:
        """Add one frame and return the environment model at its timestamp.

        ``frame.detections`` must be set (by a pose backend); timestamps must increase.
        With a locator that ``requires_keypoints`` (``paper``), a person with no seen
        keypoint (all NaN or all confidences <= 0) is left out before tracking.
        """
        det = self._check(frame)
        if getattr(self.locator, "requires_keypoints", False):
            seen = (det.confidences > 0).any(axis=1)  # NaN keypoints and confidences <= 0 are 0 here
            if not seen.all():  # no keypoint to place them by: no pedestrians (fused: no score to track)
                det = det.take(seen)
                frame = dataclasses.replace(frame, detections=det)
        t0 = time.perf_counter()
        self._predict(frame)  # first: the tracker may gate with the prediction (beyond the paper)
        t1 = time.perf_counter()
        step = self.tracker.update(det.boxes, self._yaw_shift(frame), det.scores, self._view(frame))
        t2 = time.perf_counter()
        rows = step.detection_rows
        if (rows < 0).any():  # low-score detections that continued no track are not pedestrians
            keep = rows >= 0
            det, rows = (
                Detections(det.keypoints[keep], det.confidences[keep], det.boxes[keep], det.scores[keep]),
                rows[keep],
            )
            frame = dataclasses.replace(frame, detections=det)
        peds = self._locate(frame, det, rows) if len(det) else Pedestrians.empty()
        self.timer.add(t2 - t1, (t1 - t0) + (time.perf_counter() - t2), len(det))  # the filter counts as position
        if self.behaviour is not None:  # beyond the paper: orientation, motion state, path, conflict
            f = self.tracks.filter
            peds = self.behaviour.update(frame, peds, f.x[rows], f.P[rows], f.started[rows], self.tracks.tracks.ids)
        self._last = frame
        return EnvironmentState(frame.index, frame.timestamp, frame.ego, peds, frame.scene)

    def predict_tracks(self, frame: Frame) -> PredictedTracks:
        """Where the live tracks are expected in ``frame``, before it is added (read-only): the
        tracks' last boxes moved as the tracker will move them (:func:`pedenv.tracking.prediction.predict_boxes`:
        the ego-yaw shift, then the image velocity when ``tracking.predict_motion``). Tracks only
        remembered after an occlusion (``tracking.memory_s``) are left out. What the detector is
        given to search for the people it would otherwise miss (:class:`pedenv.Pipeline`)."""
        tr = self.tracks.tracks
        live = ~tr.lost
        boxes = predict_boxes(tr.boxes[live], tr.velocities[live], self._yaw_shift(frame) if live.any() else 0.0,
                              self.config.tracking.predict_motion)
        return PredictedTracks(tr.ids[live].copy(), boxes, tr.hits[live].copy())

    def _view(self, frame: Frame) -> CameraView | None:
        """The camera view the tracker's ground gate and memory need; None while both are off."""
        cfg = self.config.tracking
        return CameraView.of(frame) if cfg.ground_gate > 0 or cfg.memory_s > 0 else None

    def _yaw_shift(self, frame: Frame) -> float:
        """The ego-yaw shift of the tracks' pixels (Eq. 1); none for a static camera, whose ego does not move."""
        if self._last is None or not self.config.tracking.yaw_compensation or frame.camera.static:
            return 0.0
        return yaw_shift_pixels(yaw_change(self._last.ego.yaw, frame.ego.yaw), frame.camera.hfov, frame.camera.width)

    @property
    def max_range_m(self) -> float:
        """The farthest horizontal range from the camera a position is reported at, metres:
        the locator's ``max_range_m`` (``fused.max_range_m``), else ``paper.max_distance_m``."""
        return float(getattr(self.locator, "max_range_m", self.config.paper.max_distance_m))

    def _predict(self, frame: Frame) -> None:
        f = self.tracks.filter
        if self._last is not None and len(f.x):
            f.x, f.P = kalman.predict(f.x, f.P, *self._transition(round(frame.timestamp - self._last.timestamp, 6)))
            lost = ~kalman.finite_states(f.x, f.P)  # an absurd interval overflowed: start those tracks afresh
            f.x[lost], f.P[lost], f.started[lost] = 0.0, np.eye(4), False

    def _locate(self, frame: Frame, det: Detections, rows: np.ndarray) -> Pedestrians:
        geo, cap, ground_z = FrameGeometry.of(frame), self.max_range_m, float(frame.ego.translation[2])
        meas, measured = bound_measurement(self.locator.locate(geo, rows), geo.centre_rays, geo.origin, ground_z, cap)
        cov, bias, f = meas.covariances, meas.bias_covariances, self.tracks.filter
        spread = cov if bias is None else cov + bias
        z = np.where(measured[:, None], meas.positions[:, :2], np.nan)  # unlocalised: no measurement
        was_started = f.started[rows]
        x, P, corrected = kalman.correct(f.x[rows], f.P[rows], was_started, z, cov, spread, self.config.kalman)
        f.x[rows], f.P[rows], f.started[rows] = x, P, was_started | corrected
        positions, velocities, skeleton = meas.positions, np.zeros_like(meas.positions), meas.keypoints_3d
        if self.config.kalman.enabled:
            # an unlocalised person whose track has a state is reported at its prediction
            use = corrected | was_started
            positions = np.where(use[:, None], np.column_stack([x[:, 0], x[:, 2], meas.positions[:, 2]]), positions)
            velocities = np.where(use[:, None], np.column_stack([x[:, 1], x[:, 3], np.zeros(len(x))]), velocities)
            cov = np.where(use[:, None, None], P[:, [0, 2]][:, :, [0, 2]], cov)
            skeleton = skeleton + (positions - meas.positions)[:, None, :]
        if bias is not None:
            cov = cov + bias
        positions, cov, skeleton, sources = clamp_reported(positions, cov, skeleton, meas.sources, geo.origin, cap)
        tr = self.tracks.tracks
        return Pedestrians(
            track_ids=tr.ids[rows], ages=tr.hits[rows], positions=positions, velocities=velocities,
            covariances=cov, keypoints=det.keypoints, confidences=det.confidences, boxes=det.boxes,
            keypoints_3d=skeleton, distances=np.linalg.norm(positions - geo.origin, axis=1), sources=sources)

    def _check(self, frame: Frame) -> Detections:
        if not isinstance(frame, Frame):
            raise InputError(f"update() takes a pedenv.records.Frame, got {type(frame).__name__}")
        where = f"frame {frame.index}" + (f" of scene {frame.scene!r}" if frame.scene else "")
        if frame.detections is None:
            raise InputError(f"{where}: field 'detections' is missing; run a pose backend first")
        if self._last is not None and frame.timestamp <= self._last.timestamp:
            raise InputError(f"{where}: field 'timestamp' goes backwards or repeats "
                             f"({_seconds(frame.timestamp)} s after {_seconds(self._last.timestamp)} s)")
        return frame.detections

    def _make_transition(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        return kalman.transition(dt, self.config.kalman.acceleration_std_mps2)


def _seconds(t: float) -> str:
    """A timestamp for an error line: microseconds where they are meaningful, else 7 significant
    digits (a stamp of 1e300 s is not 300 digits long)."""
    return f"{t:.6f}" if abs(t) < 1e12 else f"{t:.7g}"
