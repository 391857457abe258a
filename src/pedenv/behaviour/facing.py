"""Facing the ego: is the body (and, where the face shows, the head) turned towards the ego camera?"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr

from pedenv.behaviour.orientation import SkeletonCue


def body_facing_from(p: np.ndarray, cos_a: np.ndarray, cos_half_angle: float) -> np.ndarray:
    """(N,) probability that the body faces the camera: the share of the heading distribution
    p (N, B) within the half angle of the direction to the camera, from ``cos(a)`` (N, B) of each
    cell (the cosine of its angle to that direction): the cells with ``cos(a) >= cos(half_angle)``."""
    return np.minimum((p * (cos_a >= cos_half_angle)).sum(axis=1), 1.0)


def head_facing(cue: SkeletonCue, half_angle: float) -> np.ndarray:
    """(N,) probability that the head faces the camera, from this frame's face keypoints.

    How clearly the face is seen (the smallest confidence of nose and eyes) times the chance
    that the nose's sideways offset ratio ``sin(a)`` lies within ``sin(half_angle)``; a face
    not seen, or with no offset measured, is not turned towards the camera (0).
    """
    limit = np.sin(half_angle)
    inside = ndtr((limit - cue.face) / cue.face_std) - ndtr((-limit - cue.face) / cue.face_std)
    return np.where(cue.face_ok, np.clip(cue.face_seen * inside, 0.0, 1.0), 0.0)
