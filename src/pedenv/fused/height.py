"""Height cue: keypoints whose height above the ground is a known share of body height.

An upright person of height ``H`` at horizontal range ``r`` puts keypoint ``k`` (height
``f_k H`` above its own ground, ``c`` below the camera) on a ray whose elevation has

    tan_k = c / r + (H / r) f_k        (one row per seen keypoint of the table below)

A weighted straight-line fit of ``tan_k`` over ``f_k`` gives the slope ``H / r`` without
assuming where the ground is (so rolling terrain does not bias it); the rows' noise is
the pixel noise plus the spread of the fraction (head tilt, pelvis bob). Of two seen
ankles only the lower (the stance foot) is used; a lone ankle may be lifted and counts less. The spread
of human heights (``person_height_std_m``, about 5 %) scales the range as a whole.
"""

from __future__ import annotations

import numpy as np

from pedenv.config import FusedConfig
from pedenv.fused.cue import (CueEstimate, across_variance, first_reason, horizontal_bearing,
                              range_bearing_covariance, stance_ankle)
from pedenv.skeleton import ANKLE_KEYPOINTS, NUM_KEYPOINTS, CocoKeypoint as K

NAME = "height"

#: Height above the ground of an upright adult's keypoints, as a share of body height
#: (segment proportions after Drillis & Contini); NaN: no fixed height (knees, arms).
KEYPOINT_HEIGHT_FRACTION = np.full(NUM_KEYPOINTS, np.nan)
#: Spread of each fraction (head tilt, shoulders and pelvis riding on the gait, a foot
#: lifted in the swing phase), as a share of body height.
KEYPOINT_FRACTION_STD = np.full(NUM_KEYPOINTS, np.nan)
for _k, _f, _s in ((K.NOSE, 0.920, 0.012), (K.LEFT_EYE, 0.933, 0.012), (K.RIGHT_EYE, 0.933, 0.012),
                   (K.LEFT_EAR, 0.915, 0.012), (K.RIGHT_EAR, 0.915, 0.012), (K.LEFT_SHOULDER, 0.818, 0.012),
                   (K.RIGHT_SHOULDER, 0.818, 0.012), (K.LEFT_HIP, 0.530, 0.015), (K.RIGHT_HIP, 0.530, 0.015),
                   (K.LEFT_ANKLE, 0.046, 0.025), (K.RIGHT_ANKLE, 0.046, 0.025)):
    KEYPOINT_HEIGHT_FRACTION[_k], KEYPOINT_FRACTION_STD[_k] = _f, _s
#: Spread of a lone ankle's fraction: with the other ankle unseen it may be the swing
#: foot, lifted up to ~0.15 (of two seen ankles only the lower, the stance foot, is used).
LONE_ANKLE_FRACTION_STD = 0.025
#: Keypoints the height cue can use.
HEIGHT_KEYPOINTS = np.flatnonzero(np.isfinite(KEYPOINT_HEIGHT_FRACTION))
#: The used keypoints must span at least this share of body height (e.g. head to hips).
MIN_FRACTION_SPAN = 0.25
#: Reweighting passes of the least squares (the row noise depends on the range).
PASSES = 2


def elevation_tangents(rays: np.ndarray) -> np.ndarray:
    """tan of each ray's elevation above the world horizontal: (..., 3) unit -> (...,)."""
    return rays[..., 2] / np.maximum(np.linalg.norm(rays[..., :2], axis=-1), 1e-9)


def solve_range(tangents: np.ndarray, fractions: np.ndarray, fraction_std: np.ndarray, used: np.ndarray,
                height_m: np.ndarray, angle_std: float):
    """Fit ``tan_k = alpha + beta f_k`` for N people; the range is ``r = H / beta``.

    The elevations are the noisy side, so they are the dependent variable (fitting the
    ranges the other way round would shrink them towards the camera as noise grows).
    tangents, fractions, fraction_std: (N, K). used: (N, K) bool. height_m: (N,) metres.
    angle_std: noise of ``tan`` per keypoint (pixel noise / focal length).
    Returns ``(r (N,), var_r (N,))``: horizontal range in metres and its variance from the
    rows' noise (not yet the spread of heights); NaN where the rows do not determine it.
    """
    beta = np.zeros(len(tangents))
    for _ in range(PASSES):  # the fraction's spread shows in tan scaled by the slope
        noise = angle_std**2 + (fraction_std * beta[:, None]) ** 2
        w = np.where(used, 1.0 / np.maximum(noise, 1e-18), 0.0)
        sw, sf, sff = w.sum(1), (w * fractions).sum(1), (w * fractions**2).sum(1)
        st, sft = (w * tangents).sum(1), (w * fractions * tangents).sum(1)
        det = sw * sff - sf * sf
        ok = det > 1e-12 * np.maximum(sw * sff, 1e-300)
        safe = np.where(ok, det, 1.0)
        beta = np.where(ok, (sw * sft - sf * st) / safe, 0.0)
    var_beta = sw / safe
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(ok & (beta > 0), height_m / beta, np.nan)
        var = r**2 * var_beta / beta**2
    return r, var


def height_cue(keypoints_usable: np.ndarray, rays: np.ndarray, origin: np.ndarray, focal_px: float,
               config: FusedConfig, height_mean: np.ndarray | None = None,
               height_std: np.ndarray | None = None, reference_range: np.ndarray | None = None) -> CueEstimate:
    """Ground point of N pedestrians from the known body-height shares of their keypoints.

    keypoints_usable: (N, 17) bool. rays: (N, 17, 3) unit, world. origin: (3,) world, m.
    focal_px: focal length, pixels. height_mean, height_std: (N,) metres, each person's
    height belief (default: the population prior of ``config``). reference_range: (N,)
    metres, the range at which to scale the variance (NaN or None: this frame's range).
    The variance grows with the range squared; scaled at this frame's noisy range, a
    too-near estimate would count more than a too-far one and a filter averaging them
    would drift near, so a tracked pedestrian's variance is scaled at its last range.
    Declines with ``no-keypoints`` (fewer than two usable levels), ``short-extent``
    (they span too little of the body) or ``inconsistent`` (no positive range fits).
    """
    n = len(rays)
    hm = np.full(n, config.person_height_mean_m) if height_mean is None else np.asarray(height_mean, float)
    hs = np.full(n, config.person_height_std_m) if height_std is None else np.asarray(height_std, float)
    idx = HEIGHT_KEYPOINTS
    angle_std = config.keypoint_pixel_std / focal_px
    stance, lone = stance_ankle(keypoints_usable, rays, ANKLE_KEYPOINTS, angle_std)
    usable = keypoints_usable.copy()
    usable[:, list(ANKLE_KEYPOINTS)] = stance
    used = usable[:, idx]
    frac = np.broadcast_to(KEYPOINT_HEIGHT_FRACTION[idx], used.shape)
    span = np.where(used, frac, -np.inf).max(1) - np.where(used, frac, np.inf).min(1)
    levels = used.sum(axis=1)
    enough = (levels >= 2) & (span >= MIN_FRACTION_SPAN)
    frac_std = np.where(np.isin(idx, ANKLE_KEYPOINTS)[None] & lone[:, None], LONE_ANKLE_FRACTION_STD,
                        KEYPOINT_FRACTION_STD[idx][None])
    r, var = solve_range(elevation_tangents(rays[:, idx]), frac, frac_std, used & enough[:, None], hm, angle_std)
    with np.errstate(invalid="ignore"):
        good = enough & np.isfinite(r) & (r > 0.3) & np.isfinite(var)
    reasons = first_reason([(levels < 2, "no-keypoints"), (~enough, "short-extent"), (~good, "inconsistent")], n)
    r = np.where(good, r, 1.0)
    rel_var = np.where(good, var / r**2, 1.0) + (hs / hm) ** 2
    scale = r if reference_range is None else np.where(np.isfinite(reference_range), reference_range, r)
    range_var = rel_var * scale**2
    mean_ray = np.where(used[..., None], rays[:, idx], 0.0).sum(axis=1)
    bearing = horizontal_bearing(mean_ray)
    xy = origin[:2] + r[:, None] * bearing
    cov = range_bearing_covariance(bearing, range_var, across_variance(scale, focal_px, config.keypoint_pixel_std,
                                                                       config.lateral_std_m))
    return CueEstimate(NAME, xy, cov, good, reasons)
