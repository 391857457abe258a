"""PedestrianEnvironmentModel: detections + ego pose in, environment state out, per frame.

    model = PedestrianEnvironmentModel(Config())
    for frame in frames:           # frames carry detections (see pedenv.pose)
        state = model.update(frame)

Per frame: ego-yaw compensation and association in the image (``pedenv.tracker``),
the world position of every tracked skeleton (``pedenv.position``), and a
constant-velocity Kalman filter on the ground plane (``pedenv.kalman``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from pedenv import kalman
from pedenv.config import Config
from pedenv.egomotion import yaw_change, yaw_shift_pixels
from pedenv.errors import InputError
from pedenv.geometry import invert_transform, pixel_rays
from pedenv.locator import FrameGeometry, create_locator
from pedenv.records import Frame
from pedenv.state import EnvironmentState, Pedestrians
from pedenv.tracker import Tracker, carry_rows


@dataclass
class StageTimer:
    """Accumulated wall time of the stages: tracking per frame, position per pedestrian."""

    tracking_s: float = 0.0
    frames: int = 0
    position_s: float = 0.0
    pedestrians: int = 0

    def per_stage_ms(self) -> dict:
        return {
            "tracking_per_frame": 1e3 * self.tracking_s / max(self.frames, 1),
            "position_per_pedestrian": 1e3 * self.position_s / max(self.pedestrians, 1),
        }


@dataclass
class _FilterMemory:
    """Kalman state per track, row-aligned with the tracker's table."""

    x: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    P: np.ndarray = field(default_factory=lambda: np.zeros((0, 4, 4)))
    started: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    def carry(self, previous_rows: np.ndarray) -> None:
        self.x = carry_rows(self.x, previous_rows)
        self.P = carry_rows(self.P, previous_rows)
        self.started = carry_rows(self.started, previous_rows, fill=False)


class PedestrianEnvironmentModel:
    """The paper's pedestrian environment model, one frame at a time."""

    def __init__(self, config: Config | None = None) -> None:
        self.config = config or Config()
        self.tracker = Tracker(self.config.tracking)
        self.locator = create_locator(self.config)
        self.timer = StageTimer()
        self.reset()

    def reset(self) -> None:
        """Forget all tracks (start of a new scene); the stage timer keeps counting."""
        self.tracker.reset()
        self.locator.reset()
        self._filter = _FilterMemory()
        self._transitions: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self._last: Frame | None = None

    def update(self, frame: Frame) -> EnvironmentState:
        """Add one frame and return the environment model at its timestamp.

        ``frame.detections`` must be set (by a pose backend); timestamps must increase.
        """
        det = self._check(frame)
        dt = 0.0 if self._last is None else frame.timestamp - self._last.timestamp

        t0 = time.perf_counter()
        shift = 0.0
        if self._last is not None and self.config.tracking.yaw_compensation:
            shift = yaw_shift_pixels(yaw_change(self._last.ego.yaw, frame.ego.yaw), frame.camera.hfov, frame.camera.width)
        step = self.tracker.update(det.boxes, det.keypoints, shift)
        self._filter.carry(step.previous_rows)
        self.locator.carry(step.previous_rows)
        t1 = time.perf_counter()

        peds = self._locate(frame, det, step.detection_rows, dt)
        t2 = time.perf_counter()
        self.timer.tracking_s += t1 - t0
        self.timer.frames += 1
        self.timer.position_s += t2 - t1
        self.timer.pedestrians += len(det)
        self._last = frame
        return EnvironmentState(frame.index, frame.timestamp, frame.ego, peds, frame.scene)

    def _check(self, frame: Frame):
        if not isinstance(frame, Frame):
            raise InputError(f"update() takes a pedenv.records.Frame, got {type(frame).__name__}")
        where = f"frame {frame.index}" + (f" of scene {frame.scene!r}" if frame.scene else "")
        if frame.detections is None:
            raise InputError(f"{where}: field 'detections' is missing; run a pose backend first")
        if self._last is not None and frame.timestamp <= self._last.timestamp:
            raise InputError(f"{where}: field 'timestamp' goes backwards or repeats "
                             f"({frame.timestamp:.6f} s after {self._last.timestamp:.6f} s)")
        return frame.detections

    def _locate(self, frame: Frame, det, rows: np.ndarray, dt: float) -> Pedestrians:
        cfg, mem = self.config, self._filter
        if dt > 0 and len(mem.x):
            mem.x, mem.P = kalman.predict(mem.x, mem.P, *self._transition(dt))
        if len(det) == 0:
            return Pedestrians.empty()
        cam_to_world = frame.cam_to_world
        origin = cam_to_world[:3, 3]
        centre = 0.5 * (det.boxes[:, :2] + det.boxes[:, 2:])
        rays = pixel_rays(np.concatenate([det.keypoints, centre[:, None]], axis=1), frame.camera.intrinsics,
                          cam_to_world)
        geo = FrameGeometry(frame, det, rays, origin, cam_to_world, invert_transform(cam_to_world))
        meas = self.locator.locate(geo, rows)

        z = meas.positions[:, :2]
        x, P = mem.x[rows], mem.P[rows]
        fresh = ~mem.started[rows]
        if cfg.kalman.restart_gate > 0 and (~fresh).any():
            spread = meas.covariances if meas.bias_covariances is None else meas.covariances + meas.bias_covariances
            fresh |= ~fresh & (kalman.innovation_distance(x, P, z, spread) > cfg.kalman.restart_gate)
        if fresh.any():
            x[fresh], P[fresh] = kalman.initial_state(z[fresh], meas.covariances[fresh],
                                                      cfg.kalman.initial_velocity_std_mps)
        if (~fresh).any():
            x[~fresh], P[~fresh] = kalman.update(x[~fresh], P[~fresh], z[~fresh], meas.covariances[~fresh])
        mem.x[rows], mem.P[rows], mem.started[rows] = x, P, True

        if cfg.kalman.enabled:
            positions = np.column_stack([x[:, 0], x[:, 2], meas.positions[:, 2]])
            velocities = np.column_stack([x[:, 1], x[:, 3], np.zeros(len(x))])
            cov = P[:, [0, 2]][:, :, [0, 2]]
            skeleton = meas.keypoints_3d + (positions - meas.positions)[:, None, :]
        else:
            positions, velocities, cov, skeleton = meas.positions, np.zeros_like(meas.positions), meas.covariances, meas.keypoints_3d
        if meas.bias_covariances is not None:
            cov = cov + meas.bias_covariances
        return Pedestrians(
            track_ids=self.tracker.ids[rows], ages=self.tracker.hits[rows], positions=positions,
            velocities=velocities, covariances=cov, keypoints=det.keypoints, confidences=det.confidences,
            boxes=det.boxes, keypoints_3d=skeleton, distances=np.linalg.norm(positions - origin, axis=1),
            sources=meas.sources,
        )

    def _transition(self, dt: float):
        key = round(dt, 6)
        if key not in self._transitions:
            self._transitions[key] = kalman.transition(dt, self.config.kalman.acceleration_std_mps2)
        return self._transitions[key]
