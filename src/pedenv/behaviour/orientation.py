"""Body orientation cues: what one frame's skeleton and the track's velocity say about the body's yaw.

Angles: ``yaw`` is the direction the body faces, world frame, radians counter-clockwise from
+x seen from above. Seen from the camera, a body facing ``f`` shows its shoulder line
(left minus right) across the viewing ray with the length ``cos(a)`` times the shoulder
width, where ``a`` is the angle between ``f`` and the direction from the person to the camera
(``toward``); the nose sits ahead of the ears, so it appears shifted sideways by
``sin(a)`` times its full-profile offset, towards the side ``right`` (the image's right
seen from the camera: ``toward`` turned by +90 degrees). Both are measured in metres by
cutting the keypoints' viewing rays at the person's range. Each cue is a likelihood over
the cells of the heading filter (:mod:`pedenv.behaviour.heading_filter`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.behaviour.config import BehaviourConfig
from pedenv.body import EAR_FORWARD, HIP_HALF_WIDTH, NOSE_FORWARD, SHOULDER_HALF_WIDTH
from pedenv.skeleton import CocoKeypoint as KP

#: A cell's likelihood never falls below this share of the best one (an outlier never rules a heading out).
LIKELIHOOD_FLOOR = 0.02


@dataclass(frozen=True)
class SkeletonCue:
    """One frame's skeleton cue for N people.

    toward: (N, 2) unit, world x-y, from the person to the camera. right: (N, 2) unit, world
    x-y, ``toward`` turned by +90 degrees. width: (N,) the apparent width ratio ``cos(a)``
    (shoulders and hips), width_std (N,) its spread, NaN-free; width_ok (N,) bool.
    face: (N,) the nose's sideways offset ratio ``sin(a)``, face_std (N,), face_ok (N,) bool.
    face_seen: (N,) in [0, 1], how clearly the network sees the face (the smallest confidence
    of the nose and both eyes).
    """

    toward: np.ndarray
    right: np.ndarray
    width: np.ndarray
    width_std: np.ndarray
    width_ok: np.ndarray
    face: np.ndarray
    face_std: np.ndarray
    face_ok: np.ndarray
    face_seen: np.ndarray


def viewing_axes(positions: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``toward`` (N, 2) and ``right`` (N, 2) unit vectors of people at positions (N, 3) world,
    metres, seen from a camera at ``origin`` (3,) (see the module docstring)."""
    d = origin[None, :2] - positions[:, :2]
    norm = np.linalg.norm(d, axis=1, keepdims=True)
    toward = np.where(norm > 1e-6, d / np.maximum(norm, 1e-6), np.array([1.0, 0.0]))
    return toward, np.column_stack([-toward[:, 1], toward[:, 0]])


def skeleton_cue(rays: np.ndarray, confidences: np.ndarray, positions: np.ndarray, origin: np.ndarray,
                 focal_px: float, config: BehaviourConfig) -> SkeletonCue:
    """The skeleton cue of N people.

    rays: (N, 17, 3) unit viewing rays of the keypoints, world frame. confidences: (N, 17).
    positions: (N, 3) the people's ground points, world, metres. origin: (3,) camera centre.
    focal_px: the camera's focal length in pixels (turns pixel noise into metres).
    """
    toward, right = viewing_axes(positions, origin)
    bearing = -toward
    rng = np.maximum(np.linalg.norm(positions[:, :2] - origin[None, :2], axis=1), 0.5)
    along = rays[..., 0] * bearing[:, None, 0] + rays[..., 1] * bearing[:, None, 1]
    cut = origin + (rng[:, None] / np.maximum(along, 0.05))[..., None] * rays  # (N, 17, 3)
    lateral = cut[..., 0] * right[:, None, 0] + cut[..., 1] * right[:, None, 1]  # (N, 17) metres
    ok = (confidences >= config.min_keypoint_confidence) & (along > 0.05)
    pixel_m = config.keypoint_pixel_std * rng / focal_px  # one keypoint's noise in metres at the range
    h = config.person_height_m
    ratios, weights = [], []
    for left, right_kp, half in ((KP.LEFT_SHOULDER, KP.RIGHT_SHOULDER, SHOULDER_HALF_WIDTH),
                                 (KP.LEFT_HIP, KP.RIGHT_HIP, HIP_HALF_WIDTH)):
        width_m = 2.0 * half * h
        both = ok[:, left] & ok[:, right_kp]
        ratios.append(np.where(both, (lateral[:, left] - lateral[:, right_kp]) / width_m, 0.0))
        var = config.width_ratio_std**2 + 2.0 * (pixel_m / width_m) ** 2
        weights.append(np.where(both, 1.0 / var, 0.0))
    w = weights[0] + weights[1]
    width_ok = w > 0
    width = np.clip((ratios[0] * weights[0] + ratios[1] * weights[1]) / np.maximum(w, 1e-12), -1.2, 1.2)
    width_std = np.where(width_ok, 1.0 / np.sqrt(np.maximum(w, 1e-12)), 1.0)
    face, face_std, face_ok = _face_offset(lateral, ok, pixel_m, config)
    face_seen = confidences[:, [KP.NOSE, KP.LEFT_EYE, KP.RIGHT_EYE]].min(axis=1)
    return SkeletonCue(toward, right, width, width_std, width_ok, face, face_std, face_ok,
                       np.clip(np.where(np.isnan(face_seen), 0.0, face_seen), 0.0, 1.0))


def _face_offset(lateral: np.ndarray, ok: np.ndarray, pixel_m: np.ndarray,
                 config: BehaviourConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The nose's sideways offset ratio (N,) from the ears' midpoint (both ears seen) or else
    the shoulders' midpoint, its spread (N,) and where it exists (N,) bool."""
    h = config.person_height_m
    ears = ok[:, KP.LEFT_EAR] & ok[:, KP.RIGHT_EAR]
    shoulders = ok[:, KP.LEFT_SHOULDER] & ok[:, KP.RIGHT_SHOULDER]
    ear_mid = 0.5 * (lateral[:, KP.LEFT_EAR] + lateral[:, KP.RIGHT_EAR])
    shoulder_mid = 0.5 * (lateral[:, KP.LEFT_SHOULDER] + lateral[:, KP.RIGHT_SHOULDER])
    full = np.where(ears, NOSE_FORWARD - EAR_FORWARD, NOSE_FORWARD) * h  # the offset in full profile, metres
    offset = lateral[:, KP.NOSE] - np.where(ears, ear_mid, shoulder_mid)
    face_ok = ok[:, KP.NOSE] & (ears | shoulders)
    face = np.where(face_ok, np.clip(offset / full, -1.5, 1.5), 0.0)
    std = np.sqrt(config.face_offset_std**2 + 1.5 * (pixel_m / full) ** 2)
    return face, std, face_ok


def skeleton_likelihood(cue: SkeletonCue, cells: np.ndarray, config: BehaviourConfig) -> np.ndarray:
    """(N, B) likelihood of the heading cells ``cells`` (B,) radians, world, from the skeleton cue.

    The width ratio constrains ``cos(a)`` (a mixture with the mirrored ratio for a swap of
    left and right), the face offset ``sin(a)``; a row with neither is flat (all ones).
    """
    c, s = np.cos(cells), np.sin(cells)
    cos_a = cue.toward[:, :1] * c + cue.toward[:, 1:] * s  # (N, B)
    sin_a = cue.right[:, :1] * c + cue.right[:, 1:] * s
    p = config.left_right_swap_probability
    z = ((cos_a - cue.width[:, None]) / cue.width_std[:, None]) ** 2
    zm = ((cos_a + cue.width[:, None]) / cue.width_std[:, None]) ** 2
    width = (1.0 - p) * np.exp(-0.5 * z) + p * np.exp(-0.5 * zm)
    face = np.exp(-0.5 * ((sin_a - cue.face[:, None]) / cue.face_std[:, None]) ** 2)
    like = np.where(cue.width_ok[:, None], width, 1.0) * np.where(cue.face_ok[:, None], face, 1.0)
    return _floored(like)


def motion_likelihood(velocities: np.ndarray, velocity_covariances: np.ndarray, cells: np.ndarray,
                      config: BehaviourConfig) -> tuple[np.ndarray, np.ndarray]:
    """(N, B) likelihood of the cells from the walking direction, and (N,) bool where it is a cue.

    velocities: (N, 2) world x-y, m/s; velocity_covariances: (N, 2, 2) (m/s)^2. The walking
    direction counts once the speed is above ``min_walking_speed_mps`` and ``speed_sigmas``
    standard deviations; its spread is the direction's own plus ``walking_direction_std_deg``.
    """
    speed = np.linalg.norm(velocities, axis=1)
    unit = velocities / np.maximum(speed, 1e-9)[:, None]
    var_along = np.einsum("ni,nij,nj->n", unit, velocity_covariances, unit)
    normal = np.column_stack([-unit[:, 1], unit[:, 0]])
    var_across = np.einsum("ni,nij,nj->n", normal, velocity_covariances, normal)
    use = (speed > config.min_walking_speed_mps) & (speed > config.speed_sigmas * np.sqrt(np.maximum(var_along, 0.0)))
    spread = np.radians(config.walking_direction_std_deg) ** 2 + var_across / np.maximum(speed, 1e-9) ** 2
    direction = np.arctan2(unit[:, 1], unit[:, 0])
    kappa = 1.0 / np.maximum(spread, 1e-6)
    like = np.exp(np.minimum(kappa, 1e4)[:, None] * (np.cos(cells[None, :] - direction[:, None]) - 1.0))
    return np.where(use[:, None], _floored(like), 1.0), use


def _floored(like: np.ndarray) -> np.ndarray:
    top = like.max(axis=1, keepdims=True)
    return np.maximum(like, LIKELIHOOD_FLOOR * np.maximum(top, 1e-300))
