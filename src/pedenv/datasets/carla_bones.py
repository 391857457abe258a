"""CARLA's 20 pedestrian bones and their mapping to and from COCO-17.

Left and right are the pedestrian's own in both layouts. COCO's nose comes from CARLA's head
bone (the centre of the head, a few centimetres behind the face), its ears have no CARLA bone
and are marked not visible; CARLA's hips/spine/clavicle bones have no COCO counterpart and are
synthesized from the COCO joints when writing.
"""

from __future__ import annotations

import numpy as np

from pedenv.skeleton import NUM_KEYPOINTS
from pedenv.skeleton import CocoKeypoint as KP

#: The 20 bones of a recording, in the order of ``2d_skel`` / ``3d_skel``.
BONE_NAMES: tuple[str, ...] = (
    "hips", "spine", "spine01", "shoulder_L", "arm_L", "foreArm_L", "hand_L", "head", "eye_L", "eye_R",
    "shoulder_R", "arm_R", "foreArm_R", "hand_R", "thigh_R", "leg_R", "foot_R", "thigh_L", "leg_L", "foot_L",
)
NUM_BONES = len(BONE_NAMES)
B = {name: i for i, name in enumerate(BONE_NAMES)}

#: COCO keypoint -> the bone it is read from (ears read the head bone but are never visible).
COCO_FROM_BONE: np.ndarray = np.array([
    B["head"], B["eye_L"], B["eye_R"], B["head"], B["head"],
    B["arm_L"], B["arm_R"], B["foreArm_L"], B["foreArm_R"], B["hand_L"], B["hand_R"],
    B["thigh_L"], B["thigh_R"], B["leg_L"], B["leg_R"], B["foot_L"], B["foot_R"],
])
assert len(COCO_FROM_BONE) == NUM_KEYPOINTS

#: COCO keypoints that are the same joint as their bone (they survive a write and a read);
#: the nose (read from the head's centre) and the ears are not.
EXACT_KEYPOINTS: np.ndarray = np.array([k for k in range(NUM_KEYPOINTS)
                                        if k not in (KP.NOSE, KP.LEFT_EAR, KP.RIGHT_EAR)])

#: Where the clavicle bones sit between the neck (mid-shoulder) and the shoulder joint.
CLAVICLE_FRACTION = 0.5


def bones_to_coco(bones: np.ndarray) -> np.ndarray:
    """(N, 20, D) CARLA bones -> (N, 17, D) COCO keypoints (any D: pixels or metres)."""
    return np.asarray(bones, float)[:, COCO_FROM_BONE]


def visible_keypoints(bones_2d: np.ndarray, width: int, height: int) -> np.ndarray:
    """(N, 17) bool: COCO keypoints seen in the image.

    bones_2d: (N, 20, 2) pixels as recorded, clamped to ``[0, width - 1] x [0, height - 1]``.
    A point on the border was clamped (it lies outside the image) and counts as not seen;
    ears have no bone and are never seen.
    """
    uv = bones_to_coco(bones_2d)
    inside = (uv[..., 0] > 0) & (uv[..., 0] < width - 1) & (uv[..., 1] > 0) & (uv[..., 1] < height - 1)
    inside[:, [KP.LEFT_EAR, KP.RIGHT_EAR]] = False
    return inside


def coco_to_bones(keypoints_3d: np.ndarray) -> np.ndarray:
    """(N, 17, 3) COCO keypoints, metres -> (N, 20, 3) CARLA bones in the same frame.

    hips = mid-hip; spine and spine01 at 1/3 and 2/3 from the hips to the mid-shoulder;
    clavicles half-way from the mid-shoulder to each shoulder; head = mid-ear (the head's
    centre); all other bones are their COCO joint.
    """
    kp = np.asarray(keypoints_3d, float)
    bones = np.zeros((kp.shape[0], NUM_BONES, kp.shape[2]))
    for coco, bone in enumerate(COCO_FROM_BONE):
        if coco not in (KP.NOSE, KP.LEFT_EAR, KP.RIGHT_EAR):
            bones[:, bone] = kp[:, coco]
    hips = 0.5 * (kp[:, KP.LEFT_HIP] + kp[:, KP.RIGHT_HIP])
    neck = 0.5 * (kp[:, KP.LEFT_SHOULDER] + kp[:, KP.RIGHT_SHOULDER])
    bones[:, B["hips"]] = hips
    bones[:, B["spine"]] = hips + (neck - hips) / 3.0
    bones[:, B["spine01"]] = hips + 2.0 * (neck - hips) / 3.0
    bones[:, B["shoulder_L"]] = neck + CLAVICLE_FRACTION * (kp[:, KP.LEFT_SHOULDER] - neck)
    bones[:, B["shoulder_R"]] = neck + CLAVICLE_FRACTION * (kp[:, KP.RIGHT_SHOULDER] - neck)
    bones[:, B["head"]] = 0.5 * (kp[:, KP.LEFT_EAR] + kp[:, KP.RIGHT_EAR])
    return bones
