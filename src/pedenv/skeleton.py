"""The one skeleton layout used everywhere in pedenv: COCO-17.

Adapters with another layout (CARLA's 20 bones) map to this one at the boundary.
"""

from __future__ import annotations

from enum import IntEnum

NUM_KEYPOINTS = 17


class CocoKeypoint(IntEnum):
    """Index of each COCO-17 keypoint; left and right are the person's own."""

    NOSE = 0
    LEFT_EYE = 1
    RIGHT_EYE = 2
    LEFT_EAR = 3
    RIGHT_EAR = 4
    LEFT_SHOULDER = 5
    RIGHT_SHOULDER = 6
    LEFT_ELBOW = 7
    RIGHT_ELBOW = 8
    LEFT_WRIST = 9
    RIGHT_WRIST = 10
    LEFT_HIP = 11
    RIGHT_HIP = 12
    LEFT_KNEE = 13
    RIGHT_KNEE = 14
    LEFT_ANKLE = 15
    RIGHT_ANKLE = 16


K = CocoKeypoint

#: Limbs drawn between keypoints, as index pairs.
COCO_BONES: tuple[tuple[int, int], ...] = (
    (K.LEFT_ANKLE, K.LEFT_KNEE), (K.LEFT_KNEE, K.LEFT_HIP),
    (K.RIGHT_ANKLE, K.RIGHT_KNEE), (K.RIGHT_KNEE, K.RIGHT_HIP),
    (K.LEFT_HIP, K.RIGHT_HIP), (K.LEFT_SHOULDER, K.LEFT_HIP), (K.RIGHT_SHOULDER, K.RIGHT_HIP),
    (K.LEFT_SHOULDER, K.RIGHT_SHOULDER), (K.LEFT_SHOULDER, K.LEFT_ELBOW),
    (K.LEFT_ELBOW, K.LEFT_WRIST), (K.RIGHT_SHOULDER, K.RIGHT_ELBOW),
    (K.RIGHT_ELBOW, K.RIGHT_WRIST), (K.NOSE, K.LEFT_EYE), (K.NOSE, K.RIGHT_EYE),
    (K.LEFT_EYE, K.LEFT_EAR), (K.RIGHT_EYE, K.RIGHT_EAR), (K.LEFT_EAR, K.LEFT_SHOULDER),
    (K.RIGHT_EAR, K.RIGHT_SHOULDER),
)

KEYPOINT_NAMES: tuple[str, ...] = tuple(k.name.lower() for k in CocoKeypoint)

#: Keypoints at the top of the body (head) and at its bottom (ankles).
HEAD_KEYPOINTS: tuple[int, ...] = (K.NOSE, K.LEFT_EYE, K.RIGHT_EYE, K.LEFT_EAR, K.RIGHT_EAR)
ANKLE_KEYPOINTS: tuple[int, ...] = (K.LEFT_ANKLE, K.RIGHT_ANKLE)
