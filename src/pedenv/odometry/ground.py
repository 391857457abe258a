"""The road under the camera: which pixels see it, and the metric length of a step from it (pure functions).

Frames: the camera frame is optical (x right, y down, z forward); ``cam_to_vehicle`` (4, 4)
maps it to the vehicle frame (x forward, y left, z up, origin on the road under the vehicle),
so the camera's height over the road is ``cam_to_vehicle[2, 3]``.
"""

from __future__ import annotations

import functools

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
#: apart), then of the searches around the last one's best, each spanning its neighbours: 0.77 % and
#: 0.1 deg apart, then 0.19 % and 0.05 deg (one fine grid of 81 x 21 at that spacing instead of the last two
#: took the whole fit from 3.9 to 5.7 ms on KITTI raw 0002 frames 3-4, 177 road tracks, and gave the same
#: figures: benchmarks/visual_odometry.py, tests/odometry/test_motion.py).
PLANE_DISTANCES = (0.01, 100.0)
COARSE_STEPS = (120, 13)
FINE_STEPS = ((21, 11), (9, 5))
#: The plane search's arithmetic: 32-bit floats (pixels of a few thousand, errors compared with
#: :data:`ROAD_TOLERANCE_PX`: 7 significant digits leave them exact to about 1e-3 px). On KITTI raw 0002
#: (frames 3-4, 184 road tracks, with the error's numerators linear in the inverse distance) the whole fit
#: took 2.4 against 3.8 ms in 64-bit floats, the same plane and figures (benchmarks/visual_odometry.py).
PLANE_FIT_DTYPE = np.float32


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
    """(H, W) uint8 mask of ``shape``, 255 where the pixel sees the road patch (:func:`on_road`); the
    same camera's mask is made once (the last two cameras' are kept) and copied out."""
    return _road_mask((int(shape[0]), int(shape[1])), np.asarray(intrinsics, np.float64).tobytes(),
                      np.asarray(cam_to_vehicle, np.float64).tobytes()).copy()


@functools.lru_cache(maxsize=2)
def _road_mask(shape: tuple[int, int], intrinsics_bytes: bytes, cam_to_vehicle_bytes: bytes) -> np.ndarray:
    intrinsics = np.frombuffer(intrinsics_bytes, np.float64).reshape(3, 3)
    cam_to_vehicle = np.frombuffer(cam_to_vehicle_bytes, np.float64).reshape(4, 4)
    h, w = shape
    rows, cols = np.mgrid[0:h:ROAD_MASK_STEP_PX, 0:w:ROAD_MASK_STEP_PX]
    pixels = np.column_stack([cols.ravel(), rows.ravel()]).astype(np.float64) + ROAD_MASK_STEP_PX / 2
    coarse = on_road(pixels, intrinsics, cam_to_vehicle).reshape(rows.shape).astype(np.uint8) * 255
    mask = cv2.resize(coarse, (w, h), interpolation=cv2.INTER_NEAREST)
    mask.flags.writeable = False  # shared by the calls with the same camera
    return mask


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
    log_distance, found, inliers = _best_plane(p1, rays, k, rotation, direction, down, logs, pitches)
    for distances, tilts in FINE_STEPS:
        log_step, pitch_step = logs[1] - logs[0], (pitches[1] - pitches[0] if len(pitches) > 1 else 0.0)
        logs = np.linspace(log_distance - log_step, log_distance + log_step, distances)
        pitches = np.linspace(found - pitch_step, found + pitch_step, tilts if pitch_step else 1)
        log_distance, found, inliers = _best_plane(p1, rays, k, rotation, direction, down, logs, pitches)
    return (float(np.exp(log_distance)) if inliers >= MIN_ROAD_POINTS else float("nan")), float(found)


def _best_plane(p1: np.ndarray, rays: np.ndarray, k: np.ndarray, rotation: np.ndarray, direction: np.ndarray,
                down: np.ndarray, logs: np.ndarray, pitches: np.ndarray) -> tuple[float, float, int]:
    """(log distance, pitch, tracks within tolerance) of the grid's plane with the least truncated error.

    A track's homogeneous pixel on the plane at inverse distance ``u`` is ``turned + u shift``; its error's
    numerators ``(turned + u shift)[:2] - p1 (turned + u shift)[2]`` are linear in ``u``, computed in
    :data:`PLANE_FIT_DTYPE`."""
    turned = k @ rotation @ rays  # (3, N): the points' pixels (homogeneous) at infinite distance
    inverse = np.exp(-logs)[:, None].astype(PLANE_FIT_DTYPE)  # (D, 1)
    x, y = p1[:, 0], p1[:, 1]
    ax, ay = (turned[0] - x * turned[2]).astype(PLANE_FIT_DTYPE), (turned[1] - y * turned[2]).astype(PLANE_FIT_DTYPE)
    az = turned[2].astype(PLANE_FIT_DTYPE)
    best = (np.inf, 0.0, 0.0, 0)
    for pitch in pitches:
        c, s = np.cos(pitch), np.sin(pitch)
        normal = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]) @ down
        along = direction - (direction @ normal) * normal  # the vehicle moves along the road, not into it
        shift = k @ np.outer(along / np.linalg.norm(along), normal @ rays)  # (3, N): K along (normal . ray)
        bx, by = (shift[0] - x * shift[2]).astype(PLANE_FIT_DTYPE), (shift[1] - y * shift[2]).astype(PLANE_FIT_DTYPE)
        depth = az + shift[2].astype(PLANE_FIT_DTYPE) * inverse  # (D, N)
        ex, ey = ax + bx * inverse, ay + by * inverse
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            error = (ex * ex + ey * ey) / (depth * depth)
        error[~(depth > 0)] = np.inf
        cost = np.minimum(error, ROAD_TOLERANCE_PX ** 2).sum(axis=1)
        i = int(np.argmin(cost))
        if cost[i] < best[0]:
            best = (cost[i], logs[i], pitch, int((error[i] < ROAD_TOLERANCE_PX ** 2).sum()))
    return best[1], best[2], best[3]


#: The wide-baseline road search (:func:`guided_road_length`), for frames too far apart for the road's
#: flow to be tracked (KITTI at 2 Hz: 5.4 m between frames, road points 20-100 px apart): the road
#: plane's homography for each of :data:`GUIDE_STEPS` step lengths (log-spaced over
#: :data:`GUIDE_DISTANCES`, the camera's distance to the plane in step lengths: a step of 0.08 to 33 m
#: for a camera 1.65 m up) warps the second image onto the first; the warp whose road patch correlates
#: best (normalised cross-correlation over the part still in view) is refined on a grid
#: :data:`GUIDE_FINE_STEPS` finer (1.5 % apart). The road's pitch stays the calibrated one: over a long
#: step the essential matrix's own pitch error and the road's pitch trade off against the length
#: (on KITTI tracking 0001 frames 15-20 a free pitch took the length 16 % long).
GUIDE_DISTANCES = (0.05, 20.0)
GUIDE_STEPS = 40
GUIDE_FINE_STEPS = 21
#: Least share of the road patch that a warp must keep inside the second image to be scored (a long
#: step takes the nearest road out of the image's bottom: 5.4 m takes the road up to 8.5 m ahead).
GUIDE_MIN_OVERLAP = 0.2
#: Least correlation of the best warp's road patch for its length to be taken (a road seen alike in both frames).
GUIDE_MIN_CORRELATION = 0.5


def guided_road_length(gray0: np.ndarray, gray1: np.ndarray, intrinsics: np.ndarray, rotation: np.ndarray,
                       direction: np.ndarray, cam_to_vehicle: np.ndarray) -> float:
    """The camera's distance to the road in step lengths (as :func:`fit_road`'s) between two grey images too
    far apart for the road's flow, from the road plane's homography that best aligns the road patch
    (:data:`GUIDE_DISTANCES`); the camera's ``rotation`` (3, 3) and unit ``direction`` (3,) from the
    essential matrix. NaN when no warp correlates :data:`GUIDE_MIN_CORRELATION` or more."""
    k = np.asarray(intrinsics, dtype=np.float64)
    h, w = gray0.shape[:2]
    mask = road_mask((h, w), k, cam_to_vehicle)
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if len(rows) == 0:
        return float("nan")
    box = (int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1)
    down = camera_down(cam_to_vehicle)
    along = direction - (direction @ down) * down
    if not np.linalg.norm(along) > 1e-6:  # straight up or down: no motion along the road to align
        return float("nan")
    along = along / np.linalg.norm(along)
    inverse_k = np.linalg.inv(k)
    gray1 = gray1.astype(np.float32)

    def score(log_distance: float) -> float:
        warp = k @ (rotation + np.outer(along, down) * np.exp(-log_distance)) @ inverse_k
        return _alignment(gray0, gray1, warp, mask, box)

    logs = np.linspace(np.log(GUIDE_DISTANCES[0]), np.log(GUIDE_DISTANCES[1]), GUIDE_STEPS)
    scores = [score(x) for x in logs]
    best = logs[int(np.argmax(scores))]
    spacing = logs[1] - logs[0]
    fine = np.linspace(best - spacing, best + spacing, GUIDE_FINE_STEPS)
    scores = [score(x) for x in fine]
    i = int(np.argmax(scores))
    return float(np.exp(fine[i])) if scores[i] >= GUIDE_MIN_CORRELATION else float("nan")


def _alignment(gray0: np.ndarray, gray1: np.ndarray, warp: np.ndarray, mask: np.ndarray,
               box: tuple[int, int, int, int]) -> float:
    """Normalised cross-correlation over ``mask`` (within ``box`` x0, y0, x1, y1) between ``gray0`` and
    ``gray1`` (float32) warped back by ``warp`` (frame-0 pixels -> frame-1 pixels); -1 where less than
    :data:`GUIDE_MIN_OVERLAP` of the patch stays in view."""
    x0, y0, x1, y1 = box
    shift = np.array([[1.0, 0.0, x0], [0.0, 1.0, y0], [0.0, 0.0, 1.0]])
    patch = cv2.warpPerspective(gray1, warp @ shift, (x1 - x0, y1 - y0),
                                flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_CONSTANT,
                                borderValue=-1.0)
    road = mask[y0:y1, x0:x1] > 0
    valid = road & (patch >= 0)
    if valid.sum() < GUIDE_MIN_OVERLAP * road.sum():
        return -1.0
    a = gray0[y0:y1, x0:x1][valid].astype(np.float64)
    b = patch[valid].astype(np.float64)
    a, b = a - a.mean(), b - b.mean()
    denominator = np.sqrt((a * a).sum() * (b * b).sum())
    return float((a * b).sum() / denominator) if denominator > 0 else -1.0
