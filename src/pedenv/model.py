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
from pedenv.position import estimate_positions, keypoints_on_plane, pixel_heights
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
class _TrackMemory:
    """Per-track world state, row-aligned with the tracker's table."""

    rays: np.ndarray = field(default_factory=lambda: np.zeros((0, 18, 3)))
    confidences: np.ndarray = field(default_factory=lambda: np.zeros((0, 17)))
    origins: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    seen: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    x: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    P: np.ndarray = field(default_factory=lambda: np.zeros((0, 4, 4)))

    def carry(self, previous_rows: np.ndarray) -> None:
        for name in ("rays", "confidences", "origins", "seen", "x", "P"):
            setattr(self, name, carry_rows(getattr(self, name), previous_rows))


class PedestrianEnvironmentModel:
    """The paper's pedestrian environment model, one frame at a time."""

    def __init__(self, config: Config | None = None) -> None:
        self.config = config or Config()
        self.tracker = Tracker(self.config.tracking)
        self.timer = StageTimer()
        self.reset()

    def reset(self) -> None:
        """Forget all tracks (start of a new scene); the stage timer keeps counting."""
        self.tracker.reset()
        self._memory = _TrackMemory()
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
        mem = self._memory
        mem.carry(step.previous_rows)
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
        where = f"frame {frame.index}" + (f" of scene {frame.scene!r}" if frame.scene else "")
        if not isinstance(frame, Frame):
            raise InputError(f"update() takes a pedenv.records.Frame, got {type(frame).__name__}")
        if frame.detections is None:
            raise InputError(f"{where}: field 'detections' is missing; run a pose backend first")
        if self._last is not None and frame.timestamp <= self._last.timestamp:
            raise InputError(f"{where}: field 'timestamp' goes backwards or repeats "
                             f"({frame.timestamp:.6f} s after {self._last.timestamp:.6f} s)")
        return frame.detections

    def _locate(self, frame: Frame, det, rows: np.ndarray, dt: float) -> Pedestrians:
        cfg, mem = self.config, self._memory
        cam_to_world = frame.cam_to_world
        origin = cam_to_world[:3, 3]
        world_to_cam = invert_transform(cam_to_world)
        k = frame.camera.intrinsics
        ground_z = float(frame.ego.translation[2])

        if dt > 0 and len(mem.x):
            F, Q = kalman.transition(dt, cfg.kalman.acceleration_std_mps2)
            mem.x, mem.P = kalman.predict(mem.x, mem.P, F, Q)
        if len(det) == 0:
            return Pedestrians.empty()

        centre = 0.5 * (det.boxes[:, :2] + det.boxes[:, 2:])
        rays = pixel_rays(np.concatenate([det.keypoints, centre[:, None]], axis=1), k, cam_to_world)
        has_prev = mem.seen[rows]
        est = estimate_positions(rays, det.confidences, pixel_heights(det.keypoints, det.confidences > 0), origin,
                                 mem.rays[rows], mem.confidences[rows], mem.origins[rows], has_prev,
                                 k, world_to_cam, ground_z, cfg.position)

        z = est.positions[:, :2]
        var = (cfg.kalman.measurement_std_m + cfg.kalman.measurement_std_rel * est.distances) ** 2
        fresh = ~has_prev | ~np.isfinite(mem.x[rows]).all(axis=1) | (mem.P[rows, 0, 0] == 0)
        x, P = mem.x[rows], mem.P[rows]
        if fresh.any():
            x[fresh], P[fresh] = kalman.initial_state(z[fresh], var[fresh], cfg.kalman.initial_velocity_std_mps)
        if (~fresh).any():
            x[~fresh], P[~fresh] = kalman.update(x[~fresh], P[~fresh], z[~fresh], var[~fresh])
        mem.x[rows], mem.P[rows] = x, P
        mem.rays[rows], mem.confidences[rows], mem.origins[rows], mem.seen[rows] = rays, det.confidences, origin, True

        if cfg.kalman.enabled:
            positions = np.column_stack([x[:, 0], x[:, 2], est.positions[:, 2]])
            velocities = np.column_stack([x[:, 1], x[:, 3], np.zeros(len(x))])
            cov = P[:, [0, 2]][:, :, [0, 2]]
        else:
            positions = est.positions
            velocities = np.zeros_like(positions)
            cov = var[:, None, None] * np.eye(2)
        flat = np.linalg.norm(positions[:, :2] - origin[:2], axis=1)
        ratio = flat / np.maximum(np.linalg.norm(est.positions[:, :2] - origin[:2], axis=1), 1e-6)
        skeleton = keypoints_on_plane(rays[:, :17], origin, est.directions, est.distances * ratio)
        return Pedestrians(
            track_ids=self.tracker.ids[rows], ages=self.tracker.hits[rows], positions=positions,
            velocities=velocities, covariances=cov, keypoints=det.keypoints, confidences=det.confidences,
            boxes=det.boxes, keypoints_3d=skeleton, distances=np.linalg.norm(positions - origin, axis=1),
            sources=est.sources,
        )
