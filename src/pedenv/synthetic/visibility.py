"""Which pedestrians a camera sees: projection, field of view, size and occlusion rules.

Like the paper's CARLA labels (Sec. IV-A), only pedestrians the camera really sees are
kept: in front of the camera, within the distance range, with most of the projected
skeleton inside the image, tall enough in pixels, and not mostly hidden behind nearer
pedestrians. Keypoints outside the image or inside a nearer pedestrian's box are
marked not visible.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.geometry import invert_transform, project
from pedenv.records import Camera
from pedenv.validation import check_below, check_fields, number

_GRID = (np.arange(8) + 0.5) / 8.0  # sample points across a box, per axis


@dataclass(frozen=True)
class VisibilityRules:
    """Thresholds deciding which pedestrians enter a frame's ground truth.

    min_distance_m, max_distance_m: horizontal distance from the camera to the ground
        point (the scenes place people 5 to 150 m away).
    min_height_px: the projected skeleton must be at least this tall (keypoint extent).
        Raising it drops far pedestrians.
    min_inside_fraction: share of the 17 keypoints that must fall inside the image.
    max_occluded_fraction: a pedestrian whose box is covered by more than this share
        by nearer pedestrians' boxes is hidden. Lowering it drops more people in crowds.
    min_depth_m: every keypoint must be at least this far in front of the camera.

    Checked by :mod:`pedenv.validation`: distances up to 1000 m, heights up to 10000 px.
    """

    min_distance_m: float = number(5.0, 0.0, 1000.0)
    max_distance_m: float = number(150.0, 0.0, 1000.0)
    min_height_px: float = number(15.0, 0.0, 10000.0)
    min_inside_fraction: float = number(0.6, 0.0, 1.0)
    max_occluded_fraction: float = number(0.5, 0.0, 1.0)
    min_depth_m: float = number(0.5, 0.0, 100.0, low_open=True)

    def __post_init__(self) -> None:
        check_fields("visibility", self)
        check_below("visibility.min_distance_m", self.min_distance_m, "visibility.max_distance_m", self.max_distance_m)


@dataclass(frozen=True)
class Visibility:
    """What one camera sees of N pedestrians.

    keep: (N,) bool, the pedestrian belongs to the ground truth.
    keypoints: (N, 17, 2) float, pixels: exact projections (unclipped; NaN for people with
        a keypoint behind the camera, who are never kept).
    visible: (N, 17) bool, keypoint inside the image and not behind a nearer person.
    boxes: (N, 4) float, pixels: box around the 17 projections, clipped to the image.
    """

    keep: np.ndarray
    keypoints: np.ndarray
    visible: np.ndarray
    boxes: np.ndarray


def box_coverage(boxes: np.ndarray, occluders: np.ndarray, nearer: np.ndarray) -> np.ndarray:
    """Share of each box covered by the union of the boxes in front of it.

    boxes: (N, 4) pixels. occluders: (M, 4) pixels. nearer: (N, M) bool, occluder j is
    in front of person i. Returns (N,) covered fraction in [0, 1], estimated on an 8x8
    grid of points per box.
    """
    u = boxes[:, 0:1] + _GRID * (boxes[:, 2:3] - boxes[:, 0:1])  # (N, 8)
    v = boxes[:, 1:2] + _GRID * (boxes[:, 3:4] - boxes[:, 1:2])
    pu = np.repeat(u, _GRID.size, axis=1)[:, :, None]  # (N, 64, 1)
    pv = np.tile(v, (1, _GRID.size))[:, :, None]
    inside = ((pu >= occluders[:, 0]) & (pu <= occluders[:, 2]) & (pv >= occluders[:, 1]) & (pv <= occluders[:, 3]))
    covered = (inside & nearer[:, None, :]).any(axis=2)
    return covered.mean(axis=1)


def points_covered(points: np.ndarray, occluders: np.ndarray, nearer: np.ndarray) -> np.ndarray:
    """points: (N, P, 2) pixels; occluders: (M, 4); nearer: (N, M) -> (N, P) bool inside a nearer box."""
    pu, pv = points[..., 0:1], points[..., 1:2]
    inside = (pu >= occluders[:, 0]) & (pu <= occluders[:, 2]) & (pv >= occluders[:, 1]) & (pv <= occluders[:, 3])
    return (inside & nearer[:, None, :]).any(axis=2)


def visible_pedestrians(keypoints_3d: np.ndarray, ground: np.ndarray, camera: Camera, cam_to_world: np.ndarray,
                        rules: VisibilityRules = VisibilityRules()) -> Visibility:
    """Apply ``rules`` to N pedestrians seen by ``camera``.

    keypoints_3d: (N, 17, 3) world frame, metres. ground: (N, 3) world frame, metres.
    cam_to_world: (4, 4) optical camera frame -> world frame.
    """
    n = keypoints_3d.shape[0]
    pixels, depth = project(keypoints_3d, camera.intrinsics, invert_transform(cam_to_world))
    in_front = (depth > rules.min_depth_m).all(axis=1)
    w, h = camera.width, camera.height
    inside = (
        (pixels[..., 0] >= 0) & (pixels[..., 0] < w) & (pixels[..., 1] >= 0) & (pixels[..., 1] < h) & in_front[:, None]
    )
    distance = np.linalg.norm(ground[:, :2] - cam_to_world[:2, 3], axis=1)
    raw = np.concatenate([pixels.min(axis=1), pixels.max(axis=1)], axis=1)
    boxes = np.clip(raw, 0.0, [w, h, w, h])
    tall = (raw[:, 3] - raw[:, 1]) >= rules.min_height_px
    candidate = (in_front & tall & (distance >= rules.min_distance_m) & (distance <= rules.max_distance_m)
                 & (inside.mean(axis=1) >= rules.min_inside_fraction))
    # every person in front with some part in the image can hide the ones behind
    occ = np.flatnonzero(in_front & inside.any(axis=1))
    cand = np.flatnonzero(candidate)
    centre_depth = depth.mean(axis=1)
    nearer = centre_depth[occ][None, :] < centre_depth[cand][:, None] - 0.3  # (C, O)
    keep = np.zeros(n, bool)
    keep[cand] = box_coverage(boxes[cand], boxes[occ], nearer) <= rules.max_occluded_fraction
    visible = inside.copy()
    visible[cand] &= ~points_covered(pixels[cand], boxes[occ], nearer)
    return Visibility(keep, np.where(in_front[:, None, None], pixels, np.nan), visible, boxes)
