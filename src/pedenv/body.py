"""The body template: where an upright adult's COCO-17 keypoints are, as shares of body height.

One set of anthropometric proportions (segment lengths after the classic Drillis & Contini
table) for everything that needs a person's shape: the synthetic walker builds its gait
on it, the fused method's height cue reads the keypoints' heights from it, and the
benchmark and tests stand people with it.

Body frame: x forward along the person's heading, y to the person's left, z up, origin
on the ground between the feet. Every number is a share of the body height ``H`` (the
top of the head is at ``H``).
"""

from __future__ import annotations

import numpy as np

from pedenv.skeleton import NUM_KEYPOINTS
from pedenv.skeleton import CocoKeypoint as KP

#: How far (metres, 1 sigma) the mean height of the people one scene shows may lie off the
#: population's, beyond their own number's spread: the labelled pedestrians' mean height (median
#: box height per track) of the KITTI ``tracking_sequences`` drives with at least 5 of them: 1.58,
#: 1.71, 1.69, 1.78, 1.85, 1.72 m (0004, 0011, 0013, 0015, 0016, 0017; 5-42 people), 0.090 m apart,
#: of which their numbers' own spread (each drive's spread of heights over its count) is 0.037 m:
#: 0.082, rounded. One offset shared by a scene's people, so no number of them fixes a height
#: better than this: the camera's self-calibration (``pedenv.calibration.fit``) and the fused
#: method's road level (``pedenv.localization.fused.road_level``) both count it.
CROWD_MEAN_STD_M = 0.08
#: Heights above the ground of an upright person, shares of H: eyes, nose, ears,
#: shoulder joints, hip joints, knees, ankles (about 0.08 m).
EYE, NOSE, EAR, SHOULDER, HIP, KNEE, ANKLE = 0.933, 0.920, 0.915, 0.818, 0.530, 0.285, 0.046
#: Half the distance between the shoulder joints and between the hip joints, shares of H.
SHOULDER_HALF_WIDTH, HIP_HALF_WIDTH = 0.110, 0.058
#: Upper arm (shoulder to elbow) and forearm (elbow to wrist), shares of H.
UPPER_ARM, FOREARM = 0.186, 0.146
#: Face offsets, shares of H: forward of the body's vertical axis and to the side.
NOSE_FORWARD, EYE_FORWARD, EYE_HALF_WIDTH, EAR_FORWARD, EAR_HALF_WIDTH = 0.052, 0.040, 0.019, -0.004, 0.044


def _standing_template() -> np.ndarray:
    t = np.zeros((NUM_KEYPOINTS, 3))
    for left, right, forward, half_width, height in (
            (KP.LEFT_EYE, KP.RIGHT_EYE, EYE_FORWARD, EYE_HALF_WIDTH, EYE),
            (KP.LEFT_EAR, KP.RIGHT_EAR, EAR_FORWARD, EAR_HALF_WIDTH, EAR),
            (KP.LEFT_SHOULDER, KP.RIGHT_SHOULDER, 0.0, SHOULDER_HALF_WIDTH, SHOULDER),
            (KP.LEFT_ELBOW, KP.RIGHT_ELBOW, 0.0, SHOULDER_HALF_WIDTH, SHOULDER - UPPER_ARM),
            (KP.LEFT_WRIST, KP.RIGHT_WRIST, 0.0, SHOULDER_HALF_WIDTH, SHOULDER - UPPER_ARM - FOREARM),
            (KP.LEFT_HIP, KP.RIGHT_HIP, 0.0, HIP_HALF_WIDTH, HIP),
            (KP.LEFT_KNEE, KP.RIGHT_KNEE, 0.0, HIP_HALF_WIDTH, KNEE),
            (KP.LEFT_ANKLE, KP.RIGHT_ANKLE, 0.0, HIP_HALF_WIDTH, ANKLE)):
        t[left] = forward, half_width, height
        t[right] = forward, -half_width, height
    t[KP.NOSE] = NOSE_FORWARD, 0.0, NOSE
    t.setflags(write=False)
    return t


#: (17, 3) body frame, shares of H: a person standing upright, legs straight under the
#: hips, arms hanging straight down from the shoulders.
STANDING = _standing_template()


def standing_body(height: float | np.ndarray) -> np.ndarray:
    """Body-frame skeletons of upright people: height (N,) metres -> (N, 17, 3) metres."""
    return STANDING * np.asarray(height, float)[:, None, None]


def world_keypoints(ground: np.ndarray, heading: np.ndarray, body: np.ndarray) -> np.ndarray:
    """Place body-frame skeletons in the world (upright, turned to their heading).

    ground: (N, 3) world frame, metres: the ground point under each person.
    heading: (N,) radians, counter-clockwise from world +x. body: (N, 17, 3) body frame.
    Returns (N, 17, 3) world frame, metres.
    """
    c, s = np.cos(heading)[:, None], np.sin(heading)[:, None]
    x, y, z = body[..., 0], body[..., 1], body[..., 2]
    return np.stack([c * x - s * y, s * x + c * y, z], axis=-1) + np.asarray(ground, float)[:, None, :]
