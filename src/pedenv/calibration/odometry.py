"""The camera's motion from its images (visual odometry) for a vehicle without ego poses.

Between two frames: corners (``cv2.goodFeaturesToTrack``) outside the people's boxes, tracked with
pyramidal Lucas-Kanade forth and back, the essential matrix with RANSAC (``cv2.findEssentialMat``)
gives the rotation and the direction of travel; the metric length of the step comes from the road:
the tracked points on the road in front (below the horizon, in the lower middle of the image) are
triangulated with a unit step, and the step is scaled so that they lie the camera's height below it.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from pedenv.errors import InputError

#: Corners per frame, their least quality and spacing (pixels) (OpenCV's usual settings for tracking).
MAX_CORNERS, CORNER_QUALITY, CORNER_SPACING_PX = 1500, 0.01, 8
#: Largest forth-and-back disagreement of a tracked corner, pixels.
MAX_BACK_ERROR_PX = 1.0
#: RANSAC threshold of the essential matrix, pixels.
RANSAC_THRESHOLD_PX = 1.0
#: Fewest inlier points for a step, and fewest road points for its length.
MIN_INLIERS, MIN_ROAD_POINTS = 30, 10
#: The road region: rows below the horizon by this share of the image height, columns within
#: this share of the image width of its centre.
ROAD_BELOW_HORIZON, ROAD_HALF_WIDTH = 0.08, 0.25
#: Largest angle between the fitted road plane and the mounting's level, degrees (a slope and
#: the mounting's error together); beyond it the road points' median depth is used instead.
MAX_ROAD_SLOPE_DEG = 10.0
#: A step whose median image motion is under this many pixels is taken as standing still.
STILL_MOTION_PX = 0.5


@dataclass(frozen=True)
class Step:
    """One frame-to-frame motion of the camera: ``rotation`` (3, 3) and ``translation`` (3,) metres
    mapping points of the new camera frame into the old one (optical axes), ``road_points`` used."""

    rotation: np.ndarray
    translation: np.ndarray
    road_points: int


def _tracked(prev: np.ndarray, new: np.ndarray, mask: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    corners = cv2.goodFeaturesToTrack(prev, MAX_CORNERS, CORNER_QUALITY, CORNER_SPACING_PX, mask=mask)
    if corners is None:
        return np.zeros((0, 2)), np.zeros((0, 2))
    ahead, ok, _ = cv2.calcOpticalFlowPyrLK(prev, new, corners, None)
    back, ok_back, _ = cv2.calcOpticalFlowPyrLK(new, prev, ahead, None)
    good = (ok[:, 0] == 1) & (ok_back[:, 0] == 1) & (np.linalg.norm(back - corners, axis=2)[:, 0] < MAX_BACK_ERROR_PX)
    return corners[good, 0].astype(float), ahead[good, 0].astype(float)


def people_mask(shape: tuple[int, ...], boxes: np.ndarray) -> np.ndarray:
    """(H, W) uint8 mask, 0 inside the people's (or other movers') boxes (N, 4) pixels, 255 elsewhere."""
    mask = np.full(shape[:2], 255, np.uint8)
    for u0, v0, u1, v1 in np.asarray(boxes, float).reshape(-1, 4):
        mask[max(int(v0), 0):max(int(np.ceil(v1)), 0), max(int(u0), 0):max(int(np.ceil(u1)), 0)] = 0
    return mask


def step(prev: np.ndarray, new: np.ndarray, k: np.ndarray, up: np.ndarray, height_m: float,
         boxes: np.ndarray | None = None) -> Step:
    """The camera's motion from grey image ``prev`` to ``new`` ((H, W) uint8). k: (3, 3) pixels.
    up: (3,) the world's up in the camera's optical frame. height_m: the camera above the road.
    boxes: (N, 4) pixels of movers left out. Raises InputError when the images give no motion."""
    mask = None if boxes is None or not len(boxes) else people_mask(prev.shape, boxes)
    p0, p1 = _tracked(prev, new, mask)
    if len(p0) < MIN_INLIERS:
        raise InputError(f"too few corners tracked between the frames ({len(p0)}): the images are too dark, "
                         "blurred or plain for visual odometry; give --ego-poses")
    on_road = _road_region(p0, k, up, prev.shape)
    flow = np.linalg.norm(p1 - p0, axis=1)
    if np.median(flow[on_road] if on_road.sum() >= MIN_ROAD_POINTS else flow) < STILL_MOTION_PX:
        return Step(np.eye(3), np.zeros(3), 0)  # the road in front does not move: standing still
    e, inliers = cv2.findEssentialMat(p0, p1, k, cv2.RANSAC, 0.999, RANSAC_THRESHOLD_PX)
    if e is None or e.shape != (3, 3):
        raise InputError("no essential matrix between the frames; give --ego-poses")
    count, r, t, inliers = cv2.recoverPose(e, p0, p1, k, mask=inliers)
    if count < MIN_INLIERS:
        raise InputError(f"too few corners agree on one motion ({count}); give --ego-poses")
    keep = inliers[:, 0] > 0
    scale, road = _road_scale(p0[keep], p1[keep], r, t[:, 0], k, up, height_m, prev.shape)
    # recoverPose: x_new = r @ x_old + t; the new camera in the old frame: rotation r.T, position -r.T @ t
    return Step(r.T, -r.T @ t[:, 0] * scale, road)


def _road_region(points: np.ndarray, k: np.ndarray, up: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """(N,) bool: the pixels (N, 2) in the road region, below the horizon in the lower middle."""
    level = k @ np.cross(up, np.cross([0.0, 0.0, 1.0], up))  # the forward-level direction's image
    v_h = level[1] / level[2] if abs(level[2]) > 1e-9 else 0.0
    h, w = shape[:2]
    return (points[:, 1] > v_h + ROAD_BELOW_HORIZON * h) & (np.abs(points[:, 0] - k[0, 2]) < ROAD_HALF_WIDTH * w)


def _road_scale(p0: np.ndarray, p1: np.ndarray, r: np.ndarray, t: np.ndarray, k: np.ndarray, up: np.ndarray,
                height_m: float, shape: tuple[int, ...]) -> tuple[float, int]:
    """The step's length in metres per unit of ``t``: road points triangulated with a unit step lie
    a median ``d`` below the camera, and the camera is ``height_m`` above the road."""
    road = _road_region(p0, k, up, shape)
    if road.sum() < MIN_ROAD_POINTS:
        raise InputError(f"too few tracked points on the road in front ({int(road.sum())}) to give the step's "
                         "length; give --ego-poses")
    points = cv2.triangulatePoints(k @ np.eye(3, 4), k @ np.hstack([r, t[:, None]]), p0[road].T, p1[road].T)
    x = (points[:3] / points[3]).T
    x = x[(x[:, 2] > 0) & (-(x @ up) > 0)]  # ahead of and below the camera
    if len(x) < MIN_ROAD_POINTS:
        raise InputError("the road points do not lie below the camera; give --ego-poses")
    return height_m / _plane_distance(x, up), int(len(x))


def _plane_distance(points: np.ndarray, up: np.ndarray) -> float:
    """The camera's distance (units of the points) from the plane fitted to ``points`` (N, 3):
    least squares, then again without the points farther from it than 3 times the median."""
    keep = np.ones(len(points), bool)
    for _ in range(2):
        centre = points[keep].mean(axis=0)
        normal = np.linalg.svd(points[keep] - centre)[2][-1]
        normal = normal if normal @ up > 0 else -normal
        miss = np.abs((points - centre) @ normal)
        keep = miss <= 3.0 * np.median(miss) + 1e-12
        if keep.sum() < MIN_ROAD_POINTS:
            break
    if normal @ up < np.cos(np.radians(MAX_ROAD_SLOPE_DEG)):
        return float(np.median(-(points @ up)))  # no plane like a road: the points' median depth
    return float(-(centre @ normal))


def trajectory(images: Iterable[np.ndarray], k: np.ndarray, cam_to_vehicle: np.ndarray,
               boxes: Iterable[np.ndarray] | None = None) -> np.ndarray:
    """(T, 4, 4) vehicle -> world poses (the first frame's vehicle frame is the world) of the RGB
    ``images`` (H, W, 3) uint8, seen by a camera ``k`` (3, 3) pixels mounted at ``cam_to_vehicle``
    (4, 4; its height is the road's distance); ``boxes``: per frame (N, 4) px of movers left out."""
    rotation = cam_to_vehicle[:3, :3]
    up = rotation.T @ np.array([0.0, 0.0, 1.0])
    height = float(cam_to_vehicle[2, 3])
    camera = np.eye(4)  # camera frame of frame i -> camera frame of frame 0
    poses, previous = [np.eye(4)], None
    movers = iter(boxes) if boxes is not None else None
    for image in images:
        grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
        box = next(movers) if movers is not None else None
        if previous is not None:
            s = step(previous[0], grey, k, up, height, previous[1])
            move = np.eye(4)
            move[:3, :3], move[:3, 3] = s.rotation, s.translation
            camera = camera @ move
            poses.append(cam_to_vehicle @ camera @ np.linalg.inv(cam_to_vehicle))
        previous = (grey, box)
    return np.array(poses)


def write_poses(path: Path, timestamps: np.ndarray, poses: np.ndarray) -> Path:
    """``poses`` (T, 4, 4) vehicle -> world at ``timestamps`` (T,) seconds as an ``--ego-poses`` CSV
    (timestamp,x,y,z,qw,qx,qy,qz)."""
    from scipy.spatial.transform import Rotation

    quats = Rotation.from_matrix(poses[:, :3, :3]).as_quat()  # x, y, z, w
    lines = ["timestamp,x,y,z,qw,qx,qy,qz"]
    for t, pose, q in zip(timestamps, poses, quats):
        lines.append(",".join(f"{v:.6f}" for v in (t, *pose[:3, 3], q[3], q[0], q[1], q[2])))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
