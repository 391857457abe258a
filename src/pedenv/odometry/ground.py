"""The road under the camera: which pixels see it, and the metric length of a step from it (pure functions).

Frames: the camera frame is optical (x right, y down, z forward); ``cam_to_vehicle`` (4, 4)
maps it to the vehicle frame (x forward, y left, z up, origin on the road under the vehicle),
so the camera's height over the road is ``cam_to_vehicle[2, 3]``.
"""

from __future__ import annotations

import cv2
import numpy as np

#: The road patch whose tracks scale a step: from :data:`ROAD_NEAR_M` to :data:`ROAD_FAR_M`
#: ahead of the vehicle origin and within :data:`ROAD_HALF_WIDTH_M` of its centre line, metres
#: (the vehicle's own lane, where parked cars are not; beyond about 25 m the road's flow at 10 Hz
#: and 9 m/s is a few pixels, too little to weigh).
ROAD_NEAR_M = 3.0
ROAD_FAR_M = 25.0
ROAD_HALF_WIDTH_M = 2.0
#: Fewest road tracks (after the essential matrix's RANSAC) for a step's scale; with fewer the
#: step's length is taken from its neighbours' speeds (:func:`pedenv.odometry.motion.fill_lengths`).
MIN_ROAD_POINTS = 15
#: The road plane's fit: a track is on it when the plane's homography puts it within this many
#: pixels of where it was tracked (1.5 px: the essential matrix's tolerance plus the road's
#: fainter corners); the fit minimises the pixels' truncated squared error over the plane's
#: distance and its pitch, within :data:`MAX_ROAD_TILT_DEG` of the calibrated pitch (the car
#: pitching under braking, a pitch slightly off).
ROAD_TOLERANCE_PX = 1.5
MAX_ROAD_TILT_DEG = 3.0
#: The searched distances to the plane, in step lengths (0.01 to 100: a step of 1.65 m / 100 to 165 m
#: for a camera 1.65 m up), and the grids (distances, pitches) of the coarse search (7.7 % and 0.5 deg
#: apart) and of the fine one around its best (0.19 % and 0.05 deg apart).
PLANE_DISTANCES = (0.01, 100.0)
COARSE_STEPS = (120, 13)
FINE_STEPS = (81, 21)


def camera_down(cam_to_vehicle: np.ndarray) -> np.ndarray:
    """(3,) unit vector, camera frame: the vehicle's down direction (the road's normal, pointing at it)."""
    return -np.asarray(cam_to_vehicle, dtype=np.float64)[:3, :3].T @ np.array([0.0, 0.0, 1.0])


def on_road(pixels: np.ndarray, intrinsics: np.ndarray, cam_to_vehicle: np.ndarray) -> np.ndarray:
    """(N,) bool: whether each pixel of ``pixels`` (N, 2) sees the road patch ahead (above) when
    the road is the plane z = 0 of the vehicle frame."""
    if len(pixels) == 0:
        return np.zeros(0, bool)
    t = np.asarray(cam_to_vehicle, dtype=np.float64)
    rays = t[:3, :3] @ (np.linalg.inv(intrinsics) @ np.column_stack([pixels, np.ones(len(pixels))]).T)
    down = -rays[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = np.where(down > 1e-9, t[2, 3] / down, np.inf)
    hit = t[:3, 3][:, None] + rays * np.where(np.isfinite(reach), reach, 0.0)
    return np.isfinite(reach) & (hit[0] >= ROAD_NEAR_M) & (hit[0] <= ROAD_FAR_M) & (np.abs(hit[1]) <= ROAD_HALF_WIDTH_M)


#: Pixel step of the grid on which :func:`road_mask` tests the road (the mask is scaled up from it).
ROAD_MASK_STEP_PX = 4


def road_mask(shape: tuple[int, int], intrinsics: np.ndarray, cam_to_vehicle: np.ndarray) -> np.ndarray:
    """(H, W) uint8 mask of ``shape``, 255 where the pixel sees the road patch (:func:`on_road`)."""
    h, w = shape
    rows, cols = np.mgrid[0:h:ROAD_MASK_STEP_PX, 0:w:ROAD_MASK_STEP_PX]
    pixels = np.column_stack([cols.ravel(), rows.ravel()]).astype(np.float64) + ROAD_MASK_STEP_PX / 2
    coarse = on_road(pixels, intrinsics, cam_to_vehicle).reshape(rows.shape).astype(np.uint8) * 255
    return cv2.resize(coarse, (w, h), interpolation=cv2.INTER_NEAREST)


def fit_road(p0: np.ndarray, p1: np.ndarray, intrinsics: np.ndarray, rotation: np.ndarray, direction: np.ndarray,
             down: np.ndarray, pitch: float | None = None) -> tuple[float, float]:
    """(distance, pitch): the camera's distance to the road plane in lengths of the step ``direction``
    (3,), and the plane normal's pitch, radians, from road tracks ``p0`` (N, 2) -> ``p1`` (N, 2) pixels;
    distance NaN with fewer than :data:`MIN_ROAD_POINTS` tracks on the plane.

    A road point ``x`` (camera-0 frame) with ``normal @ x = distance`` moves to
    ``(rotation + direction normal^T / distance) x``; ``normal`` is ``down`` (3,), the calibrated
    normal, turned by ``pitch`` about the camera's x axis (positive: the camera pitched further down).
    The distance, and the pitch within :data:`MAX_ROAD_TILT_DEG` unless ``pitch`` is given, that put
    the tracks closest (truncated squared error, :data:`ROAD_TOLERANCE_PX`) are searched on a grid.
    """
    if len(p0) < MIN_ROAD_POINTS:
        return float("nan"), float("nan")
    k = np.asarray(intrinsics, dtype=np.float64)
    rays = np.linalg.inv(k) @ np.column_stack([p0, np.ones(len(p0))]).T
    tilt = np.radians(MAX_ROAD_TILT_DEG)
    logs = np.linspace(np.log(PLANE_DISTANCES[0]), np.log(PLANE_DISTANCES[1]), COARSE_STEPS[0])
    pitches = np.linspace(-tilt, tilt, COARSE_STEPS[1]) if pitch is None else np.array([pitch])
    best = _best_plane(p1, rays, k, rotation, direction, down, logs, pitches)
    log_step, pitch_step = logs[1] - logs[0], (pitches[1] - pitches[0] if len(pitches) > 1 else 0.0)
    logs = np.linspace(best[0] - log_step, best[0] + log_step, FINE_STEPS[0])
    pitches = np.linspace(best[1] - pitch_step, best[1] + pitch_step, FINE_STEPS[1] if pitch_step else 1)
    log_distance, found, inliers = _best_plane(p1, rays, k, rotation, direction, down, logs, pitches)
    return (float(np.exp(log_distance)) if inliers >= MIN_ROAD_POINTS else float("nan")), float(found)


def _best_plane(p1: np.ndarray, rays: np.ndarray, k: np.ndarray, rotation: np.ndarray, direction: np.ndarray,
                down: np.ndarray, logs: np.ndarray, pitches: np.ndarray) -> tuple[float, float, int]:
    """(log distance, pitch, tracks within tolerance) of the grid's plane with the least truncated error."""
    turned = k @ rotation @ rays  # (3, N): the points' pixels (homogeneous) at infinite distance
    inverse = np.exp(-logs)[:, None]  # (D, 1)
    best = (np.inf, 0.0, 0.0, 0)
    for pitch in pitches:
        c, s = np.cos(pitch), np.sin(pitch)
        normal = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]) @ down
        along = direction - (direction @ normal) * normal  # the vehicle moves along the road, not into it
        shift = k @ np.outer(along / np.linalg.norm(along), normal @ rays)  # (3, N): K along (normal . ray)
        depth = turned[2] + shift[2] * inverse  # (D, N): homogeneous pixels are turned + shift / distance
        with np.errstate(divide="ignore", invalid="ignore"):
            error = ((turned[0] + shift[0] * inverse) / depth - p1[:, 0]) ** 2 \
                + ((turned[1] + shift[1] * inverse) / depth - p1[:, 1]) ** 2
        error = np.where(depth > 0, error, np.inf)
        cost = np.minimum(error, ROAD_TOLERANCE_PX ** 2).sum(axis=1)
        i = int(np.argmin(cost))
        if cost[i] < best[0]:
            best = (cost[i], logs[i], pitch, int((error[i] < ROAD_TOLERANCE_PX ** 2).sum()))
    return best[1], best[2], best[3]
