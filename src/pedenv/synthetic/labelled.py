"""Skeletons rendered from labelled 3D boxes: real motion, modelled perception.

Where a dataset has each person's 3D box over time (KITTI tracking: bottom-face centre,
height, yaw) but no image, the built-in body model (:mod:`pedenv.synthetic.walker`) stands
a COCO-17 skeleton in each box: the box's height as body height, its yaw as heading, the
gait phase from the distance the person has walked along the labelled track and the gait's
amplitude from the labelled speed. The detector model
(:class:`pedenv.synthetic.detector.DetectorModel`) then adds a real network's noise, misses
and false positives. The dataset's occlusion flags hide keypoints and cause misses here
(:func:`occlusion_visibility`).
"""

from __future__ import annotations

import zlib

import numpy as np

from pedenv.body import world_keypoints
from pedenv.skeleton import CocoKeypoint as KP
from pedenv.synthetic.walker import body_keypoints, gait_amplitude, stride_length

#: A labelled person slower than this (m/s) stands (no gait); the behaviour evaluation's bound too.
STANDING_SPEED_MPS = 0.3
#: Half-width (frames) of the centred window over which a track's labelled positions are
#: averaged before its speed and walked distance are taken: labels jitter by 5-30 cm from
#: frame to frame (KITTI, standing people), which over one 0.1 s step reads as 1-3 m/s.
SMOOTH_HALF_WINDOW = 3
#: Probability that a person is detected at all, by KITTI's ``occluded`` flag (0 fully visible,
#: 1 partly occluded, 2 largely occluded, 3 unknown), on top of the detector model's size curve.
#: Assumed, not measured: the drives have no images to measure a network on.
OCCLUDED_DETECTION = (1.0, 0.9, 0.6, 0.6)
#: Keypoints hidden by each ``occluded`` flag: partly, the legs below the knees' tops; largely
#: (or unknown), everything below the shoulders but the elbows.
_LEGS: list[int] = [KP.LEFT_KNEE, KP.RIGHT_KNEE, KP.LEFT_ANKLE, KP.RIGHT_ANKLE]
HIDDEN_BY_OCCLUSION: tuple[list[int], ...] = (
    [], _LEGS, _LEGS + [KP.LEFT_HIP, KP.RIGHT_HIP, KP.LEFT_WRIST, KP.RIGHT_WRIST], _LEGS + [KP.LEFT_HIP, KP.RIGHT_HIP])
#: A person with fewer keypoints than this inside the image (truncated at the border) is missed.
MIN_KEYPOINTS_INSIDE = 5


def track_motion(ids: np.ndarray, frames: np.ndarray, xy: np.ndarray, rate_hz: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Speed (N,) m/s and distance walked since the track's first label (N,) m of N labelled
    positions: track ``ids`` (N,), ``frames`` (N,) frame numbers, ``xy`` (N, 2) world, metres.

    Each track's positions are averaged over :data:`SMOOTH_HALF_WINDOW` frames either side;
    the speed is the smoothed positions' centred difference (one-sided at the track's ends).
    """
    speed, walked = np.zeros(len(ids)), np.zeros(len(ids))
    for track in np.unique(ids):
        rows = np.flatnonzero(ids == track)
        rows = rows[np.argsort(frames[rows])]
        t = frames[rows] / rate_hz
        smooth = _smoothed(xy[rows], frames[rows])
        steps = np.linalg.norm(np.diff(smooth, axis=0), axis=1)
        walked[rows] = np.concatenate([[0.0], np.cumsum(steps)])
        if len(rows) > 1:
            v = np.gradient(smooth, t, axis=0)
            speed[rows] = np.linalg.norm(v, axis=1)
    return speed, walked


def _smoothed(xy: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """(K, 2) positions averaged over the labelled frames within the window of each."""
    gap = np.abs(frames[:, None] - frames[None, :]) <= SMOOTH_HALF_WINDOW
    return (gap @ xy) / gap.sum(axis=1, keepdims=True)


def render_skeletons(ground: np.ndarray, heading: np.ndarray, heights: np.ndarray, speed: np.ndarray,
                     walked: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """World skeletons (N, 17, 3) of N persons standing on ``ground`` (N, 3) world, metres, facing
    ``heading`` (N,) radians, ``heights`` (N,) m tall, moving at ``speed`` (N,) m/s, having walked
    ``walked`` (N,) m; each track's gait starts at a phase of its own (from its id)."""
    ids = np.asarray(ids, np.int64)
    start = np.array([zlib.crc32(int(i).to_bytes(8, "little", signed=True)) % 1000 for i in ids]) / 1000.0
    phase = 2.0 * np.pi * (start + walked / stride_length(heights, np.maximum(speed, 0.5)))
    gait = np.where(speed >= STANDING_SPEED_MPS, gait_amplitude(speed), 0.0)
    body = body_keypoints(heights, phase, gait, np.zeros((len(ids), 2)))
    return world_keypoints(ground, heading, body)


def occlusion_visibility(inside: np.ndarray, occluded: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(N, 17) bool keypoints seen: ``inside`` (N, 17) the image, less those the ``occluded`` (N,)
    flags hide; a person missed (:data:`OCCLUDED_DETECTION`, :data:`MIN_KEYPOINTS_INSIDE`) has none."""
    flags = np.clip(np.asarray(occluded, np.int64), 0, 3)
    seen = inside.copy()
    for flag, hidden in enumerate(HIDDEN_BY_OCCLUSION):
        if hidden:
            seen[np.ix_(flags == flag, hidden)] = False
    found = rng.random(len(flags)) < np.asarray(OCCLUDED_DETECTION)[flags]
    found &= inside.sum(axis=1) >= MIN_KEYPOINTS_INSIDE
    return seen & found[:, None]
