"""Position methods ("locators"): per-track memory plus one call per frame.

A locator turns the tracked skeletons of a frame into position *measurements* with a
covariance; the model then filters them over time. ``paper`` is the paper's method
(``pedenv.position``); others register in :data:`LOCATORS`.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from pedenv.config import Config
from pedenv.position import estimate_positions, keypoints_on_plane, pixel_heights
from pedenv.records import Detections, Frame
from pedenv.tracker import carry_rows


@dataclass(frozen=True)
class FrameGeometry:
    """What every locator needs of the frame's camera, computed once per frame.

    rays: (N, 18, 3) unit rays, world frame: the 17 keypoints, then the box centre.
    origin: (3,) camera centre, world. world_to_cam: (4, 4). cam_to_world: (4, 4).
    """

    frame: Frame
    detections: Detections
    rays: np.ndarray
    origin: np.ndarray
    cam_to_world: np.ndarray
    world_to_cam: np.ndarray


@dataclass(frozen=True)
class Measurement:
    """Position measurements of the N pedestrians of one frame.

    positions: (N, 3) world frame, metres, ground point. covariances: (N, 2, 2) m^2 of x-y.
    distances: (N,) metres camera to body centre. directions: (N, 3) unit, world.
    sources: (N,) str, which cues produced the position. keypoints_3d: (N, 17, 3) world.
    bias_covariances: optional (N, 2, 2) m^2, the part of the error that repeats from frame
        to frame for the same person (e.g. their unknown body height). The filter cannot
        average it away, so it is left out of the filter and added to the covariance the
        state reports; ``covariances`` is then the frame-to-frame part alone.
    """

    positions: np.ndarray
    covariances: np.ndarray
    distances: np.ndarray
    directions: np.ndarray
    sources: np.ndarray
    keypoints_3d: np.ndarray
    bias_covariances: np.ndarray | None = None


class Locator(Protocol):
    """Per-track memory row-aligned with the tracker, and the per-frame estimate."""

    def reset(self) -> None: ...

    def carry(self, previous_rows: np.ndarray) -> None: ...

    def locate(self, geo: FrameGeometry, rows: np.ndarray) -> Measurement: ...


class PaperLocator:
    """The paper's two-frame intersection with height refinement (``pedenv.position``).

    Its measurement covariance is isotropic: ``(measurement_std_m + measurement_std_rel *
    distance)^2`` per axis (``KalmanConfig``); the paper gives none.
    """

    def __init__(self, config: Config) -> None:
        self.config = config
        self.reset()

    def reset(self) -> None:
        self.rays = np.zeros((0, 18, 3))
        self.confidences = np.zeros((0, 17))
        self.origins = np.zeros((0, 3))
        self.seen = np.zeros(0, bool)

    def carry(self, previous_rows: np.ndarray) -> None:
        for name in ("rays", "confidences", "origins", "seen"):
            setattr(self, name, carry_rows(getattr(self, name), previous_rows))

    def locate(self, geo: FrameGeometry, rows: np.ndarray) -> Measurement:
        det, frame = geo.detections, geo.frame
        est = estimate_positions(
            geo.rays, det.confidences, pixel_heights(det.keypoints, det.confidences > 0), geo.origin,
            self.rays[rows], self.confidences[rows], self.origins[rows], self.seen[rows],
            frame.camera.intrinsics, geo.world_to_cam, float(frame.ego.translation[2]), self.config.position)
        self.rays[rows], self.confidences[rows], self.origins[rows], self.seen[rows] = (
            geo.rays, det.confidences, geo.origin, True)
        k = self.config.kalman
        var = (k.measurement_std_m + k.measurement_std_rel * est.distances) ** 2
        skeleton = keypoints_on_plane(geo.rays[:, :17], geo.origin, est.directions, est.distances)
        return Measurement(est.positions, var[:, None, None] * np.eye(2), est.distances, est.directions,
                           est.sources, skeleton)


#: Method name -> "module:class"; each class takes the whole Config.
LOCATORS: dict[str, str] = {
    "paper": "pedenv.locator:PaperLocator",
    "fused": "pedenv.fused.locator:FusedLocator",
}


def create_locator(config: Config) -> Locator:
    """The locator of ``config.position.method``."""
    name = config.position.method
    if name not in LOCATORS:
        raise ValueError(f"unknown position method {name!r}; valid: {', '.join(LOCATORS)}")
    module, cls = LOCATORS[name].split(":")
    return getattr(importlib.import_module(module), cls)(config)
