"""Ground positions and the image: what the tracker needs of the camera (beyond the paper).

The tracker compares a track's Kalman-predicted ground position with a detection's box:
the prediction and its covariance are projected into the image (linearized with the
Jacobian of the ground-to-pixel map) and compared with the box's foot point
(:func:`pixel_distances`). Under that linearization this squared Mahalanobis distance is
the same as the one between the foot point cut with the road and the prediction on the
ground, with the foot point's pixel spread carried to the ground; in the image, the
spread of the road's height and a box cut by the image's edge are simple to state.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pedenv.geometry import inverse_2x2, invert_transform

if TYPE_CHECKING:
    from pedenv.records import Frame

#: Pixel spread of a box's foot point (bottom centre) on the person's ground point, as a
#: share of the box height (stance, box regression) plus a floor in pixels.
FOOT_PIXEL_STD_FRACTION, FOOT_PIXEL_STD_MIN = 0.08, 2.0
#: A box reaching this close (pixels) to the image's bottom edge is cut there: its foot
#: point says nothing about the range, so its v coordinate gets no weight.
BOTTOM_MARGIN_PX = 2.0
#: Spread of the road's height under a pedestrian against the vehicle's plane: a floor
#: (kerbs, camber) plus a grade per metre of distance (rolling roads up to about 5 %).
#: Off the plane, a ground point projects higher or lower in the image: this keeps the
#: foot point's v from vetoing the right track on a road that is not flat.
ROAD_HEIGHT_STD_M, ROAD_GRADE_STD = 0.1, 0.02
#: Relative range error of a track's position that repeats frame after frame (body height
#: prior, posture) and so is not in the filter's covariance.
RANGE_BIAS_STD = 0.08
#: Points nearer than this in front of the camera (metres) are not projected.
MIN_DEPTH_M = 0.5
#: A predicted position is projected only when it lies in front of the camera by this
#: many standard deviations of its depth (plus :data:`MIN_DEPTH_M`): the linearization
#: holds only where the whole spread is in front. A track predicted 1 m ahead with 0.4 m
#: spread (a person the car has nearly passed) projects to thousands of pixels of spread
#: below the image, which a far detection near the horizon would otherwise fall inside.
FRONT_SIGMAS = 3.0
_LOOSE = 1e8  # variance (px^2) of a coordinate that carries no information


@dataclass(frozen=True)
class CameraView:
    """The camera and road of one frame, as the tracker needs them.

    intrinsics: (3, 3). cam_to_world, world_to_cam: (4, 4), optical camera frame (x right,
    y down, z forward) to world, metres. ground_normal: (3,) unit, world; the road is the
    plane ``ground_normal . p = ground_offset`` (metres). height: image rows. timestamp: s.
    """

    intrinsics: np.ndarray
    cam_to_world: np.ndarray
    world_to_cam: np.ndarray
    ground_normal: np.ndarray
    ground_offset: float
    height: int
    timestamp: float

    @classmethod
    def of(cls, frame: Frame) -> CameraView:
        """The view of a :class:`~pedenv.records.Frame`; the road is the vehicle's plane."""
        normal = frame.ego.rotation[:, 2]
        cam_to_world = frame.cam_to_world
        return cls(frame.camera.intrinsics, cam_to_world, invert_transform(cam_to_world), normal,
                   float(normal @ frame.ego.translation), int(frame.camera.height), float(frame.timestamp))

    def ground_points(self, xy: np.ndarray) -> np.ndarray:
        """(T, 3) world points on the road under ground positions ``xy`` (T, 2), metres."""
        n = self.ground_normal
        z = (self.ground_offset - xy @ n[:2]) / n[2]
        return np.column_stack([xy, z])

    def jacobian(self, xy: np.ndarray, with_height: bool = False) -> tuple[np.ndarray, ...]:
        """Pixels (T, 2) of ground positions ``xy`` (T, 2), d pixel / d xy (T, 2, 2) and
        whether each lies at least :data:`MIN_DEPTH_M` in front of the camera (T,); with
        ``with_height`` also d pixel / d z (T, 2), the ground point raised off the road,
        the depths (T,) metres and their gradients d depth / d (x, y, z) (T, 3)."""
        R, t, K = self.world_to_cam[:3, :3], self.world_to_cam[:3, 3], self.intrinsics
        pc = self.ground_points(xy) @ R.T + t
        depth = pc[:, 2]
        front = depth > MIN_DEPTH_M
        z = np.where(front, depth, 1.0)
        pixels = (pc @ K.T)[:, :2] / z[:, None]
        n = self.ground_normal
        d_world = np.array([[1.0, 0.0], [0.0, 1.0], [-n[0] / n[2], -n[1] / n[2]]])  # (3, 2)
        d_cam = R @ d_world  # (3, 2)
        fx, fy = K[0, 0], K[1, 1]
        d_pix = np.zeros((len(xy), 2, 3))
        d_pix[:, 0, 0], d_pix[:, 0, 2] = fx / z, -fx * pc[:, 0] / z**2
        d_pix[:, 1, 1], d_pix[:, 1, 2] = fy / z, -fy * pc[:, 1] / z**2
        if with_height:
            d_depth = np.broadcast_to(np.append(d_cam[2], R[2, 2]), (len(xy), 3))
            return pixels, d_pix @ d_cam, front, d_pix @ R[:, 2], depth, d_depth
        return pixels, d_pix @ d_cam, front


def foot_points(boxes: np.ndarray) -> np.ndarray:
    """(N, 2) pixels: the bottom centre of boxes (N, 4) ``[u_min, v_min, u_max, v_max]``."""
    return np.column_stack([0.5 * (boxes[:, 0] + boxes[:, 2]), boxes[:, 3]])


def foot_covariance(boxes: np.ndarray, image_height: int) -> np.ndarray:
    """(N, 2, 2) pixels^2: spread of each box's foot point around the person's ground point;
    the v coordinate of a box cut by the image's bottom edge carries no information."""
    std = FOOT_PIXEL_STD_FRACTION * (boxes[:, 3] - boxes[:, 1]) + FOOT_PIXEL_STD_MIN
    cov = np.zeros((len(boxes), 2, 2))
    cov[:, 0, 0] = cov[:, 1, 1] = std**2
    cov[boxes[:, 3] >= image_height - 1 - BOTTOM_MARGIN_PX, 1, 1] = _LOOSE
    return cov


def project_ground(view: CameraView, xy: np.ndarray, cov_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ground positions ``xy`` (T, 2) with covariance ``cov_xy`` (T, 2, 2), world, metres,
    into the image: pixels (T, 2), covariance (T, 2, 2) pixels^2, in front (T,) bool.

    The covariance adds a range bias (:data:`RANGE_BIAS_STD`) along the line of sight and
    the road's height under the point (:data:`ROAD_HEIGHT_STD_M`, :data:`ROAD_GRADE_STD`).
    ``in front`` holds where the position lies :data:`FRONT_SIGMAS` standard deviations of
    its depth beyond :data:`MIN_DEPTH_M` in front of the camera: elsewhere the linearized
    projection means nothing (its spread is not Gaussian, part of it is behind the camera).
    """
    pixels, J, _, J_z, depth, d_depth = view.jacobian(xy, with_height=True)
    sight = xy - view.cam_to_world[:2, 3]
    r = np.linalg.norm(sight, axis=1)
    cov = cov_xy + (RANGE_BIAS_STD**2) * np.einsum("ti,tj->tij", sight, sight)
    z_var = (ROAD_HEIGHT_STD_M + ROAD_GRADE_STD * r) ** 2
    pix = J @ cov @ np.transpose(J, (0, 2, 1)) + z_var[:, None, None] * np.einsum("ti,tj->tij", J_z, J_z)
    g = d_depth[:, :2]
    depth_var = np.einsum("ti,tij,tj->t", g, cov, g) + z_var * d_depth[:, 2] ** 2
    front = depth - FRONT_SIGMAS * np.sqrt(np.maximum(depth_var, 0.0)) > MIN_DEPTH_M
    return pixels, pix, front


def pixel_distances(view: CameraView, boxes: np.ndarray, xy: np.ndarray, cov_xy: np.ndarray) -> np.ndarray:
    """(N, T) squared Mahalanobis distances of the foot points of ``boxes`` (N, 4) pixels
    from the projected ground positions ``xy`` (T, 2) (covariance ``cov_xy`` (T, 2, 2), m^2);
    inf for a position not surely in front of the camera (see :func:`project_ground`)."""
    pixels, cov, front = project_ground(view, xy, cov_xy)
    e = foot_points(boxes)[:, None, :] - pixels[None]  # (N, T, 2)
    S = cov[None] + foot_covariance(boxes, view.height)[:, None]
    d2 = np.einsum("nti,ntij,ntj->nt", e, inverse_2x2(S), e)
    return np.where(front[None], d2, np.inf)
