"""Tracks between two grey images: FAST corners outside the person boxes, followed by pyramidal
Lucas-Kanade flow (the full image's, or the half image's refined on the full image's level) and kept
when the backward flow returns to the start (pure functions)."""

from __future__ import annotations

from operator import attrgetter

import cv2
import numpy as np

#: FAST's contrast threshold, grey levels (OpenCV's default, 10): absolute, so a dark or
#: flat image yields few corners instead of corners in its noise.
FAST_THRESHOLD = 10
#: More than the largest FAST score (a grey-level difference, below 256): a corner's sort key is its cell
#: times this less its score, so that one sort puts each cell's corners strongest first (as sorting on the
#: two keys did, in 0.5 against 0.8 ms for the 12866 corners of a KITTI raw frame).
FAST_SCORE_SPAN = 1024
#: Corners kept per cell of a :data:`GRID_CELLS` grid (strongest first), so that the road,
#: with weaker corners than trees and signs, keeps its share of tracks. (Four a cell cost half
#: as much but took the rendered road's distance 2.5 % short, beyond its 2 % test.)
CORNERS_PER_CELL = 12
#: The grid over the image, (rows, columns).
GRID_CELLS = (8, 16)
#: Extra corners taken on the road patch (:func:`pedenv.odometry.ground.road_mask`), whose texture is
#: often too faint for FAST (a road in shade): Shi-Tomasi corners (OpenCV's ``goodFeaturesToTrack``)
#: at least :data:`ROAD_CORNER_QUALITY` of the patch's best (a third of OpenCV's example 0.01: a
#: shaded road's corners are weak beside a car's on it) and :data:`ROAD_CORNER_SPACING_PX` apart.
#: 300 (600 before) gave the same KITTI and rendered-road figures within their spread, at less flow.
ROAD_CORNERS = 300
ROAD_CORNER_QUALITY = 0.003
ROAD_CORNER_SPACING_PX = 7
#: Lucas-Kanade window, pixels, and pyramid levels (OpenCV's window; 4 levels follow flows of
#: about 21 * 2**4 / 2 = 170 px, a car at 15 m/s and 10 Hz near the image's bottom edge). A 15 px
#: window costs half as much but took a rendered road blurred over 2 px 6 % short.
FLOW_WINDOW_PX = 21
FLOW_LEVELS = 4
#: Largest forward-backward flow error, pixels: a track whose backward flow lands farther from
#: its start is an outlier flow (an occlusion, a repeated texture, a mover's edge).
MAX_ROUND_TRIP_PX = 1.0
#: The forward flow's coarse levels (all but the full image's own) are followed on the half image (OpenCV's
#: ``pyrDown``: the full image's pyramid level 1) with a looser stop, at most :data:`COARSE_CRITERIA`'s
#: 10 iterations or a move below 0.1 px (OpenCV's default: 30 or 0.01 px): a coarse level only has to bring
#: the track within the window of the next, and the full image's level, run to OpenCV's default stop from
#: there, gives the track's precision. On KITTI raw 0002 (frames 3-4, 1779 corners) this cut the forward
#: flow from 36 to 28 ms at the same figures within their spread (benchmarks/visual_odometry.py). (The half
#: image with an 11 px window instead, cheaper still, took the darkened frames' step 6 % short:
#: tests/odometry/test_kitti_raw.py.)
COARSE_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 10, 0.1)
#: Pyramid levels of the backward flow, which starts at the track's start rather than searching the
#: whole pyramid again: a correct track returns within a pixel, a wrong one drifts off. The full image's
#: level alone (0) costs half as much as two levels (0 and 1; a seventh of a full backward search); the
#: KITTI and rendered-road figures stayed within their spread (benchmarks/visual_odometry.py,
#: tests/odometry/test_motion.py, tests/odometry/test_kitti_raw.py). (A 13 px backward window instead took
#: a rendered road blurred over 3 px 10 % short.)
BACK_FLOW_LEVELS = 0
#: The half image's flow (:func:`track_half`), for the FAST corners (the essential matrix's tracks; the few on
#: the road patch join its fit too), while the Shi-Tomasi road corners keep :func:`track`: the whole pyramid followed
#: on the half image (OpenCV's ``pyrDown``) with a window of :data:`HALF_WINDOW_PX` (the full image's 21 px window
#: at half scale) and :data:`COARSE_CRITERIA`'s loose stop, checked by the backward flow on the half image's own
#: level (:data:`MAX_ROUND_TRIP_PX` full-image pixels), then placed to OpenCV's precision by the full image's own
#: level (21 px window, started at the half image's result; a track that moves :data:`MAX_ROUND_TRIP_PX` or more
#: there is dropped). On KITTI raw 0002 frames 3-4 (749 corners, one OpenCV thread) it took their flow from 18.9 to
#: 6.5 ms, at the same figures within their spread (benchmarks/visual_odometry.py). The half image's flow alone
#: (no full level) took a rendered road at a 6 degree pitch 2.2 % short, beyond tests/odometry/test_motion.py's
#: 2 %; the road corners by this flow took the rendered road 2.8 % short and KITTI raw 0002's step blurred over
#: 4 px 8 % short (tests/odometry/test_kitti_raw.py's bound is 5 %).
HALF_WINDOW_PX = 11
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
    :data:`CORNERS_PER_CELL` per grid cell: every cell's strongest first, then every cell's second, and
    so on (:func:`ranked_corners`)."""
    return ranked_corners(gray, mask)[0]


def ranked_corners(gray: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`detect_corners`'s (N, 2) corners and each one's (N,) rank in its grid cell (0: the cell's strongest)."""
    points = cv2.FastFeatureDetector.create(threshold=FAST_THRESHOLD, nonmaxSuppression=True).detect(gray, mask)
    if not points:
        return np.empty((0, 2), np.float32), np.empty(0, int)
    xy = np.asarray(cv2.KeyPoint.convert(points), np.float32).reshape(-1, 2)
    strength = np.fromiter(map(attrgetter("response"), points), np.float64, len(points))
    rows, cols = GRID_CELLS
    pixel = xy.astype(np.int64)  # FAST's corners lie on whole pixels
    cell = np.minimum(pixel[:, 1] * rows // gray.shape[0], rows - 1) * cols \
        + np.minimum(pixel[:, 0] * cols // gray.shape[1], cols - 1)
    order = np.argsort(cell * FAST_SCORE_SPAN - strength, kind="stable")  # by cell, strongest first
    rank = np.arange(len(order)) - np.searchsorted(cell[order], cell[order])
    order, rank = order[rank < CORNERS_PER_CELL], rank[rank < CORNERS_PER_CELL]
    by_rank = np.argsort(rank, kind="stable")
    return xy[order[by_rank]], rank[by_rank]


def detect_road_corners(gray: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(N, 2) float32 pixel positions of up to :data:`ROAD_CORNERS` Shi-Tomasi corners where ``mask`` is non-zero
    (searched within the mask's bounding box only: the road patch is a small part of the image)."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if len(rows) == 0:
        return np.empty((0, 2), np.float32)
    top, left = max(rows[0] - 1, 0), max(cols[0] - 1, 0)  # a pixel of margin: the corner measure's window
    bottom, right = rows[-1] + 2, cols[-1] + 2
    found = cv2.goodFeaturesToTrack(np.ascontiguousarray(gray[top:bottom, left:right]), ROAD_CORNERS,
                                    ROAD_CORNER_QUALITY, ROAD_CORNER_SPACING_PX,
                                    mask=np.ascontiguousarray(mask[top:bottom, left:right]))
    if found is None:
        return np.empty((0, 2), np.float32)
    return (found.reshape(-1, 2) + np.array([left, top], np.float32)).astype(np.float32)


def track(gray0: np.ndarray, gray1: np.ndarray, points: np.ndarray, levels: int = FLOW_LEVELS,
          guess: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``points`` (N, 2) of ``gray0`` that track into ``gray1`` and back: (M, 2) float64 pixels in
    ``gray0``, their (M, 2) positions in ``gray1``, and which of the ``points`` they are, (N,) bool.
    ``levels``: the forward flow's pyramid levels (fewer where ``guess``, (N, 2) pixels in ``gray1``
    where the flow starts, puts the points close)."""
    if len(points) == 0:
        return np.empty((0, 2)), np.empty((0, 2)), np.zeros(0, bool)
    window = (FLOW_WINDOW_PX, FLOW_WINDOW_PX)
    p0 = points.reshape(-1, 1, 2).astype(np.float32)
    if guess is None and levels >= 1:  # the coarse levels on the half image, then the full image's own level
        coarse, ok0, _ = cv2.calcOpticalFlowPyrLK(cv2.pyrDown(gray0), cv2.pyrDown(gray1), p0 / 2, np.empty(0),
                                                  winSize=window, maxLevel=levels - 1, criteria=COARSE_CRITERIA)
        p1, ok1, _ = cv2.calcOpticalFlowPyrLK(gray0, gray1, p0, 2 * coarse, winSize=window, maxLevel=0,
                                              flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
        ok1 &= ok0
    elif guess is None:
        p1, ok1, _ = cv2.calcOpticalFlowPyrLK(gray0, gray1, p0, np.empty(0), winSize=window, maxLevel=levels)
    else:
        p1, ok1, _ = cv2.calcOpticalFlowPyrLK(gray0, gray1, p0, guess.reshape(-1, 1, 2).astype(np.float32),
                                              winSize=window, maxLevel=levels, flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
    back, ok2, _ = cv2.calcOpticalFlowPyrLK(gray1, gray0, p1, p0.copy(), winSize=window, maxLevel=BACK_FLOW_LEVELS,
                                            flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
    error = np.linalg.norm((back - p0).reshape(-1, 2), axis=1)
    h, w = gray1.shape
    q = p1.reshape(-1, 2)
    edge = FLOW_WINDOW_PX // 2  # a window cut by the image's edge drags the flow
    inside = (q[:, 0] >= edge) & (q[:, 0] < w - edge) & (q[:, 1] >= edge) & (q[:, 1] < h - edge)
    keep = ok1.ravel().astype(bool) & ok2.ravel().astype(bool) & (error < MAX_ROUND_TRIP_PX) & inside
    return p0.reshape(-1, 2)[keep].astype(np.float64), q[keep].astype(np.float64), keep


def track_half(gray0: np.ndarray, gray1: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`track`'s result, (M, 2) float64 pixels in ``gray0`` and ``gray1`` and (N,) bool, from the half
    image's flow and backward check, refined on the full image's level (:data:`HALF_WINDOW_PX`)."""
    if len(points) == 0:
        return np.empty((0, 2)), np.empty((0, 2)), np.zeros(0, bool)
    window = (HALF_WINDOW_PX, HALF_WINDOW_PX)
    half0, half1 = cv2.pyrDown(gray0), cv2.pyrDown(gray1)
    p0 = points.reshape(-1, 1, 2).astype(np.float32) / 2
    p1, ok1, _ = cv2.calcOpticalFlowPyrLK(half0, half1, p0, np.empty(0), winSize=window, maxLevel=FLOW_LEVELS - 1,
                                          criteria=COARSE_CRITERIA)
    back, ok2, _ = cv2.calcOpticalFlowPyrLK(half1, half0, p1, p0.copy(), winSize=window, maxLevel=0,
                                            flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
    error = 2 * np.linalg.norm((back - p0).reshape(-1, 2), axis=1)
    keep = ok1.ravel().astype(bool) & ok2.ravel().astype(bool) & (error < MAX_ROUND_TRIP_PX)
    if not keep.any():  # none tracked (a black frame): OpenCV refuses an empty list of points
        return np.empty((0, 2)), np.empty((0, 2)), keep
    start, coarse = 2 * p0[keep], 2 * p1[keep]
    full = (FLOW_WINDOW_PX, FLOW_WINDOW_PX)
    fine, ok3, _ = cv2.calcOpticalFlowPyrLK(gray0, gray1, start, coarse.copy(), winSize=full, maxLevel=0,
                                            flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
    q = fine.reshape(-1, 2)
    h, w = gray1.shape
    edge = FLOW_WINDOW_PX // 2  # a window cut by the image's edge drags the flow
    inside = (q[:, 0] >= edge) & (q[:, 0] < w - edge) & (q[:, 1] >= edge) & (q[:, 1] < h - edge)
    good = ok3.ravel().astype(bool) & inside & (np.linalg.norm(q - coarse.reshape(-1, 2), axis=1) < MAX_ROUND_TRIP_PX)
    keep[np.flatnonzero(keep)[~good]] = False
    return start.reshape(-1, 2)[good].astype(np.float64), q[good].astype(np.float64), keep


#: Descriptor matching across a wide baseline (:func:`match_features`), when the flow loses the frames:
#: ORB (OpenCV's oriented FAST and rotated BRIEF, scale pyramid of 8 levels, 1.2 apart) keypoints, at most
#: :data:`ORB_FEATURES`, matched by Hamming distance and kept when the best match is clearly better than
#: the second (Lowe's ratio test, his 0.8) and the match is mutual; each match is then refined to a
#: fraction of a pixel by the flow started at it (:data:`MATCH_REFINE_LEVELS` pyramid levels: a keypoint
#: of a coarse ORB level is placed to a few pixels). Unrefined, the matches' pixel noise took KITTI raw
#: 0002's distance 20 % short and its yaw 4.8 degrees off.
ORB_FEATURES = 3000
MATCH_RATIO = 0.8
MATCH_REFINE_LEVELS = 1


def match_features(gray0: np.ndarray, gray1: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(p0, p1): (M, 2) float64 pixels of ORB keypoints of ``gray0`` (where ``mask`` is non-zero) and of
    their matches in ``gray1`` (ratio test and mutual best match)."""
    orb = cv2.ORB.create(nfeatures=ORB_FEATURES)
    k0, d0 = orb.detectAndCompute(gray0, mask)
    k1, d1 = orb.detectAndCompute(gray1, None)
    if d0 is None or d1 is None or len(k0) < 2 or len(k1) < 2:
        return np.empty((0, 2)), np.empty((0, 2))
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING)
    forward = matcher.knnMatch(d0, d1, k=2)
    backward = {m.queryIdx: m.trainIdx for m in matcher.match(d1, d0)}
    pairs = [(m.queryIdx, m.trainIdx) for m, *rest in (f for f in forward if f)
             if (not rest or m.distance < MATCH_RATIO * rest[0].distance) and backward.get(m.trainIdx) == m.queryIdx]
    if not pairs:
        return np.empty((0, 2)), np.empty((0, 2))
    i0, i1 = np.array(pairs).T
    xy0, xy1 = (np.asarray(cv2.KeyPoint.convert(k), np.float64).reshape(-1, 2) for k in (k0, k1))
    p0, p1, _ = track(gray0, gray1, xy0[i0], levels=MATCH_REFINE_LEVELS, guess=xy1[i1])
    return p0, p1
