"""Tracks between two grey images: FAST corners outside the person boxes, followed by pyramidal
Lucas-Kanade flow and kept when the backward flow returns to the start (pure functions)."""

from __future__ import annotations

import cv2
import numpy as np

#: FAST's contrast threshold, grey levels (OpenCV's default, 10): absolute, so a dark or
#: flat image yields few corners instead of corners in its noise.
FAST_THRESHOLD = 10
#: Corners kept per cell of a :data:`GRID_CELLS` grid (strongest first), so that the road,
#: with weaker corners than trees and signs, keeps its share of tracks.
CORNERS_PER_CELL = 12
#: The grid over the image, (rows, columns).
GRID_CELLS = (8, 16)
#: Extra corners taken on the road patch (:func:`pedenv.odometry.ground.road_mask`), whose texture is
#: often too faint for FAST (a road in shade): Shi-Tomasi corners (OpenCV's ``goodFeaturesToTrack``)
#: at least :data:`ROAD_CORNER_QUALITY` of the patch's best (a third of OpenCV's example 0.01: a
#: shaded road's corners are weak beside a car's on it) and :data:`ROAD_CORNER_SPACING_PX` apart.
ROAD_CORNERS = 600
ROAD_CORNER_QUALITY = 0.003
ROAD_CORNER_SPACING_PX = 7
#: Lucas-Kanade window, pixels, and pyramid levels (OpenCV's window; 4 levels follow flows of
#: about 21 * 2**4 / 2 = 170 px, a car at 15 m/s and 10 Hz near the image's bottom edge).
FLOW_WINDOW_PX = 21
FLOW_LEVELS = 4
#: Largest forward-backward flow error, pixels: a track whose backward flow lands farther from
#: its start is an outlier flow (an occlusion, a repeated texture, a mover's edge).
MAX_ROUND_TRIP_PX = 1.0
#: Margin added around each person box before its corners are left out, in box widths.
BOX_MARGIN = 0.1


def person_mask(shape: tuple[int, int], boxes: np.ndarray | None) -> np.ndarray:
    """(H, W) uint8 mask, 255 where corners may be taken: everywhere but inside ``boxes``.

    boxes: (N, 4) float ``[x1, y1, x2, y2]`` pixels (the frame's person detections), or None.
    """
    mask = np.full(shape, 255, np.uint8)
    if boxes is None or len(boxes) == 0:
        return mask
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    pad = BOX_MARGIN * (b[:, 2] - b[:, 0])
    lo = np.floor(b[:, :2] - pad[:, None]).clip(0, None).astype(int)
    hi = np.ceil(b[:, 2:] + pad[:, None]).astype(int)
    for (x1, y1), (x2, y2) in zip(lo, hi):
        mask[y1:max(y2, y1), x1:max(x2, x1)] = 0
    return mask


def detect_corners(gray: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(N, 2) float32 pixel positions of FAST corners where ``mask`` is non-zero, at most
    :data:`CORNERS_PER_CELL` per grid cell, the strongest first."""
    points = cv2.FastFeatureDetector.create(threshold=FAST_THRESHOLD, nonmaxSuppression=True).detect(gray, mask)
    if not points:
        return np.empty((0, 2), np.float32)
    xy = np.array([p.pt for p in points], np.float32)
    strength = np.array([p.response for p in points])
    rows, cols = GRID_CELLS
    cell = (np.minimum(xy[:, 1] * rows // gray.shape[0], rows - 1) * cols
            + np.minimum(xy[:, 0] * cols // gray.shape[1], cols - 1)).astype(int)
    order = np.lexsort((-strength, cell))
    rank = np.arange(len(order)) - np.searchsorted(cell[order], cell[order])
    return xy[order[rank < CORNERS_PER_CELL]]


def detect_road_corners(gray: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(N, 2) float32 pixel positions of up to :data:`ROAD_CORNERS` Shi-Tomasi corners where ``mask`` is non-zero."""
    found = cv2.goodFeaturesToTrack(gray, ROAD_CORNERS, ROAD_CORNER_QUALITY, ROAD_CORNER_SPACING_PX, mask=mask)
    return np.empty((0, 2), np.float32) if found is None else found.reshape(-1, 2).astype(np.float32)


def track(gray0: np.ndarray, gray1: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``points`` (N, 2) of ``gray0`` that track into ``gray1`` and back: (M, 2) float64 pixels in
    ``gray0``, their (M, 2) positions in ``gray1``, and which of the ``points`` they are, (N,) bool."""
    if len(points) == 0:
        return np.empty((0, 2)), np.empty((0, 2)), np.zeros(0, bool)
    window = (FLOW_WINDOW_PX, FLOW_WINDOW_PX)
    p0 = points.reshape(-1, 1, 2).astype(np.float32)
    p1, ok1, _ = cv2.calcOpticalFlowPyrLK(gray0, gray1, p0, np.empty(0), winSize=window, maxLevel=FLOW_LEVELS)
    back, ok2, _ = cv2.calcOpticalFlowPyrLK(gray1, gray0, p1, np.empty(0), winSize=window, maxLevel=FLOW_LEVELS)
    error = np.linalg.norm((back - p0).reshape(-1, 2), axis=1)
    h, w = gray1.shape
    q = p1.reshape(-1, 2)
    edge = FLOW_WINDOW_PX // 2  # a window cut by the image's edge drags the flow
    inside = (q[:, 0] >= edge) & (q[:, 0] < w - edge) & (q[:, 1] >= edge) & (q[:, 1] < h - edge)
    keep = ok1.ravel().astype(bool) & ok2.ravel().astype(bool) & (error < MAX_ROUND_TRIP_PX) & inside
    return p0.reshape(-1, 2)[keep].astype(np.float64), q[keep].astype(np.float64), keep
