"""The own uncertainty of a box-bottom ground truth, from the camera's geometry and the body.

MOT17's static-camera truth (:func:`pedenv.datasets.ucmctrack.mot17_static_scene`) is each
annotated box's bottom centre cut with the estimated camera's ground: the MOTChallenge 3D /
PETS practice. That point is not the person's ground point. Two parts of the difference follow
from the image's geometry and body proportions alone, without looking at any estimate:

* **slant**: a camera looking down sees upright people slanted toward the vertical vanishing
  point (the image of the straight-down direction). Their box's bottom centre is then not under
  their feet, which lie where the line from that point through the box's centre meets the box's
  bottom edge (kept inside the box). The ground points of the two pixels differ by ``d``, counted
  as 1 sigma along ``d``. MOT17-04 (62 deg down; the point 15 px below the image): about 0.16 m
  per axis (RMS over its matches); MOT17-02 and -09 (4 and 0.8 deg down): about 1 cm.
* **foot**: the box's bottom edge is the lowest pixel of the feet, the near end of the nearer
  foot; the person's ground point may lie anywhere within a foot's length of it along the ray
  (:data:`FOOT_LENGTH_FRACTION` of body height), counted as uniform: sigma ``L / sqrt(12)``.

The annotation's own pixel noise is left out: it cannot be measured on these samples. Their
boxes are interpolated between key frames: the box bottoms' second differences over the 4-8
consecutive frames are exactly 0 for 68-75 % of them and 0.2 px RMS over all, which bounds the
smoothness of the interpolation, not the accuracy of the key frames.
"""

from __future__ import annotations

import numpy as np

from pedenv.records import Camera

#: Foot length over body height (Winter, *Biomechanics and Motor Control of Human Movement*,
#: segment lengths: 0.152 H): 0.26 m for the fused method's 1.72 m person.
FOOT_LENGTH_FRACTION = 0.152
#: Body height (m) the foot length is taken of: ``fused.person_height_mean_m``'s default.
BODY_HEIGHT_M = 1.72
#: Below this downward component of the camera's view of straight down (unit vector, camera
#: frame) the vertical vanishing point lies beyond the image's horizon: no slant.
MIN_DOWN_DEPTH = 1e-6


def slant_feet(camera: Camera, boxes: np.ndarray) -> np.ndarray:
    """(N, 2) pixels: where the feet of the upright people boxed by ``boxes`` (N, 4) px lie on
    the boxes' bottom edge: on the line from the vertical vanishing point through each box's
    centre (module notes); the bottom centre for a camera that does not look down."""
    bottom = np.column_stack([0.5 * (boxes[:, 0] + boxes[:, 2]), boxes[:, 3]])
    down = camera.cam_to_vehicle[:3, :3].T @ np.array([0.0, 0.0, -1.0])  # camera frame
    if down[2] <= MIN_DOWN_DEPTH:
        return bottom
    vp = (camera.intrinsics @ down)[:2] / (camera.intrinsics @ down)[2]
    centre_v = 0.5 * (boxes[:, 1] + boxes[:, 3])
    gap = np.where(np.abs(vp[1] - centre_v) > 1.0, vp[1] - centre_v, np.inf)  # px, centre row to the point
    u = bottom[:, 0] + (boxes[:, 3] - centre_v) * (vp[0] - bottom[:, 0]) / gap
    return np.column_stack([np.clip(u, boxes[:, 0], boxes[:, 2]), boxes[:, 3]])


def truth_covariances(camera: Camera, boxes: np.ndarray, truth_xy: np.ndarray) -> np.ndarray:
    """(N, 2, 2) m^2, the box-bottom truths' own covariances (module notes), ground x-y.

    camera: the static camera (:class:`pedenv.records.Camera`, its vehicle frame the world: the
    ego at the identity). boxes: (N, 4) px, the truths' boxes. truth_xy: (N, 2) metres, their
    ground points (each bottom centre's cut with the ground).
    """
    from pedenv.datasets.ucmctrack import ground_points

    feet, _ = ground_points(camera, slant_feet(camera, boxes))
    d = feet[:, :2] - truth_xy
    ray = truth_xy - camera.cam_to_vehicle[:2, 3]
    ray /= np.maximum(np.linalg.norm(ray, axis=1, keepdims=True), 1e-9)
    foot = (FOOT_LENGTH_FRACTION * BODY_HEIGHT_M) ** 2 / 12.0
    return d[:, :, None] * d[:, None, :] + foot * ray[:, :, None] * ray[:, None, :]
