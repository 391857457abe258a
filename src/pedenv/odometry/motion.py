"""One step of the camera between two frames, and the steps' lengths completed (pure functions).

A step is in the camera frame (optical: x right, y down, z forward): camera 1 maps camera-0
points ``x`` to ``rotation @ x + translation``; the translation is ``direction * length``,
``direction`` unit and ``length`` in metres (NaN until the road has given it).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from pedenv.errors import InputError
from pedenv.odometry.features import detect_road_corners, match_features, person_mask, ranked_corners, track, track_half
from pedenv.odometry.ground import camera_down, fit_road, guided_road_length, on_road, road_mask

#: Fewest tracks between two frames, and fewest of them agreeing on one motion (the essential
#: matrix's inliers): below these the frame is too dark, blurred or covered for odometry.
#: (The five-point essential matrix needs 5; tens make its RANSAC and the road plane reliable.)
MIN_TRACKS = 40
MIN_INLIERS = 25
#: The flow first follows each grid cell's :data:`FIRST_PASS_PER_CELL` strongest FAST corners (of its
#: :data:`~pedenv.odometry.features.CORNERS_PER_CELL`) and the road's corners; only when fewer than
#: :data:`FIRST_PASS_MIN_TRACKS` of them track (frames far apart, dark, blurred or covered) are the
#: cells' other corners followed too. A car's camera at 10 Hz keeps most of its tracks (KITTI raw 0002:
#: about 730 of the first pass's 1050), and the essential matrix and the road plane found from them gave
#: the same figures within their spread at 40 % less flow; a hard step (KITTI at 2 Hz: a few hundred
#: tracks) keeps all its corners, whose number its motion needs (with 6 a cell everywhere the 2 Hz
#: frames' yaw error went from 0.18 to 0.28 degrees; 4 a cell in the first pass took KITTI raw 0002's
#: distance +4.5 % and one of its steps beyond its test's 5 %).
FIRST_PASS_PER_CELL = 6
FIRST_PASS_MIN_TRACKS = 500
#: Median parallax, pixels, below which the camera did not translate measurably: the raw flow
#: (a static camera: on vtest.avi at most 0.095 px against its first frame) and the flow left after taking out the
#: rotation (a camera turning on the spot). Such a step's translation is zero, not noise.
MIN_PARALLAX_PX = 0.5
#: Median flow, pixels, below which an essential matrix that finds no motion means too little
#: baseline yet, not a bad image (on the rendered road it fails up to about 1.1 px of flow).
MIN_BASELINE_FLOW_PX = 2.0
#: The essential matrix's robust fit (:data:`ESSENTIAL_METHOD`) and its tolerance: the largest distance of a
#: track from its epipolar line, pixels, and the confidence (OpenCV's defaults).
#: OpenCV's USAC_DEFAULT: RANSAC with local optimisation (LO-RANSAC), which on the rendered road gives the
#: direction of travel to about 0.1 deg where plain RANSAC's best five-point sample was 1-2 deg off. USAC_ACCURATE
#: (graph-cut local optimisation) gave the same inliers, pose and figures on KITTI raw 0002, the tracking samples
#: and the rendered roads at 3.5x the cost (frames 3-4, 692 tracks, one OpenCV thread: 5.0 against 1.4 ms;
#: benchmarks/visual_odometry.py, tests/odometry/test_motion.py).
ESSENTIAL_METHOD = cv2.USAC_DEFAULT
EPIPOLAR_TOLERANCE_PX = 1.0
RANSAC_CONFIDENCE = 0.999
#: Largest angle, degrees, between the motion from matched descriptors and the vehicle's forward axis:
#: a car's camera moves along it (a few degrees off in a tight turn), while a repeated texture matched
#: one period off agrees on a sideways motion (KITTI raw 0002 frames 6-7: 72 degrees off, 93 % inliers).
MAX_SIDESLIP_DEG = 20.0
#: Shortest step, metres, whose length is taken from the road's alignment
#: (:func:`~pedenv.odometry.ground.guided_road_length`) when the road's flow gave none: the alignment
#: needs the road to move many pixels (KITTI tracking 0001: -1.3 % over its 5.4 m steps at 2 Hz, but
#: -23 % over a 1.2 m step at 10 Hz); a shorter step takes its neighbours' speed.
GUIDE_MIN_STEP_M = 2.0


@dataclass(frozen=True)
class Step:
    """The camera's motion between two frames (module doc). rotation: (3, 3); direction: (3,) unit
    or zeros when the camera did not translate; length: metres (0 without translation, NaN when
    the road was not seen); pitch: the road plane's pitch fitted with it, radians (NaN without);
    road: the road tracks, (M, 2) pixels in each frame; tracks, inliers: counts; parallax: median
    flow without rotation, pixels; seen: whether the motion was measurable (else the frame is no new
    keyframe of :class:`~pedenv.odometry.estimator.VisualOdometry`); guided: the road's flow did not
    fit and the length is the road homography's that aligns the road best
    (:func:`~pedenv.odometry.ground.guided_road_length`: frames far apart; kept as it is, no pitch);
    wide: the flow lost the frames and the motion is from matched descriptors
    (:func:`~pedenv.odometry.features.match_features`)."""

    rotation: np.ndarray
    direction: np.ndarray
    length: float
    tracks: int
    inliers: int
    parallax: float
    pitch: float = float("nan")
    road: tuple[np.ndarray, np.ndarray] = (np.empty((0, 2)), np.empty((0, 2)))
    seen: bool = True
    guided: bool = False
    wide: bool = False

    @property
    def moved(self) -> bool:
        """Whether the camera translated measurably (its parallax at least :data:`MIN_PARALLAX_PX`)."""
        return bool(np.any(self.direction))


def still(tracks: int, flow: float) -> Step:
    """A step without measurable motion: the tracks' median flow ``flow`` (pixels) below
    :data:`MIN_PARALLAX_PX`, or below :data:`MIN_BASELINE_FLOW_PX` with no essential matrix."""
    return Step(np.eye(3), np.zeros(3), 0.0, tracks, tracks, flow, seen=False)


def road_length(step: Step, intrinsics: np.ndarray, cam_to_vehicle: np.ndarray, pitch: float | None = None) -> float:
    """``step``'s length, metres, from its road tracks with the road's pitch fixed at ``pitch`` (radians,
    :func:`~pedenv.odometry.ground.fit_road`), or fitted when None; NaN when the road does not fit."""
    if not step.moved:
        return 0.0
    if step.guided:
        return step.length  # aligned with the calibrated pitch: no road tracks to refit
    distance, _ = fit_road(*step.road, intrinsics, step.rotation, step.direction, camera_down(cam_to_vehicle), pitch)
    return float(cam_to_vehicle[2][3] / distance)


def estimate_step(gray0: np.ndarray, gray1: np.ndarray, intrinsics: np.ndarray, cam_to_vehicle: np.ndarray, *,
                  boxes: np.ndarray | None = None, where: str = "frame") -> Step:
    """The camera's :class:`Step` from grey image ``gray0`` (H, W) uint8 to ``gray1``.

    intrinsics: (3, 3) pixels. cam_to_vehicle: (4, 4) camera -> vehicle (the road's normal and
    the camera's height over it). boxes: (N, 4) ``[x1, y1, x2, y2]`` pixels of ``gray0``'s people,
    whose corners are left out. ``where`` names the frame in the InputError raised when too few
    tracks or inliers are found (:data:`MIN_TRACKS`, :data:`MIN_INLIERS`).
    """
    k = np.array(intrinsics, dtype=np.float64)  # a contiguous copy: USAC misreads a strided matrix
    shape = (gray0.shape[0], gray0.shape[1])
    allowed = person_mask(shape, boxes)
    corners, rank = ranked_corners(gray0, allowed)
    road_corners = detect_road_corners(gray0, allowed & road_mask(shape, k, cam_to_vehicle))
    p0, p1, kept = _tracks(gray0, gray1, corners, int((rank < FIRST_PASS_PER_CELL).sum()), road_corners)
    # the count of FAST's corners tracked says whether the images hold enough contrast (absolute)
    tracked, wide = int(kept[:len(corners)].sum()), False
    count, rotation, direction, inlier = 0, np.eye(3), np.zeros(3), np.zeros(len(p0), bool)
    if tracked >= MIN_TRACKS:
        flow = float(np.median(np.linalg.norm(p1 - p0, axis=1)))
        if flow < MIN_PARALLAX_PX:
            return still(len(p0), flow)
        count, rotation, direction, inlier = _essential(p0, p1, k)
        if count < MIN_INLIERS and flow < MIN_BASELINE_FLOW_PX:
            return still(len(p0), flow)  # too little baseline yet: the keyframe waits for more
    if count < MIN_INLIERS:  # the flow lost the frames (far apart, or too dark): descriptors matched instead
        q0, q1 = match_features(gray0, gray1, allowed)
        found = _essential(q0, q1, k) if len(q0) >= MIN_INLIERS else (0, rotation, direction, inlier)
        if found[0] < MIN_INLIERS or not _along_vehicle(found[2], cam_to_vehicle):
            _require(tracked, MIN_TRACKS, "tracks", where)
            _require(count, MIN_INLIERS, "tracks agreeing on one motion", where)
        (count, rotation, direction, inlier), p0, p1, wide = found, q0, q1, True
    parallax = _parallax(p0[inlier], p1[inlier], k, rotation)
    if parallax < MIN_PARALLAX_PX:
        return Step(rotation, np.zeros(3), 0.0, len(p0), int(count), parallax, wide=wide)  # turning on the spot
    road = inlier & on_road(p0, k, cam_to_vehicle) & (not wide)  # asphalt gives descriptors few matches
    distance, pitch = fit_road(p0[road], p1[road], k, rotation, direction, camera_down(cam_to_vehicle))
    if not np.isfinite(distance):  # frames too far apart for the road's flow: the road's homography aligned
        distance = guided_road_length(gray0, gray1, k, rotation, direction, cam_to_vehicle)
        if not cam_to_vehicle[2][3] / distance >= GUIDE_MIN_STEP_M:
            distance = float("nan")  # a short step: its neighbours' speed is the better guess
        return Step(rotation, direction, float(cam_to_vehicle[2][3] / distance), len(p0), int(count), parallax,
                    guided=bool(np.isfinite(distance)), wide=wide)
    return Step(rotation, direction, float(cam_to_vehicle[2][3] / distance), len(p0), int(count), parallax, pitch,
                (p0[road], p1[road]), wide=wide)


def _tracks(gray0: np.ndarray, gray1: np.ndarray, corners: np.ndarray, first: int,
            road_corners: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The tracks (p0, p1: (M, 2) pixels) of the FAST ``corners`` (N, 2), strongest of each cell first, and the
    ``road_corners`` (R, 2), and which of them tracked ((N + R,) bool, in that order): the ``first`` corners by
    the half image's flow (:func:`~pedenv.odometry.features.track_half`), the road's by the full image's. A hard
    step (fewer than :data:`FIRST_PASS_MIN_TRACKS` tracks) takes the full image's flow for the corners, then
    follows the rest of them too."""
    fast, road = track_half(gray0, gray1, corners[:first]), track(gray0, gray1, road_corners)
    if len(fast[0]) + len(road[0]) < FIRST_PASS_MIN_TRACKS:
        fast = track(gray0, gray1, corners[:first])
    p0, p1, kept = np.vstack([fast[0], road[0]]), np.vstack([fast[1], road[1]]), np.concatenate([fast[2], road[2]])
    if len(p0) < FIRST_PASS_MIN_TRACKS:
        q0, q1, more = track(gray0, gray1, corners[first:])
        p0, p1, kept = np.vstack([p0, q0]), np.vstack([p1, q1]), np.concatenate([kept[:first], more, kept[first:]])
    return p0, p1, kept


def _along_vehicle(direction: np.ndarray, cam_to_vehicle: np.ndarray) -> bool:
    """Whether the camera's ``direction`` of travel (3,), camera frame, lies within :data:`MAX_SIDESLIP_DEG`
    of the vehicle's forward or backward axis (a car does not move sideways)."""
    forward = np.asarray(cam_to_vehicle, dtype=np.float64)[:3, :3].T @ np.array([1.0, 0.0, 0.0])
    return bool(abs(direction @ forward) >= np.cos(np.radians(MAX_SIDESLIP_DEG)) * np.linalg.norm(direction))


def _essential(p0: np.ndarray, p1: np.ndarray, k: np.ndarray) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """(inliers, rotation (3, 3), unit direction (3,), which tracks are inliers (N,) bool) of the essential
    matrix between the tracks ``p0`` -> ``p1`` (N, 2) pixels (USAC, then its pose with the most tracks in front,
    :func:`pose_in_front`); 0 inliers when none."""
    essential, mask = cv2.findEssentialMat(p0, p1, k, method=ESSENTIAL_METHOD, prob=RANSAC_CONFIDENCE,
                                           threshold=EPIPOLAR_TOLERANCE_PX)
    if essential is None or essential.shape[0] < 3:
        return 0, np.eye(3), np.zeros(3), np.zeros(len(p0), bool)
    # several solutions stack up: the first, the best
    inlier = np.flatnonzero(mask.ravel() > 0)
    rotation, direction, front = pose_in_front(essential[:3], p0[inlier], p1[inlier], k)
    chosen = np.zeros(len(p0), bool)
    chosen[inlier[front]] = True
    return int(front.sum()), rotation, direction, chosen


#: Farthest depth, in step lengths, of a track counted in front of the cameras (OpenCV's ``recoverPose``
#: default, 50: a farther point is as good as at infinity, its side of the cameras undecided).
MAX_DEPTH_STEPS = 50.0


def pose_in_front(essential: np.ndarray, p0: np.ndarray, p1: np.ndarray,
              k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rotation (3, 3), unit direction (3,), which tracks are in front (N,) bool): of the essential matrix's
    four poses (OpenCV's ``decomposeEssentialMat``), the one that puts the most tracks ``p0`` -> ``p1`` (N, 2)
    pixels in front of both cameras, closer than :data:`MAX_DEPTH_STEPS`. As OpenCV's ``recoverPose``, with
    each track's two depths solved in closed form (least squares of ``z0 rotation x0 + direction = z1 x1``)
    instead of its linear triangulation: on KITTI raw 0002 frames 3-4 (1034 tracks, one OpenCV thread)
    0.4 against 5.0 ms, the same pose, 12 of its 700 tracks in front judged otherwise."""
    rotation_a, rotation_b, t = cv2.decomposeEssentialMat(essential)
    inverse = np.linalg.inv(k)
    x0 = inverse @ np.vstack([p0.T, np.ones(len(p0))])
    x1 = inverse @ np.vstack([p1.T, np.ones(len(p1))])
    best: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    for rotation, direction in ((rotation_a, t.ravel()), (rotation_b, t.ravel()), (rotation_a, -t.ravel()),
                                (rotation_b, -t.ravel())):
        a = rotation @ x0
        aa, ab, bb = (a * a).sum(axis=0), -(a * x1).sum(axis=0), (x1 * x1).sum(axis=0)
        at, bt = direction @ a, -(direction @ x1)
        with np.errstate(divide="ignore", invalid="ignore"):
            z0 = (ab * bt - bb * at) / (aa * bb - ab * ab)
            z1 = (ab * at - aa * bt) / (aa * bb - ab * ab)
        front = (z0 > 0) & (z1 > 0) & (z0 < MAX_DEPTH_STEPS) & (z1 < MAX_DEPTH_STEPS)
        if best is None or front.sum() > best[2].sum():
            best = (rotation, direction, front)
    assert best is not None
    return best


def _parallax(p0: np.ndarray, p1: np.ndarray, k: np.ndarray, rotation: np.ndarray) -> float:
    """Median distance, pixels, between ``p1`` and ``p0`` turned by ``rotation`` alone (the infinite homography)."""
    turned = (k @ rotation @ np.linalg.inv(k) @ np.column_stack([p0, np.ones(len(p0))]).T).T
    return float(np.median(np.linalg.norm(turned[:, :2] / turned[:, 2:] - p1, axis=1)))


def _require(count: int, needed: int, what: str, where: str) -> None:
    if count < needed:
        raise InputError(f"{where}: too dark, blurred or covered for visual odometry: {count} {what} to the next "
                         f"frame, {needed} needed; give the ego poses (--ego-poses)")


def pooled_pitch(pool: list[Step]) -> float | None:
    """The road's pitch, radians, pooled over the steps ``pool``: the median of the moving steps' own fits
    (:func:`~pedenv.odometry.ground.fit_road`; one step's pitch and length trade off against each other); None
    without any. Both :class:`~pedenv.odometry.estimator.VisualOdometry` and
    :class:`~pedenv.odometry.stream.OdometryStream` refit their steps' lengths with it (:func:`road_length`)."""
    pitches = [s.pitch for s in pool if s.moved and np.isfinite(s.length) and np.isfinite(s.pitch)]
    return float(np.median(pitches)) if pitches else None


def fill_lengths(lengths: np.ndarray, durations: np.ndarray, where: str = "the recording") -> np.ndarray:
    """(S,) step lengths, metres, with each NaN (road not seen) replaced by the duration (S,) seconds
    times the speed interpolated from the nearest measured steps. InputError when no moving step
    has a length (the road was never seen)."""
    lengths = np.asarray(lengths, dtype=np.float64).copy()
    missing = np.isnan(lengths)
    if not missing.any():
        return lengths
    known = np.flatnonzero(~missing & (lengths > 0))
    if len(known) == 0:
        raise InputError(f"{where}: visual odometry saw no road ahead of the camera to give the motion its scale "
                         "(check the calibration's cam_to_vehicle: the camera's height and pitch); give --ego-poses")
    speeds = lengths[known] / durations[known]
    lengths[missing] = np.interp(np.flatnonzero(missing), known, speeds) * durations[missing]
    return lengths
