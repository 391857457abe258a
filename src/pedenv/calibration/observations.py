"""People's foot and head points from 2D skeletons: what the camera is fitted to.

A person counts when both ankles and a head keypoint are confident, the head is above the
feet and the skeleton is upright enough (its torso within :data:`MAX_LEAN_DEG` of the
foot-to-head line): a sitting, bending or cut-off person would pull the fit. The head point is
the ears' midpoint where both ears are confident (it sits on the body's vertical axis,
``pedenv.body.EAR_FORWARD`` 0.004 of the height behind it), else the eyes' (0.040 of the height,
about 7 cm, in front of the axis, towards wherever the person faces), else the nose.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pedenv.body import ANKLE, EYE
from pedenv.errors import check_array
from pedenv.records import Detections
from pedenv.skeleton import CocoKeypoint as KP

#: Keypoints below this confidence are not used (the fused method's ``min_keypoint_confidence``).
MIN_CONFIDENCE = 0.3
#: A person shorter than this from feet to head (pixels) is left out: its keypoints' noise (a
#: few pixels) would be a large share of its span, and near a detector's smallest person the
#: people found are the taller ones (and those whose noise lengthened them), which pulls the
#: camera's height low. On the built-in ``static-plaza`` (150 frames, the ``default`` detector
#: model: 50 % found at 25 px, 3.5 px noise at 30 px) with its true tracks, 24 px gave the height
#: -4.5 %, 40 px -0.6 %.
MIN_SPAN_PX = 40.0
#: Largest angle between the shoulders-to-hips line and the feet-to-head line, degrees: an
#: upright person's torso lies along it; a bending or sitting one's does not.
MAX_LEAN_DEG = 20.0

_ANKLES = [KP.LEFT_ANKLE, KP.RIGHT_ANKLE]
#: The head keypoints in order of preference (see the module's doc): a standing person's facing
#: is unknown, so the eyes' forward offset cannot be modelled and spreads the feet-to-head lines.
_HEADS = ([KP.LEFT_EAR, KP.RIGHT_EAR], [KP.LEFT_EYE, KP.RIGHT_EYE], [KP.NOSE])
_SHOULDERS, _HIPS = [KP.LEFT_SHOULDER, KP.RIGHT_SHOULDER], [KP.LEFT_HIP, KP.RIGHT_HIP]


@dataclass(frozen=True)
class Observations:
    """Upright people seen by one camera, over any number of images.

    feet: (N, 2) float, pixels, the midpoint of the ankles. heads: (N, 2) float, pixels,
    the ears' midpoint, else the eyes', else the nose. head_share: (N,) float, that head
    point's height as a share of body height (:mod:`pedenv.body`). tracks: (N,) int, the
    person's track id, -1 where unknown. frames: (N,) int, the image each came from.
    """

    feet: np.ndarray
    heads: np.ndarray
    head_share: np.ndarray
    tracks: np.ndarray
    frames: np.ndarray

    def __post_init__(self) -> None:
        n = check_array("feet", self.feet, (None, 2)).shape[0]
        check_array("heads", self.heads, (n, 2))
        check_array("head_share", self.head_share, (n,))
        check_array("tracks", self.tracks, (n,), finite=False)
        check_array("frames", self.frames, (n,), finite=False)

    def __len__(self) -> int:
        return self.feet.shape[0]

    @property
    def people(self) -> int:
        """Distinct people: tracks where known, else observations per image on average."""
        known = self.tracks[self.tracks >= 0]
        unknown = int(np.sum(self.tracks < 0))
        frames = max(len(np.unique(self.frames[self.tracks < 0])), 1)
        return len(np.unique(known)) + int(np.ceil(unknown / frames))

    def subset(self, keep: np.ndarray) -> Observations:
        """The observations where ``keep`` ((N,) bool or indices)."""
        return Observations(self.feet[keep], self.heads[keep], self.head_share[keep], self.tracks[keep],
                            self.frames[keep])

    @classmethod
    def empty(cls) -> Observations:
        z2 = np.zeros((0, 2))
        return cls(z2, z2, np.zeros(0), np.zeros(0, int), np.zeros(0, int))

    @classmethod
    def concat(cls, parts: list[Observations]) -> Observations:
        if not parts:
            return cls.empty()
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in
                     ("feet", "heads", "head_share", "tracks", "frames")))


def _mean_of(points: np.ndarray, confident: np.ndarray, groups: tuple[list, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Per person the mean of the first group of keypoints all confident: ((N, 2), index of the group or -1)."""
    out, which = np.full((points.shape[0], 2), np.nan), np.full(points.shape[0], -1)
    for g, idx in enumerate(groups):
        ok = confident[:, idx].all(axis=1) & (which < 0)
        out[ok] = points[ok][:, idx].mean(axis=1)
        which[ok] = g
    return out, which


def observations_of(detections: Detections, frame: int = 0, tracks: np.ndarray | None = None) -> Observations:
    """The upright people of one image's ``detections`` (``tracks``: (N,) ids of the detections, or None)."""
    from pedenv.body import EAR, EYE, NOSE

    kp, conf = detections.keypoints, detections.confidences >= MIN_CONFIDENCE
    feet, has_feet = _mean_of(kp, conf, (_ANKLES,))
    heads, group = _mean_of(kp, conf, _HEADS)
    torso_top, has_top = _mean_of(kp, conf, (_SHOULDERS,))
    torso_low, has_low = _mean_of(kp, conf, (_HIPS,))
    axis, torso = heads - feet, torso_top - torso_low
    with np.errstate(invalid="ignore"):
        cos = np.sum(axis * torso, axis=1) / (np.linalg.norm(axis, axis=1) * np.linalg.norm(torso, axis=1) + 1e-9)
        keep = (has_feet >= 0) & (group >= 0) & (has_top >= 0) & (has_low >= 0) \
            & (feet[:, 1] - heads[:, 1] >= MIN_SPAN_PX) & (cos >= np.cos(np.radians(MAX_LEAN_DEG)))
    share = np.array([EAR, EYE, NOSE])[np.maximum(group, 0)]  # in the order of _HEADS
    ids = np.full(len(kp), -1) if tracks is None else np.asarray(tracks, int)
    return Observations(feet[keep], heads[keep], share[keep], ids[keep], np.full(int(keep.sum()), frame))


#: Pixel noise (1-sigma) and least feet-to-eyes span of :func:`rendered_observations`: the rendering
#: the calibration benchmarks chose for the KITTI drives without images (a modelled perception, not fitted
#: to a network; the span :data:`MIN_SPAN_PX` had before people under 40 px were left out).
RENDER_NOISE_PX, RENDER_MIN_SPAN_PX = 2.0, 24.0


def rendered_observations(people: Any, intrinsics: np.ndarray, rng: np.random.Generator
                          ) -> tuple[Observations, np.ndarray]:
    """Upright people rendered from labelled 3D boxes: each one's ankle and eye points (their anatomical
    shares of the box's height, :mod:`pedenv.body`) projected with ``intrinsics`` (3, 3) and
    :data:`RENDER_NOISE_PX` of Gaussian noise from ``rng``; kept where the box stands over 1 m in front
    of the camera, spans :data:`RENDER_MIN_SPAN_PX` and is at most partly occluded.

    people: labels with ``locations`` (N, 3) bottom-face centres, camera frame (x right, y down, z
    forward), ``dimensions`` (N, 3) with the height first, ``occluded``, ``track_id`` and ``frame``
    (N,) (:class:`pedenv.datasets.kitti_files.KittiLabels`). Returns the observations and the (N,) mask
    of the people kept."""
    bottom, tall = people.locations, people.dimensions[:, 0]
    feet, heads = (np.c_[bottom[:, 0], bottom[:, 1] - share * tall, bottom[:, 2]] @ intrinsics.T
                   for share in (ANKLE, EYE))
    feet, heads = feet[:, :2] / feet[:, 2:], heads[:, :2] / heads[:, 2:]
    feet = feet + rng.normal(0, RENDER_NOISE_PX, feet.shape)
    heads = heads + rng.normal(0, RENDER_NOISE_PX, heads.shape)
    seen = (bottom[:, 2] > 1.0) & (feet[:, 1] - heads[:, 1] > RENDER_MIN_SPAN_PX) & (people.occluded <= 1)
    obs = Observations(feet[seen], heads[seen], np.full(int(seen.sum()), EYE), people.track_id[seen],
                       people.frame[seen])
    return obs, seen
