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

import math
from dataclasses import dataclass

import numpy as np

from pedenv.behaviour.motion_state import SPEED_SIGMAS, VelocityStats, velocity_stats
from pedenv.body import EAR_FORWARD, HIP_HALF_WIDTH, NOSE_FORWARD, SHOULDER_HALF_WIDTH
from pedenv.skeleton import CocoKeypoint as KP

#: A cell's likelihood never falls below this share of the best one (an outlier never rules a heading out).
LIKELIHOOD_FLOOR = 0.02
#: The body height (metres) the expected shoulder, hip and face widths are scaled from: the adult
#: mean of the anthropometric tables (:mod:`pedenv.synthetic.population`, the fused height prior).
PERSON_HEIGHT_M = 1.72
#: Pixel noise of one keypoint (1 sigma, u and v): turns the widths' pixel noise into the spread
#: of their ratios; the fused method's prior (``fused.keypoint_pixel_std``) for the same networks.
KEYPOINT_PIXEL_STD = 3.0
#: Keypoints below this confidence are not used by the skeleton cue (the fused cues' default).
MIN_KEYPOINT_CONFIDENCE = 0.3
#: Spread of the apparent shoulder (hip) width as a share of the width expected at the person's
#: range, beyond pixel noise (body shape, arms, a twisted torso); set on the built-in scenes'
#: rendered skeletons and checked on the real KITTI persons (``benchmarks/behaviour_real.py``).
WIDTH_RATIO_STD = 0.25
#: Spread of the nose's sideways offset from the ears (or shoulders) as a share of the offset in
#: full profile (head turns against the body, the keypoints' placement); set with the width's.
FACE_OFFSET_STD = 0.5
#: How often the pose network swaps a person's left and right: the weight of the mirrored angle in
#: the width's likelihood, so front and back stay open until the face or the walk decides.
LEFT_RIGHT_SWAP_PROBABILITY = 0.1
#: How far (degrees, 1 sigma) the body may face away from its walking direction (sidesteps,
#: looking around while walking).
WALKING_DIRECTION_STD_DEG = 20.0
#: The walking direction is a cue only above this filtered speed (m/s), below a slow walk
#: (about 1.4 m/s), where a standing person's filter noise would point it anywhere.
MIN_WALKING_SPEED_MPS = 0.5


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


#: The keypoints the skeleton cue measures, in the order of :func:`cue_from_rays`'s rays: the
#: left shoulder and hip, the right shoulder and hip, the nose and the left and right ear.
CUE_KEYPOINTS = np.array([KP.LEFT_SHOULDER, KP.LEFT_HIP, KP.RIGHT_SHOULDER, KP.RIGHT_HIP, KP.NOSE, KP.LEFT_EAR,
                          KP.RIGHT_EAR])
_ONES3 = np.ones(3)
_HALF_WIDTHS = np.array([SHOULDER_HALF_WIDTH, HIP_HALF_WIDTH])
_AXES = (np.array([[0, 1], [1, 0]]), np.array([[-1.0, -1.0], [-1.0, 1.0]]))  # toward -> [bearing, right] columns


def _toward(positions: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``toward`` (N, 2) unit and the ground distance (N,) metres from the camera."""
    d = origin[:2] - positions[:, :2]
    norm = np.hypot(d[:, 0], d[:, 1])
    toward = d / np.maximum(norm, 1e-6)[:, None]
    if len(norm) and norm.min() <= 1e-6:
        toward[norm <= 1e-6] = (1.0, 0.0)
    return toward, norm


def skeleton_cue(rays: np.ndarray, confidences: np.ndarray, positions: np.ndarray, origin: np.ndarray,
                 focal_px: float) -> SkeletonCue:
    """The skeleton cue of N people.

    rays: (N, 17, 3) unit viewing rays of the keypoints, world frame. confidences: (N, 17).
    positions: (N, 3) the people's ground points, world, metres. origin: (3,) camera centre.
    focal_px: the camera's focal length in pixels (turns pixel noise into metres).
    """
    return cue_from_rays(rays[:, CUE_KEYPOINTS], confidences, positions, origin, focal_px)


def cue_from_rays(rays: np.ndarray, confidences: np.ndarray, positions: np.ndarray, origin: np.ndarray,
                  focal_px: float) -> SkeletonCue:
    """:func:`skeleton_cue` from the viewing rays (N, 7, 3), world frame, of the
    :data:`CUE_KEYPOINTS` only (the others are not needed; the rays need not be unit vectors);
    confidences (N, 17) of all keypoints."""
    toward, dist = _toward(positions, origin)
    rng = np.maximum(dist, 0.5)
    # each ray's component along the bearing (away from the camera) and to the right
    length = np.sqrt((rays * rays) @ _ONES3)
    proj = (rays[..., :2] @ (toward[:, _AXES[0]] * _AXES[1])) / length[..., None]  # (N, 7, 2)
    along = proj[..., 0]
    # the sideways offset (metres, N x 7) where the ray meets the person's range, less the camera's
    # own (which cancels in every difference taken below)
    lateral = (rng[:, None] / np.maximum(along, 0.05)) * proj[..., 1]
    ok = (confidences[:, CUE_KEYPOINTS] >= MIN_KEYPOINT_CONFIDENCE) & (along > 0.05)
    pixel_m = KEYPOINT_PIXEL_STD * rng / focal_px  # one keypoint's noise in metres at the range
    width_m = (2.0 * PERSON_HEIGHT_M) * _HALF_WIDTHS  # shoulders, hips
    both = ok[:, 0:2] & ok[:, 2:4]
    ratios = np.where(both, (lateral[:, 0:2] - lateral[:, 2:4]) / width_m, 0.0)
    weights = np.where(both, 1.0 / (WIDTH_RATIO_STD**2 + 2.0 * (pixel_m[:, None] / width_m) ** 2), 0.0)
    w = weights[:, 0] + weights[:, 1]  # (a reduction over a last axis of 2 is slow)
    width_ok = w > 0
    weighted = ratios * weights
    w_safe = np.maximum(w, 1e-12)
    width = np.minimum(np.maximum((weighted[:, 0] + weighted[:, 1]) / w_safe, -1.2), 1.2)
    width_std = np.where(width_ok, 1.0 / np.sqrt(w_safe), 1.0)
    face, face_std, face_ok = _face_offset(lateral, ok, pixel_m)
    seen = np.minimum(np.minimum(confidences[:, KP.NOSE], confidences[:, KP.LEFT_EYE]), confidences[:, KP.RIGHT_EYE])
    face_seen = np.minimum(np.fmax(seen, 0.0), 1.0)  # NaN -> 0
    return SkeletonCue(toward, toward[:, ::-1] * _AXES[1][1], width, width_std, width_ok, face, face_std, face_ok,
                       face_seen)


def _face_offset(lateral: np.ndarray, ok: np.ndarray, pixel_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The nose's sideways offset ratio (N,) from the ears' midpoint (both ears seen) or else
    the shoulders' midpoint, its spread (N,) and where it exists (N,) bool. lateral, ok: (N, 7)
    in the order of :data:`CUE_KEYPOINTS`."""
    h = PERSON_HEIGHT_M
    ears = ok[:, 5] & ok[:, 6]
    face_ok = ok[:, 4] & (ears | (ok[:, 0] & ok[:, 2]))
    mid = 0.5 * np.where(ears, lateral[:, 5] + lateral[:, 6], lateral[:, 0] + lateral[:, 2])
    full = np.where(ears, (NOSE_FORWARD - EAR_FORWARD) * h, NOSE_FORWARD * h)  # the offset in full profile, metres
    face = np.where(face_ok, np.minimum(np.maximum((lateral[:, 4] - mid) / full, -1.5), 1.5), 0.0)
    std = np.sqrt(FACE_OFFSET_STD**2 + 1.5 * (pixel_m / full) ** 2)
    return face, std, face_ok


def keypoint_rays(keypoints: np.ndarray, inverse_intrinsics: np.ndarray, cam_to_world: np.ndarray) -> np.ndarray:
    """Viewing rays (N, J, 3), world frame, not of unit length, of pixels (N, J, 2) (the camera's
    inverse intrinsics (3, 3), its (4, 4) camera-to-world transform): :func:`pedenv.geometry.pixel_rays`
    without the normalisation :func:`cue_from_rays` does itself."""
    m = cam_to_world[:3, :3] @ inverse_intrinsics
    return keypoints @ m[:, :2].T + m[:, 2]


def skeleton_likelihood(cue: SkeletonCue, cells: np.ndarray) -> np.ndarray:
    """(N, B) likelihood of the heading cells ``cells`` (B,) radians, world, from the skeleton cue.

    The width ratio constrains ``cos(a)`` (a mixture with the mirrored ratio for a swap of
    left and right), the face offset ``sin(a)``; a row with neither is flat (all ones).
    """
    cos_sin = np.stack([np.cos(cells), np.sin(cells)])
    return cue_likelihood(cue, cue.toward @ cos_sin, cue.right @ cos_sin)


def cue_likelihood(cue: SkeletonCue, cos_a: np.ndarray, sin_a: np.ndarray) -> np.ndarray:
    """:func:`skeleton_likelihood` from ``cos(a)`` and ``sin(a)`` (N, B) of each cell."""
    p = LEFT_RIGHT_SWAP_PROBABILITY
    k = np.where(cue.width_ok, -0.5 / cue.width_std**2, 0.0)[:, None]  # a row without the cue: exp(0)
    width = cue.width[:, None]
    a, b, c = cos_a - width, cos_a + width, sin_a - cue.face[:, None]
    face = c * c * np.where(cue.face_ok, -0.5 / cue.face_std**2, 0.0)[:, None]  # the face's exponent
    like = (1.0 - p) * np.exp(a * a * k + face)
    like += p * np.exp(b * b * k + face)
    return _floored(like)


def motion_likelihood(velocities: np.ndarray, velocity_covariances: np.ndarray, cells: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """(N, B) likelihood of the cells from the walking direction, and (N,) bool where it is a cue.

    velocities: (N, 2) world x-y, m/s; velocity_covariances: (N, 2, 2) (m/s)^2. The walking
    direction counts once the speed is above :data:`MIN_WALKING_SPEED_MPS` and
    :data:`~pedenv.behaviour.motion_state.SPEED_SIGMAS` standard deviations; its spread is the
    direction's own plus :data:`WALKING_DIRECTION_STD_DEG`.
    """
    v = velocity_stats(velocities, velocity_covariances)
    return walking_likelihood(v, np.stack([np.cos(cells), np.sin(cells)]))


def walking_likelihood(v: VelocityStats, cos_sin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`motion_likelihood` from the velocities' :class:`VelocityStats` and the cells'
    cosines and sines (2, B)."""
    speed = v.speed
    use = (speed > MIN_WALKING_SPEED_MPS) & (speed > SPEED_SIGMAS * np.sqrt(np.maximum(v.var_along, 0.0)))
    spread = math.radians(WALKING_DIRECTION_STD_DEG) ** 2 + v.var_across() / np.maximum(speed, 1e-9) ** 2
    kappa = np.where(use, np.minimum(1.0 / np.maximum(spread, 1e-6), 1e4), 0.0)[:, None]  # unused: exp(0)
    return _floored(np.exp(kappa * (v.unit() @ cos_sin - 1.0))), use


def _floored(like: np.ndarray) -> np.ndarray:
    top = like.max(axis=1, keepdims=True)
    return np.maximum(like, LIKELIHOOD_FLOOR * np.maximum(top, 1e-300))
