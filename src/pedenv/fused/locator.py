"""The ``fused`` locator: ground contact, triangulation and height prior, gated and fused.

Per frame and vectorized over the N tracked skeletons: each enabled cue gives an x-y
estimate with its covariance or declines with a reason; :func:`~pedenv.fused.fusion.fuse_cues`
drops a cue that disagrees and fuses the rest; the model's Kalman filter then filters the
fused measurement with its (anisotropic) covariance. ``sources`` says which cues made
each position and why the others did not, e.g. ``ground+height;triangulation:no-baseline``.
A pedestrian no cue can place gets a wide guess from its box height (``box``).
"""

from __future__ import annotations

import numpy as np

from pedenv.config import Config
from pedenv.fused.cue import (CueEstimate, across_variance, horizontal_bearing, keypoint_usable,
                              range_bearing_covariance)
from pedenv.fused.fusion import fuse_cues
from pedenv.fused.ground import ground_cue
from pedenv.fused.height import KEYPOINT_HEIGHT_FRACTION, height_cue
from pedenv.fused.history import TORSO_KEYPOINTS, TrackHistory
from pedenv.fused.triangulation import triangulation_cue
from pedenv.locator import FrameGeometry, Measurement
from pedenv.skeleton import CocoKeypoint as K

#: A pedestrian no cue can place is guessed from its box with this relative spread.
BOX_RELATIVE_STD = 0.5


def box_estimate(boxes: np.ndarray, centre_rays: np.ndarray, origin: np.ndarray, focal_px: float,
                 height_m: float) -> CueEstimate:
    """Last resort: range ``f H / box height`` along the box centre's ray, 50 % spread.

    boxes: (N, 4) pixels. centre_rays: (N, 3) unit, world. origin: (3,) world, metres.
    """
    r = np.clip(focal_px * height_m / np.maximum(boxes[:, 3] - boxes[:, 1], 1.0), 0.5, 500.0)
    bearing = horizontal_bearing(centre_rays)
    cov = range_bearing_covariance(bearing, (BOX_RELATIVE_STD * r) ** 2, across_variance(r, focal_px, 5.0, 0.5))
    return CueEstimate("box", origin[:2] + r[:, None] * bearing, cov, np.ones(len(r), bool), np.full(len(r), ""))


def describe_sources(cues: list[CueEstimate], used: np.ndarray, outvoted: np.ndarray) -> np.ndarray:
    """(N,) str: used cues joined by ``+``, then ``;cue:reason`` for each cue left out."""
    n = used.shape[0]
    head = np.full(n, "", dtype=object)
    tail = np.full(n, "", dtype=object)
    for c, cue in enumerate(cues):
        head = np.where(used[:, c], np.where(head == "", cue.name, head + "+" + cue.name), head)
        why = np.where(outvoted[:, c], "outvoted", cue.reasons)
        tail = np.where(~used[:, c] & (why != ""), tail + ";" + cue.name + ":" + why.astype(object), tail)
    return (head + tail).astype(str)


def keypoints_at_range(rays: np.ndarray, origin: np.ndarray, bearing: np.ndarray, ranges: np.ndarray) -> np.ndarray:
    """3D skeleton (N, 17, 3), world, metres: each keypoint ray (N, 17, 3) cut by the vertical
    plane facing the camera at horizontal ``ranges`` (N,) along ``bearing`` (N, 2)."""
    along = np.einsum("nkc,nc->nk", rays[..., :2], bearing)
    return origin + (ranges[:, None] / np.maximum(along, 1e-3))[..., None] * rays


class FusedLocator:
    """The ``fused`` position method (``Config.fused``), one :class:`Measurement` per frame."""

    def __init__(self, config: Config) -> None:
        self.config = config
        self.history = TrackHistory(config.fused.history_length)

    def reset(self) -> None:
        self.history.reset()

    def carry(self, previous_rows: np.ndarray) -> None:
        self.history.carry(previous_rows)

    def locate(self, geo: FrameGeometry, rows: np.ndarray) -> Measurement:
        cfg, frame, det = self.config.fused, geo.frame, geo.detections
        n, cam = len(det), frame.camera
        focal = float(cam.intrinsics[0, 0])
        rays, origin = geo.rays[:, :17], geo.origin
        usable = keypoint_usable(det.keypoints, det.confidences, cam.width, cam.height, cfg.min_keypoint_confidence)
        torso = usable[:, TORSO_KEYPOINTS]

        cues: list[CueEstimate] = []
        if "ground" in cfg.cues:
            cues.append(ground_cue(frame, det.keypoints, usable, rays, origin, cfg))
        h = self.history
        if "height" in cfg.cues:
            last = np.where(h.placed[rows], np.linalg.norm(h.positions[rows] - origin[:2], axis=1), np.nan)
            cues.append(height_cue(usable, rays, origin, focal, cfg, reference_range=last))
        if "triangulation" in cfg.cues:
            cues.append(triangulation_cue(rays[:, TORSO_KEYPOINTS], torso, origin, frame.timestamp,
                                          h.rays[rows], h.usable[rows], h.origins[rows], h.times[rows],
                                          h.filled[rows], cfg.keypoint_pixel_std / focal, cfg))
            h.push(rows, rays[:, TORSO_KEYPOINTS], torso, origin, frame.timestamp)
        fused = fuse_cues(cues, cfg.gate_probability)
        h.place(rows, fused.positions, fused.valid)
        sources = describe_sources(cues, fused.used, fused.outvoted)

        xy, cov = fused.positions, fused.covariances
        if not fused.valid.all():
            box = box_estimate(det.boxes, geo.rays[:, 17], origin, focal, cfg.person_height_mean_m)
            lost = ~fused.valid
            xy, cov = np.where(lost[:, None], box.positions, xy), np.where(lost[:, None, None], box.covariances, cov)
            sources = np.where(lost, np.char.add("box", sources), sources)
        cov = cfg.variance_scale * cov

        positions = np.column_stack([xy, road_height(frame.ego.rotation, frame.ego.translation, xy)])
        offset = xy - origin[:2]
        ranges = np.linalg.norm(offset, axis=1)
        bearing = horizontal_bearing(np.column_stack([offset, np.zeros(n)]))
        centre = positions + np.array([0.0, 0.0, KEYPOINT_HEIGHT_FRACTION[K.LEFT_HIP] * cfg.person_height_mean_m])
        distances = np.linalg.norm(centre - origin, axis=1)
        directions = (centre - origin) / np.maximum(distances, 1e-9)[:, None]
        skeleton = keypoints_at_range(rays, origin, bearing, ranges)
        return Measurement(positions, cov, distances, directions, sources, skeleton)


def road_height(rotation: np.ndarray, translation: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """World z (N,) of the vehicle's road plane (vehicle z = 0) at world ``xy`` (N, 2), metres."""
    normal = rotation[:, 2]
    return translation[2] - ((xy - translation[:2]) @ normal[:2]) / max(normal[2], 1e-6)
