"""What every position method ("locator") shares: the frame's geometry, the measurement
it returns and the protocol it follows.

A locator turns the tracked skeletons of a frame into position *measurements* with a
covariance; the model's Kalman filter then filters them over time. Its memory of past
observations is a :class:`~pedenv.tracking.table.ColumnGroup` in the model's track table,
so the tracker carries it with every other per-track column.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from pedenv.errors import InputError
from pedenv.geometry import invert_transform, pixel_rays
from pedenv.records import Detections, Frame
from pedenv.tracking.table import ColumnGroup


@dataclass(frozen=True)
class FrameGeometry:
    """What every locator needs of the frame's camera, computed once per frame.

    rays: (N, 17, 3) unit viewing rays of the keypoints, world frame.
    centre_rays: (N, 3) unit viewing rays of the detections' box centres, world frame.
    origin: (3,) camera centre, world, metres. cam_to_world, world_to_cam: (4, 4).
    """

    frame: Frame
    detections: Detections
    rays: np.ndarray
    centre_rays: np.ndarray
    origin: np.ndarray
    cam_to_world: np.ndarray
    world_to_cam: np.ndarray

    @classmethod
    def of(cls, frame: Frame) -> FrameGeometry:
        """The geometry of ``frame`` and its detections (which must be set)."""
        det, cam_to_world = frame.detections, frame.cam_to_world
        if det is None:
            raise InputError(f"frame {frame.index}: no detections to locate (run a pose backend first)")
        centre = 0.5 * (det.boxes[:, :2] + det.boxes[:, 2:])
        rays = pixel_rays(np.concatenate([det.keypoints, centre[:, None]], axis=1), frame.camera.intrinsics,
                          cam_to_world)
        return cls(frame, det, rays[:, :17], rays[:, 17], cam_to_world[:3, 3], cam_to_world,
                   invert_transform(cam_to_world))


@dataclass(frozen=True)
class Measurement:
    """Position measurements of the N pedestrians of one frame.

    positions: (N, 3) world frame, metres, ground point. covariances: (N, 2, 2) m^2 of x-y.
    sources: (N,) str, which cues produced the position. keypoints_3d: (N, 17, 3) world.
    bias_covariances: optional (N, 2, 2) m^2, the part of the error that repeats from frame
        to frame for the same person (e.g. their unknown body height). The filter cannot
        average it away, so it is left out of the filter and added to the covariance the
        state reports; ``covariances`` is then the frame-to-frame part alone.
    """

    positions: np.ndarray
    covariances: np.ndarray
    sources: np.ndarray
    keypoints_3d: np.ndarray
    bias_covariances: np.ndarray | None = None


class Locator(Protocol):
    """A position method: its per-track memory and the per-frame estimate.

    ``columns`` is the locator's group of per-track columns (row-aligned with the track
    table, carried by the tracker); ``locate`` reads and writes the rows ``rows`` (N,)
    of the frame's N detections. A locator with a true attribute ``requires_keypoints``
    is never given a person without a seen keypoint (the model leaves those out).
    """

    columns: ColumnGroup

    def locate(self, geo: FrameGeometry, rows: np.ndarray) -> Measurement: ...
