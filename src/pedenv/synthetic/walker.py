"""Articulated COCO-17 walking skeletons in 3D, vectorized over pedestrians.

A person of height ``H`` is built in a body frame (x forward along the heading, y to
the person's left, z up, origin on the ground between the feet) from the body template's
proportions of ``H`` (:mod:`pedenv.body`: shoulders at 0.818 H, hip joints at 0.530 H,
knees at 0.285 H, ankles at 0.046 H, eyes at 0.933 H, nose at 0.920 H). Placing the
body-frame skeletons in the world is :func:`pedenv.body.world_keypoints`.

Walking is a gait cycle of phase ``phi`` (radians) advancing by ``2 pi`` per stride,
so it is phase-locked to the distance walked: the legs swing in anti-phase (thigh
about +-22 deg, the knee flexing in the swing phase), the arms swing against the legs
and the pelvis rides on the stance leg. ``gait`` scales the motion (0 = standing, 1 =
normal walk at 1.4 m/s); a standing person only sways slightly about the ankles.
"""

from __future__ import annotations

import numpy as np

from pedenv.body import (
    ANKLE,
    EAR,
    EAR_FORWARD,
    EAR_HALF_WIDTH,
    EYE,
    EYE_FORWARD,
    EYE_HALF_WIDTH,
    FOREARM,
    HIP,
    HIP_HALF_WIDTH,
    KNEE,
    NOSE,
    NOSE_FORWARD,
    SHOULDER,
    SHOULDER_HALF_WIDTH,
    UPPER_ARM,
)
from pedenv.skeleton import NUM_KEYPOINTS
from pedenv.skeleton import CocoKeypoint as KP

# Thigh (hip joint to knee) and shank (knee to ankle), as shares of the body height H.
THIGH, SHANK = HIP - KNEE, KNEE - ANKLE

#: Walking speed (m/s) at which ``gait`` = 1.
NORMAL_WALKING_SPEED = 1.4
THIGH_SWING_RAD = 0.38
KNEE_SWING_FLEX_RAD = 0.75
KNEE_STANCE_FLEX_RAD = 0.10
KNEE_PEAK_LEAD_RAD = 0.5  # the knee flexes most early in the swing, before the thigh passes vertical
ARM_SWING_RAD = 0.30
ELBOW_FLEX_RAD = 0.25
FORWARD_LEAN_RAD = 0.05
ARM_ABDUCTION_RAD = 0.08


def stride_length(height: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Length of one gait cycle (two steps): height (N,) m, speed (N,) m/s -> (N,) m.

    About 0.83 H at 1.4 m/s, longer when walking faster (cadence rises less than speed).
    """
    return np.asarray(height, float) * (0.55 + 0.2 * np.asarray(speed, float))


def gait_amplitude(speed: np.ndarray) -> np.ndarray:
    """Scale of the gait motion: speed (N,) m/s -> (N,) in [0, 1.3]."""
    return np.clip(np.asarray(speed, float) / NORMAL_WALKING_SPEED, 0.0, 1.3)


def body_keypoints(height: np.ndarray, phase: np.ndarray, gait: np.ndarray, sway: np.ndarray) -> np.ndarray:
    """Skeletons in their body frames.

    height: (N,) metres. phase: (N,) radians, gait phase of the left leg.
    gait: (N,) amplitude, 0 standing .. ~1.3 fast walk. sway: (N, 2) radians, lean of the
    whole body about the ankles (forward, to the left), for a standing person's sway.
    Returns (N, 17, 3) float, body frame (x forward, y left, z up), metres.
    """
    h = np.asarray(height, float)[:, None]
    a = np.asarray(gait, float)[:, None]
    phase = np.asarray(phase, float)[:, None]
    n = h.shape[0]
    side = np.array([1.0, -1.0])  # left, right: +y is the person's left
    leg_phase = phase + np.array([0.0, np.pi])  # (N, 2)
    thigh = a * THIGH_SWING_RAD * np.sin(leg_phase)
    knee_flex = a * (
        KNEE_STANCE_FLEX_RAD + KNEE_SWING_FLEX_RAD * np.maximum(np.cos(leg_phase + KNEE_PEAK_LEAD_RAD), 0.0) ** 2
    )
    shank = thigh - knee_flex
    leg_drop = THIGH * np.cos(thigh) + SHANK * np.cos(shank)  # (N, 2), in units of H
    hip_z = (ANKLE + leg_drop.max(axis=1, keepdims=True)) * h  # pelvis rides on the stance leg

    kp = np.zeros((n, NUM_KEYPOINTS, 3))
    hips = np.stack([np.zeros((n, 2)), side * HIP_HALF_WIDTH * h, np.broadcast_to(hip_z, (n, 2))], axis=-1)
    knees = hips + np.stack([THIGH * np.sin(thigh), np.zeros_like(thigh), -THIGH * np.cos(thigh)], -1) * h[..., None]
    ankles = knees + np.stack([SHANK * np.sin(shank), np.zeros_like(shank), -SHANK * np.cos(shank)], -1) * h[..., None]
    kp[:, [KP.LEFT_HIP, KP.RIGHT_HIP]] = hips
    kp[:, [KP.LEFT_KNEE, KP.RIGHT_KNEE]] = knees
    kp[:, [KP.LEFT_ANKLE, KP.RIGHT_ANKLE]] = ankles

    torso_z = hip_z + (SHOULDER - HIP) * h  # (N, 1)
    shoulders = np.stack([np.zeros((n, 2)), side * SHOULDER_HALF_WIDTH * h, np.broadcast_to(torso_z, (n, 2))], -1)
    arm = -a * ARM_SWING_RAD * np.sin(leg_phase)  # each arm swings against its own leg
    forearm = arm + ELBOW_FLEX_RAD * (0.6 + 0.4 * a) * (1.0 + 0.5 * np.sin(-leg_phase))
    elbows = shoulders + _limb(arm, side * ARM_ABDUCTION_RAD, UPPER_ARM * h)
    wrists = elbows + _limb(forearm, side * ARM_ABDUCTION_RAD / 2, FOREARM * h)
    kp[:, [KP.LEFT_SHOULDER, KP.RIGHT_SHOULDER]] = shoulders
    kp[:, [KP.LEFT_ELBOW, KP.RIGHT_ELBOW]] = elbows
    kp[:, [KP.LEFT_WRIST, KP.RIGHT_WRIST]] = wrists

    head_base = torso_z - SHOULDER * h  # the head follows the torso's bob
    face = np.array([
        [NOSE_FORWARD, 0.0, NOSE], [EYE_FORWARD, EYE_HALF_WIDTH, EYE], [EYE_FORWARD, -EYE_HALF_WIDTH, EYE],
        [EAR_FORWARD, EAR_HALF_WIDTH, EAR], [EAR_FORWARD, -EAR_HALF_WIDTH, EAR],
    ])
    kp[:, [KP.NOSE, KP.LEFT_EYE, KP.RIGHT_EYE, KP.LEFT_EAR, KP.RIGHT_EAR]] = face * h[..., None]
    kp[:, [KP.NOSE, KP.LEFT_EYE, KP.RIGHT_EYE, KP.LEFT_EAR, KP.RIGHT_EAR], 2] += head_base

    # Upper body leans forward with speed, pivoting at the hips.
    upper = [KP.NOSE, KP.LEFT_EYE, KP.RIGHT_EYE, KP.LEFT_EAR, KP.RIGHT_EAR, KP.LEFT_SHOULDER, KP.RIGHT_SHOULDER,
             KP.LEFT_ELBOW, KP.RIGHT_ELBOW, KP.LEFT_WRIST, KP.RIGHT_WRIST]
    kp[:, upper] = _tilt(kp[:, upper], FORWARD_LEAN_RAD * a[:, 0], hip_z, axis=0)
    # Sway: a small lean of the whole body about the ankles (inverted pendulum).
    sway = np.asarray(sway, float)
    kp = _tilt(kp, sway[:, 0], np.zeros((n, 1)), axis=0)
    return _tilt(kp, sway[:, 1], np.zeros((n, 1)), axis=1)


def _limb(pitch: np.ndarray, abduction: np.ndarray, length: np.ndarray) -> np.ndarray:
    """Vector of a limb hanging down, swung forward by ``pitch`` and outward by ``abduction``.

    pitch: (N, 2) radians. abduction: (2,) radians, signed (+ towards +y). length: (N, 1) m.
    Returns (N, 2, 3) body frame, metres.
    """
    ca = np.cos(abduction)
    unit = np.stack([np.sin(pitch) * ca, np.broadcast_to(np.sin(abduction), pitch.shape), -np.cos(pitch) * ca], -1)
    return unit * length[..., None]


def _tilt(points: np.ndarray, angle: np.ndarray, pivot_z: np.ndarray, axis: int) -> np.ndarray:
    """Rotate points (N, P, 3) so that up leans towards body ``axis`` (0 forward, 1 left)
    by ``angle`` (N,) radians about the horizontal line at height ``pivot_z`` (N, 1)."""
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    out = points.copy()
    dz = points[..., 2] - pivot_z
    out[..., axis] = points[..., axis] * c + dz * s
    out[..., 2] = pivot_z + dz * c - points[..., axis] * s
    return out
